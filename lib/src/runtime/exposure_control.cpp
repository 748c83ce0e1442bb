#include "pyrocam/runtime/exposure_control.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/bracket_fusion.h"

namespace pyrocam {

HotLevel hot_level(const cv::Mat& raw, int hot_pixels, double saturation_dn) {
  if (raw.empty()) throw InputError("hot level of an empty frame");
  if (hot_pixels < 1) throw InputError("hot_pixels must be at least 1");
  if (raw.depth() != CV_8U && raw.depth() != CV_16U)
    throw InputError("hot level of a frame that is not 8- or 16-bit");
  const int bins = raw.depth() == CV_8U ? 256 : 65536;
  std::vector<std::uint64_t> histogram(static_cast<std::size_t>(bins), 0);
  for (int y = 0; y < raw.rows; ++y) {
    if (raw.depth() == CV_8U) {
      const std::uint8_t* p = raw.ptr<std::uint8_t>(y);
      for (int x = 0; x < raw.cols * raw.channels(); ++x) ++histogram[p[x]];
    } else {
      const std::uint16_t* p = raw.ptr<std::uint16_t>(y);
      for (int x = 0; x < raw.cols * raw.channels(); ++x) ++histogram[p[x]];
    }
  }
  const std::uint64_t total = raw.total() * static_cast<std::uint64_t>(raw.channels());
  const std::uint64_t wanted =
      std::min<std::uint64_t>(static_cast<std::uint64_t>(hot_pixels), total);
  std::uint64_t seen = 0;
  int value = bins - 1;
  for (; value > 0; --value) {
    seen += histogram[static_cast<std::size_t>(value)];
    if (seen >= wanted) break;
  }
  HotLevel out;
  out.level_dn = value;
  out.clipped = value >= saturation_dn;
  return out;
}

ExposureController::ExposureController(const ExposureControlSettings& s) : settings_(s) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw InputError("exposure control: " + what);
  };
  require(s.target >= 0.05 && s.target <= 0.95, "target must be 0.05..0.95");
  require(std::isfinite(s.dark_dn) && std::isfinite(s.saturation_dn) && s.saturation_dn > s.dark_dn,
          "the saturation level must be above the dark level");
  require(s.min_exposure_us > 0 && s.max_exposure_us >= s.min_exposure_us &&
              std::isfinite(s.max_exposure_us),
          "the exposure range must be 0 < min <= max");
  require(s.max_step >= 1.5 && std::isfinite(s.max_step), "max_step must be at least 1.5");
  require(s.tolerance > 0 && s.tolerance < 0.5, "tolerance must be in (0, 0.5)");
  require(s.latency_frames >= 0, "latency_frames must be >= 0");
  require(s.max_gain_db >= 0 && s.max_gain_db <= 100, "max_gain_db must be 0..100");
}

std::optional<ExposureCommand> ExposureController::update(const HotLevel& level,
                                                          std::optional<double> frame_exposure_us,
                                                          double current_us) {
  std::optional<ExposureSetting> frame;
  if (frame_exposure_us) frame = ExposureSetting{*frame_exposure_us, 0.0};
  return update(level, frame, ExposureSetting{current_us, 0.0});
}

