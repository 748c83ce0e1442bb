// Motion between the frames of an exposure bracket, for MosaicBracketFusion: a melt pool moves
// along its track between the frames, so a sample of an earlier frame is taken from where the
// content it shows has moved since. The motion is a translation at a constant velocity, found
// between the latest frame and the last one taken with the same light (the bracket's cycle
// before: the same samples expose well in both, where consecutive exposures of a bracket share
// only a thin band of brightness).
#pragma once

#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>

namespace pyrocam::bracket_motion {

// The logarithm of the mean of each period x period cell of a dark-subtracted mosaic (CV_32F)
// where all its samples lie in [low, high] (numbers, neither dim nor near the level); NaN
// elsewhere. (rows / period) x (cols / period), CV_32F.
cv::Mat cell_logs(const cv::Mat& signal, int period, float low, float high);

// The translation, in pixels, that moved `before`'s content to where it is `now` (content at x
// now was at x - shift then), from two frames' cell_logs taken with the same light: the whole
// cells' shift of least mean squared difference over the cells both have, within kMaxShiftCells
// cells, refined by a parabola along each axis. False where no shift fits clearly better than
// none (a still scene: the least difference at no shift, or under kMinGain of the difference at
// none) or the best lies at the search's edge, or too few cells are shared.
bool find_shift(const cv::Mat& now, const cv::Mat& before, int period, cv::Point2d& shift);
inline constexpr int kMaxShiftCells = 16;
inline constexpr int kMinSharedCells = 16;
inline constexpr double kMinGain = 0.5;    // the best's mean difference at most half of none's
inline constexpr int kMaxCompared = 2048;  // cells of `now` compared, evenly spread

// Where a frame's samples are read from once its content moved by `shift` (pixels): along each
// axis two of the band's own samples (`period` pixels apart) on either side of (x, y) - shift,
// with their weights.
struct Displacement {
  Displacement(const cv::Point2d& shift, int period);
  int dx, dy;  // from (x, y) to the first sample along each axis, pixels
  int period;
  double wx[2], wy[2];
};

// Row y of a frame whose content moved since (d): at(x) is the sample at x from the band's
// samples around where it was, interpolated in the logarithm (a steep side's brightness is close
// to exponential in position) or linearly where one is under kLogFromDn (a cold background's
// noise, where the logarithm means nothing). NaN where one is NaN or outside the frame; +INF
// where one is saturated (and none NaN); *near: whether `near_level` (CV_8U) is set at one of
// them. Holds pointers into the frames.
inline constexpr float kLogFromDn = 16;
class DisplacedRow {
 public:
  DisplacedRow(const cv::Mat& signal, const cv::Mat& near_level, const Displacement& d, int y);
  float at(int x, bool* near) const;

 private:
  Displacement d_;
  int width_;
  bool inside_ = true;
  const float* rows_[2] = {nullptr, nullptr};
  const std::uint8_t* flags_[2] = {nullptr, nullptr};
};

inline float DisplacedRow::at(int x, bool* near) const {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  *near = false;
  if (!inside_) return std::numeric_limits<float>::quiet_NaN();
  double linear = 0, logs = 0;
  bool well_exposed = true, saturated = false;
  for (int j = 0; j < 2; ++j) {
    if (d_.wy[j] == 0) continue;
    for (int i = 0; i < 2; ++i) {
      const double w = d_.wx[i] * d_.wy[j];
      if (w == 0) continue;
      const int sx = x + d_.dx + i * d_.period;
      if (sx < 0 || sx >= width_) return std::numeric_limits<float>::quiet_NaN();
      const float v = rows_[j][sx];
      if (std::isnan(v)) return v;
      *near = *near || flags_[j][sx] != 0;
      if (v == kInf) {
        saturated = true;
        continue;
      }
      linear += w * v;
      well_exposed = well_exposed && v >= kLogFromDn;
      if (well_exposed) logs += w * std::log(static_cast<double>(v));
    }
  }
  if (saturated) return kInf;
  return static_cast<float>(well_exposed ? std::exp(logs) : linear);
}

}  // namespace pyrocam::bracket_motion
