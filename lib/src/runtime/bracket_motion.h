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
#include <vector>

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
// *still (optional): set where the least difference lies at no shift (the content held still).
bool find_shift(const cv::Mat& now, const cv::Mat& before, int period, cv::Point2d& shift,
                bool* still = nullptr);
inline constexpr int kMaxShiftCells = 16;
inline constexpr int kMinSharedCells = 16;
inline constexpr double kMinGain = 0.5;    // the best's mean difference at most half of none's
inline constexpr int kMaxCompared = 2048;  // cells of `now` compared, evenly spread

// The change of log brightness a frame at each cell of `now` since `before`, two frames' cell_logs
// taken with the same light `age` frames apart, `before`'s content having moved by `shift` pixels
// since (read where it was, interpolated between its cells): (now - before) / age, with its
// variance from the samples' noise (kRateShotDnPerDn DN of shot variance per DN, a floor of
// kRateFloorDn2, over the cell's period^2 samples). CV_32FC2 (rate, variance), NaN where either
// cell is unknown.
cv::Mat log_rates(const cv::Mat& now, const cv::Mat& before, const cv::Point2d& shift, int period,
                  int age);
inline constexpr double kRateShotDnPerDn = 1;
inline constexpr double kRateFloorDn2 = 4;

// The brightness change a frame to apply at each cell of the latest frame, from the log_rates of
// the frames held (`rates[j]`, its content moved by `shifts[j]` pixels since; the latest's first:
// each cell takes the most recent that knows it): their inverse-variance weighted mean over 3 x 3
// cells where it lies beyond kRateDeviations of its standard deviation, else 0 (a steady scene's
// noise is no change). CV_32F, the latest's cells.
cv::Mat brightness_change(const std::vector<cv::Mat>& rates, const std::vector<cv::Point2d>& shifts,
                          int period);
inline constexpr double kRateDeviations = 3;

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
// to exponential in position) or linearly where one is under kLogFromDn (noise about no light,
// where the logarithm means nothing). The floor is low: a ratio of bands whose samples were
// interpolated one in the logarithm and one linearly (each off the other way on a curved side)
// read a moving pool's front 150-200 degC high, where both in the logarithm read it within 100
// (scratch study: 1.8 times as many wild readings with the floor at 16 DN). NaN where one is NaN or
// outside the frame; +INF where one is saturated (and none NaN); *near: whether `near_level`
// (CV_8U) is set at one of them. Holds pointers into the frames.
inline constexpr float kLogFromDn = 1;
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
