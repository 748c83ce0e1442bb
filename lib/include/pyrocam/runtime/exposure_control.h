// Automatic exposure for thermal reading: keeps the hottest region's brightest band near a
// target share of the usable signal range (dark to saturation), so that the object of interest
// reads (a saturated band gives no reading, a dim one a noisy or no reading), by the exposure and,
// when allowed, the analogue gain. Frame-by-frame logic only; the autoexposure element feeds it.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

namespace pyrocam {

// The level of the hottest region of a raw frame: the `hot_pixels`-th brightest raw value (so
// that a few hot or defective pixels do not set it), in raw DN.
struct HotLevel {
  double level_dn = 0;   // the hot_pixels-th brightest value
  bool clipped = false;  // level_dn at or above the saturation level: the true level is higher
};
// raw: CV_8U or CV_16U (any layout: the brightest band dominates the top values). Throws
// InputError for another type, an empty image or hot_pixels < 1.
HotLevel hot_level(const cv::Mat& raw, int hot_pixels, double saturation_dn);

struct ExposureControlSettings {
  double target = 0.7;         // wanted hot level: dark + target (saturation - dark), 0.05..0.95
  double dark_dn = 0;          // raw dark level
  double saturation_dn = 255;  // raw level from which a pixel is saturated
  double min_exposure_us = 10, max_exposure_us = 1e6;  // the camera's range
  double max_step = 8;     // largest change of the exposure per adjustment (factor), >= 1.5
  double tolerance = 0.1;  // no change while the level is within this share of the target
  int latency_frames = 3;  // frames before a change shows, when frames do not carry their exposure
  // Largest analogue gain to set, dB, 0..100; 0: the gain is never changed (the exposure alone
  // is controlled, whatever gain the frames were taken with).
  double max_gain_db = 0;
};

// What a frame was taken with, or what the camera is set to.
struct ExposureSetting {
  double exposure_us = 0;
  double gain_db = 0;  // analogue gain: the signal is 10^(gain_db / 20) times that at 0 dB
};

struct ExposureCommand {
  double exposure_us = 0;
  // The gain to set; with max_gain_db 0 the frame's own (or the current) gain, not to be set.
  double gain_db = 0;
  bool clamped = false;  // the wanted brightness was outside what the ranges allow
};

class ExposureController {
 public:
  // Throws InputError for settings out of their ranges (see the struct).
  explicit ExposureController(const ExposureControlSettings& settings);
  // One frame: its hot level and the exposure it was taken with, when the frame says
  // (`frame_exposure_us`), else the one last commanded (or `current_us` at the start) after
  // latency_frames. Returns a new exposure to set, or nothing to keep the current one.
  // Normalising by the frame's own exposure makes the step dead-beat: the frames still taken
  // with the old exposure ask for the same new one, so latency makes no oscillation.
  // A camera without gain: the same as update() with every gain 0.
  std::optional<ExposureCommand> update(const HotLevel& level,
                                        std::optional<double> frame_exposure_us, double current_us);
  // With gain (max_gain_db > 0): the wanted brightness, exposure times gain factor, is the
  // frame's own times the ratio of target to level; it is made by the exposure alone (gain 0 dB)
  // up to max_exposure_us, and only beyond that by the gain at the longest exposure. So the gain
  // rises only once the exposure is at its longest, and a too bright scene brings the gain back
  // to 0 dB before the exposure shortens. `frame` is what the frame says it was taken with;
  // without it, the setting last commanded (or `current` at the start) after latency_frames.
  std::optional<ExposureCommand> update(const HotLevel& level, std::optional<ExposureSetting> frame,
                                        const ExposureSetting& current);
  // The camera was set to `setting` by the caller (not by a command of update()): frames
  // without their own settings are taken with it after latency_frames, as after a command.
  void set_by_caller(const ExposureSetting& setting) {
    commanded_ = setting;
    frames_since_command_ = 0;
  }
  const ExposureControlSettings& settings() const { return settings_; }
  // Whether the last frame wanted an exposure outside the camera's range (clamped to it).
  bool at_limit() const { return at_limit_; }

 private:
  bool at_limit_ = false;
  ExposureControlSettings settings_;
  std::optional<ExposureSetting> commanded_;
  // The last brightness (exposure us at 0 dB) whose level was no signal, and the last one whose
  // level clipped, while no level in between was seen: the next setting lies between them.
  std::optional<double> dark_at_, clipped_at_;
  // The last level neither clipped nor without signal, and its brightness.
  struct ReadLevel {
    double brightness, signal;
  };
  std::optional<ReadLevel> last_read_;
  int frames_since_command_ = 0;
};

// What a frame that does not say it (no exposure meta: aravissrc's frames) was taken with: the
// camera's setting read as each frame passes, once it has stayed the same for latency frames
// (frames between setting an exposure and the first frame taken with it: a change, whoever
// made it, takes that long to reach the frames). The first setting read is taken to be in
// effect from the start (the camera was set before it streamed).
class SettingInEffect {
 public:
  // Throws InputError for a negative latency.
  explicit SettingInEffect(int latency_frames);
  // `current`: the camera's setting read as this frame passes. Returns what the frame was taken
  // with, or nothing while that is not known (the setting changed less than latency frames ago).
  std::optional<ExposureSetting> frame_setting(const ExposureSetting& current);

 private:
  int latency_;
  std::optional<ExposureSetting> last_;
  int unchanged_ = 0;  // frames since last_ was first read (capped at latency_)
};

// Exposure bracketing by the camera's own setting, for cameras whose frames do not say what they
// were taken with (aravissrc): the camera is set to base x each factor in turn and each setting
// is held for latency + 1 frames, so that the last frame of a step is known to be taken with it
// (SettingInEffect). That frame is the step's; the frames before it may be either exposure and
// are not used. Only the sequence of frames is kept here; the caller sets the camera.
class CameraBracket {
 public:
  // factors: two or more (parse_bracket's range); latency_frames >= 0. Throws InputError.
  CameraBracket(std::vector<double> factors, int latency_frames);
  struct Step {
    bool keep = false;   // the last frame of a step: taken with its setting
    bool first = false;  // ... of the first factor's step (the one exposure control reads)
    double factor = 1;   // the factor a kept frame was taken with
    bool set = false;    // set the camera to base x next_factor now (after this frame)
    double next_factor = 1;
  };
  // One frame, in stream order. The first frame starts the first step.
  Step next_frame();
  const std::vector<double>& factors() const { return factors_; }

 private:
  std::vector<double> factors_;
  int latency_;
  std::size_t step_ = 0;
  int frames_in_step_ = -1;  // frames since the step was set; -1: none set yet
};

}  // namespace pyrocam
