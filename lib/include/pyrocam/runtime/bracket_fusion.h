// High dynamic range by exposure bracketing: the camera cycles through two or more exposures and
// the temperature frames of one cycle are fused, so that a 2500 degC core (saturated at the long
// exposure) and a 1300 degC rim (too dim at the short one) both read in one frame.
#pragma once

#include <cstddef>
#include <deque>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace pyrocam {

inline constexpr int kMaxBracketFrames = 16;
inline constexpr double kMinBracketFactor = 0.001, kMaxBracketFactor = 1000;

// The exposure factors a camera cycles through, e.g. "1,0.1": 1 to kMaxBracketFrames numbers
// from kMinBracketFactor to kMaxBracketFactor, comma-separated; "" is none. Throws InputError
// naming what is wrong.
std::vector<double> parse_bracket(const std::string& text);

// Fuses each new temperature frame with the ones before it: each pixel takes its reading from
// the frame, among the last `frames`, taken with the most light (exposure times the linear gain)
// where it has one; ties go to the latest. More light is a higher signal in every band, so
// where both read, the more exposed frame's reading has the smaller noise (shot and read noise);
// where it saturates or is dim it has no reading and a less exposed frame's is used. A pixel
// read in no frame has none. The fused frame carries the latest frame's time: a pixel taken from
// an earlier frame is as old as that frame (over a moving pool, where the pool was then).
class BracketFusion {
 public:
  // frames: 1..kMaxBracketFrames (1: no fusion); throws InputError otherwise.
  explicit BracketFusion(int frames);

  // decikelvin: CV_16U, 0 = no reading; light > 0 (e.g. exposure in microseconds times the
  // linear gain). Writes the fused frame to `out` (CV_16U, the same size; may be `decikelvin`
  // itself). A frame of another size than the ones held starts anew. Throws InputError for
  // another type or a light that is not > 0.
  void add(const cv::Mat& decikelvin, double light, cv::Mat& out);
  void reset() { held_.clear(); }
  int frames() const { return frames_; }
  std::size_t held() const { return held_.size(); }

 private:
  struct Held {
    cv::Mat decikelvin;
    double light;
  };
  int frames_;
  std::deque<Held> held_;  // oldest first, at most frames_ - 1 before the new one
};

// Fuses an exposure bracket before demosaicking: each sample of the dark-subtracted mosaic
// (CV_32F, +INF saturated, NaN no reading, as darksub gives it) from the frame, among the last
// `frames`, taken with the most light where it is a number and, if it is near the saturation
// level (within 15 % of the largest number seen), none of its band's samples within two cells
// (`period` pixels a cell: 2 for Bayer, 5 for a 5x5 mosaic; 24 neighbours) is saturated; scaled
// to the DN of the frame with the most light held (the reference). So every band of a
// demosaicking footprint has a value even where the footprint spans more brightness than one
// exposure holds between the dim and the saturation thresholds (a melt pool's steep side),
// which BracketFusion, taking whole readings, cannot give. The neighbours decide, not the
// sample: taken wherever it is below the level, a sample near the level is kept only where its
// own noise pulled it down, and the fused values there are low by up to 0.4 of a sample's
// standard deviation (the mean of a normal cut at its mean); decided by the neighbours' noise,
// at most 0.033 (from the case where the sample alone saturates). Where no frame has such a
// sample, the first that is a number is taken. A sample that is a number in no frame is NaN if
// it is NaN in any (no reading wins over saturated, as everywhere in the chain), else +INF.
// Values above the saturation level are readings then, from a shorter exposure. The scaled
// samples' noise is that of their own exposure times the scale, more than the noise model of
// the reference assumes: uncertainties of such pixels are low. Samples from different frames
// meet in one footprint, so over a pool that moves between the bracket's frames the bands of a
// pixel near a boundary are from different moments: last_agreement() says how each frame agrees
// with the one before, for a warning (mosaicfuse's). Unless set_follows_motion(false), the fusion
// follows a scene that moves at a constant velocity (a melt pool along its track): the velocity
// is the translation between the latest frame and the last one held with the same light (the
// bracket's cycle before; bracket_motion::find_shift), and each earlier frame's samples are taken
// from where the content moved since (its age times the velocity), interpolated along the band's
// own samples, and brought forward by the change of brightness a frame found between the same
// frames (bracket_motion::brightness_change: a pool's peak rises and falls as it moves; a
// sample whose brightness changed by more than a factor 2 since is not fused). A still
// scene, or one moving less than about half a cell a cycle, is fused as without it.
class MosaicBracketFusion {
 public:
  // frames: 1..kMaxBracketFrames (1: no fusion); period: the mosaic's cell size, 1..16 (the
  // distance between samples of one band); throws InputError otherwise.
  MosaicBracketFusion(int frames, int period);