std::optional<ExposureCommand> ExposureController::update(const HotLevel& level,
                                                          std::optional<ExposureSetting> frame,
                                                          const ExposureSetting& current) {
  ExposureSetting taken;
  if (frame) {
    taken = *frame;
  } else {
    // Without the frame's own settings, frames right after a change may still be the old ones.
    if (commanded_ && ++frames_since_command_ <= settings_.latency_frames) return std::nullopt;
    taken = commanded_.value_or(current);
  }
  if (!(taken.exposure_us > 0) || !std::isfinite(taken.exposure_us) ||
      !std::isfinite(taken.gain_db))
    return std::nullopt;
  const ExposureControlSettings& s = settings_;
  const double wanted_signal = s.target * (s.saturation_dn - s.dark_dn);
  const double signal = level.level_dn - s.dark_dn;
  // Brightness in exposure microseconds at 0 dB.
  const double brightness = taken.exposure_us * analogue_gain_factor(taken.gain_db);
  double ratio;
  if (level.clipped) {
    ratio = 1 / s.max_step;  // only a lower bound on the level: step down as far as allowed
    clipped_at_ = brightness;
    if (dark_at_ && *dark_at_ >= brightness) dark_at_.reset();  // the scene brightened
  } else if (signal <= 0) {
    ratio = s.max_step;
    dark_at_ = brightness;
    if (clipped_at_ && *clipped_at_ <= brightness) clipped_at_.reset();  // the scene dimmed
  } else {
    ratio = wanted_signal / signal;
    dark_at_.reset(), clipped_at_.reset();
    // The step takes the signal to be proportional to the brightness, as it is when dark_dn is
    // the frames' black level. Set above it (or below), the proportional step overshoots (by 2
    // at a dark_dn 70 DN too high for a target of 70 DN: 2400 <-> 2850 us for ever); where this
    // frame and the last one lie either side of the target, the line through them gives the
    // brightness instead (regula falsi, exact for an offset).
    if (last_read_ && (signal - wanted_signal) * (last_read_->signal - wanted_signal) < 0 &&
        std::abs(last_read_->brightness - brightness) > 1e-3 * brightness) {
      const double slope = (signal - last_read_->signal) / (brightness - last_read_->brightness);
      if (slope > 0) ratio = (brightness + (wanted_signal - signal) / slope) / brightness;
    }
    ratio = std::clamp(ratio, 1 / s.max_step, s.max_step);
    last_read_ = ReadLevel{brightness, signal};
  }
  // A level that is clipped at one setting and no signal at the next one max_step away says
  // nothing in between: halve the interval (geometrically). Stepping by max_step each way went
  // back and forth for ever (a dark-level set above the frames' black level, 104 DN at
  // 1 ms and saturated at 8 ms).
  if ((level.clipped || signal <= 0) && dark_at_ && clipped_at_)
    ratio =
        std::clamp(std::sqrt(*dark_at_ * *clipped_at_) / brightness, 1 / s.max_step, s.max_step);
  if (!level.clipped && signal > 0 &&
      std::abs(signal - wanted_signal) <= s.tolerance * wanted_signal) {
    at_limit_ = false;
    return std::nullopt;
  }
  ExposureCommand command;
  if (s.max_gain_db > 0) {
    // Brightness in exposure microseconds at 0 dB: the exposure first, then the gain.
    const double wanted = taken.exposure_us * analogue_gain_factor(taken.gain_db) * ratio;
    const double highest = s.max_exposure_us * analogue_gain_factor(s.max_gain_db);
    const double reached = std::clamp(wanted, s.min_exposure_us, highest);
    command.clamped = reached != wanted;
    command.exposure_us = std::min(reached, s.max_exposure_us);
    command.gain_db = reached > s.max_exposure_us
                          ? std::min(20 * std::log10(reached / s.max_exposure_us), s.max_gain_db)
                          : 0.0;
  } else {
    // The gain is not ours: whatever it is, the exposure alone scales the level.
    const double wanted_us = taken.exposure_us * ratio;
    command.exposure_us = std::clamp(wanted_us, s.min_exposure_us, s.max_exposure_us);
    command.gain_db = taken.gain_db;
    command.clamped = command.exposure_us != wanted_us;
  }
  at_limit_ = command.clamped;
  const ExposureSetting last = commanded_.value_or(current);
  // Already asked for (frames taken before the change took effect ask again): nothing new.
  const bool same_gain = s.max_gain_db <= 0 || std::abs(command.gain_db - last.gain_db) <= 1e-3;
  if (std::abs(command.exposure_us - last.exposure_us) <= 1e-3 * last.exposure_us && same_gain)
    return std::nullopt;
  commanded_ = ExposureSetting{command.exposure_us, command.gain_db};
  frames_since_command_ = 0;
  return command;
}

SettingInEffect::SettingInEffect(int latency_frames) : latency_(latency_frames) {
  if (latency_frames < 0)
    throw InputError("exposure latency: " + std::to_string(latency_frames) +
                     " frames (must be 0 or more)");
}

std::optional<ExposureSetting> SettingInEffect::frame_setting(const ExposureSetting& current) {
  // Exact comparison: the camera's properties read back the values they hold.
  if (!last_) {
    last_ = current;
    unchanged_ = latency_;
  } else if (current.exposure_us != last_->exposure_us || current.gain_db != last_->gain_db) {
    last_ = current;
    unchanged_ = 0;
  } else if (unchanged_ < latency_) {
    ++unchanged_;
  }
  if (unchanged_ < latency_ || !(current.exposure_us > 0) || !std::isfinite(current.exposure_us) ||
      !std::isfinite(current.gain_db))
    return std::nullopt;
  return current;
}

CameraBracket::CameraBracket(std::vector<double> factors, int latency_frames)
    : factors_(std::move(factors)), latency_(latency_frames) {
  if (factors_.size() < 2 || static_cast<int>(factors_.size()) > kMaxBracketFrames)
    throw InputError("exposure bracket: 2 to " + std::to_string(kMaxBracketFrames) +
                     " exposure factors are needed, not " + std::to_string(factors_.size()));
  for (double f : factors_)
    if (!(f >= kMinBracketFactor && f <= kMaxBracketFactor))
      throw InputError("exposure bracket: factor " + std::to_string(f) + " is outside " +
                       std::to_string(kMinBracketFactor) + ".." +
                       std::to_string(kMaxBracketFactor));
  if (latency_frames < 0)
    throw InputError("exposure bracket: latency " + std::to_string(latency_frames) +
                     " frames (must be 0 or more)");
}

CameraBracket::Step CameraBracket::next_frame() {
  Step s;
  if (frames_in_step_ < 0) {
    frames_in_step_ = 0;
    s.set = true;
    s.next_factor = factors_[0];
    return s;
  }
  if (++frames_in_step_ <= latency_) return s;
  s.keep = true;
  s.first = step_ == 0;
  s.factor = factors_[step_];
  step_ = (step_ + 1) % factors_.size();
  frames_in_step_ = 0;
  s.set = true;
  s.next_factor = factors_[step_];
  return s;
}

}  // namespace pyrocam
