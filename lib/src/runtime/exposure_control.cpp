#include "pyrocam/runtime/exposure_control.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "pyrocam/core/error.h"

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
}

std::optional<ExposureCommand> ExposureController::update(const HotLevel& level,
                                                          std::optional<double> frame_exposure_us,
                                                          double current_us) {
  double taken_us;
  if (frame_exposure_us) {
    taken_us = *frame_exposure_us;
  } else {
    // Without the frame's own exposure, frames right after a change may still be the old one.
    if (commanded_us_ && ++frames_since_command_ <= settings_.latency_frames) return std::nullopt;
    taken_us = commanded_us_.value_or(current_us);
  }
  if (!(taken_us > 0) || !std::isfinite(taken_us)) return std::nullopt;
  const ExposureControlSettings& s = settings_;
  const double wanted_signal = s.target * (s.saturation_dn - s.dark_dn);
  const double signal = level.level_dn - s.dark_dn;
  double ratio;
  if (level.clipped)
    ratio = 1 / s.max_step;  // only a lower bound on the level: step down as far as allowed
  else if (signal <= 0)
    ratio = s.max_step;
  else
    ratio = std::clamp(wanted_signal / signal, 1 / s.max_step, s.max_step);
  if (!level.clipped && std::abs(ratio - 1) <= s.tolerance) {
    at_limit_ = false;
    return std::nullopt;
  }
  const double wanted_us = taken_us * ratio;
  ExposureCommand command;
  command.exposure_us = std::clamp(wanted_us, s.min_exposure_us, s.max_exposure_us);
  command.clamped = command.exposure_us != wanted_us;
  at_limit_ = command.clamped;
  const double last = commanded_us_.value_or(current_us);
  // Already asked for (frames taken before the change took effect ask again): nothing new.
  if (std::abs(command.exposure_us - last) <= 1e-3 * last) return std::nullopt;
  commanded_us_ = command.exposure_us;
  frames_since_command_ = 0;
  return command;
}

}  // namespace pyrocam