  // signal: CV_32F; light > 0 (exposure times the linear gain). Writes the fused mosaic to
  // `out` (CV_32F, the same size; may be `signal` itself) and returns the reference light (the
  // most of the frames fused), whose DN its values are in. A frame of another size than the ones
  // held starts anew (reset()). Throws InputError for another type or a light that is not > 0.
  double add(const cv::Mat& signal, double light, cv::Mat& out);
  void reset() {
    held_.clear();
    velocity_ = {};
    frames_since_velocity_ = 0;
    largest_ = 0;
    agreement_ = {};
  }
  int frames() const { return frames_; }
  void set_follows_motion(bool follows) { follows_motion_ = follows; }
  bool follows_motion() const { return follows_motion_; }
  // The velocity the last add() followed, pixels a frame (0, 0 where it found none).
  const cv::Point2d& velocity() const { return velocity_; }

  // How the last frame added agrees with the one before it, sample by sample, scaled to one
  // exposure: of the samples well exposed in both (at least kMotionLowDn and below the level's
  // neighbourhood in each frame's own DN), how many differ by more than a bound on their noise
  // (shot variance of at most 1 DN per DN, a floor of 4 DN^2, 4 standard deviations, and 5 % for
  // the exposures' own inaccuracy). The bound is several times a real sensor's noise, so a still
  // scene disagrees on next to none; a pool that moves between the frames disagrees on its steep
  // sides. `moved`: at least kMovedShare of them and kMovedSamples (a small pool gives a few a
  // frame: sum the frames' agreements, as mosaicfuse does over its stream).
  struct Agreement {
    std::size_t compared = 0, disagreeing = 0;
    Agreement& operator+=(const Agreement& o) {
      compared += o.compared;
      disagreeing += o.disagreeing;
      return *this;
    }
    bool moved() const {
      return disagreeing >= kMovedSamples &&
             static_cast<double>(disagreeing) >= kMovedShare * static_cast<double>(compared);
    }
  };
  static constexpr double kMotionLowDn = 16;
  static constexpr std::size_t kMovedSamples = 20;
  static constexpr double kMovedShare = 0.002;
  const Agreement& last_agreement() const { return agreement_; }

 private:
  struct Held {
    cv::Mat signal;
    cv::Mat near_saturated;  // CV_8U: 1 where a sample of its band `period_` away saturates
    double light;
    cv::Mat cells;  // bracket_motion::cell_logs, where the fusion follows motion
    cv::Mat rates;  // bracket_motion::log_rates since the last frame of its light, where known
    cv::Mat logs;   // bracket_motion::sample_logs, once its samples are read displaced
  };
  int frames_, period_;
  // Oldest first, at most frames_ before the new one: the last frames_ - 1 are fused, and the
  // one before them may have the new one's light (the bracket's cycle before).
  std::deque<Held> held_;
  bool follows_motion_ = true;
  cv::Point2d velocity_;           // pixels a frame
  int frames_since_velocity_ = 0;  // frames added since velocity_ was found
  // The largest number of any frame since the start, each in its own DN: at most the
  // saturation level less the dark, and close to it once something has been near the level.
  float largest_ = 0;
  Agreement agreement_;
};

}  // namespace pyrocam
