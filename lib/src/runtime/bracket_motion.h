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
// axis the band's own samples (`period` pixels apart) around (x, y) - shift, with their weights:
// the two on either side for linear interpolation, and for the curved kinds (Lagrange's
// polynomials, in kCurvedKinds) nodes -1 .. 2, node 0 being the first of those two.
inline constexpr int kCurvedKinds = 3;  // cubic on nodes -1..2, quadratic on 0..2, on -1..1
struct Displacement {
  Displacement(const cv::Point2d& shift, int period);
  int dx, dy;  // from (x, y) to node 0 along each axis, pixels
  int period;
  double wx[2], wy[2];
  double curved_x[kCurvedKinds][4], curved_y[kCurvedKinds][4];  // weights of nodes -1 .. 2
};

// Samples under this are interpolated linearly: noise about no light, where the logarithm means
// nothing. Others in the logarithm: a steep side's brightness is close to exponential in position.
inline constexpr float kLogFromDn = 1;

// The logarithm of each sample of a dark-subtracted mosaic (CV_32F) that is a number at least
// kLogFromDn, NaN elsewhere: computed once a frame for DisplacedRow, not for every sample of
// every later frame that reads it.
cv::Mat sample_logs(const cv::Mat& signal);

// Row y of a frame whose content moved since (d): at(x) is the sample at x from the band's
// samples around where it was. Where the nearest (2 x 2) are all at least kLogFromDn, in the
// logarithm by the first curved kind whose nodes all are (`logs`: sample_logs of the frame):
// across a melt pool's peak and steep front the brightness's logarithm curves, and the nearest
// two's chord there is 4-11 % low, more in the bands of shorter wavelength (on the targets
// suite's moving pool, bands from frames of different ages then read its front 150-200 degC
// high); the quadratics serve where the cubic's farthest node is saturated (the next exposure's
// zone) or dim. Else by the nearest two in the logarithm, or linearly where one is under
// kLogFromDn (a ratio of bands interpolated one in the logarithm and one linearly, each off the
// other way on a curved side, read wrong too: the floor was 16 DN). NaN where one of the nearest
// is NaN or outside the frame; +INF where one is saturated (and none NaN); *near: whether
// `near_level` (CV_8U) is set at one of the nearest. Holds pointers into the frames.
class DisplacedRow {
 public:
  DisplacedRow(const cv::Mat& signal, const cv::Mat& near_level, const cv::Mat& logs,
               const Displacement& d, int y);
  float at(int x, bool* near) const;

 private:
  double curved(int x, double nearest) const;

  Displacement d_;
  int width_;
  bool inside_ = true;
  const float* rows_[2] = {nullptr, nullptr};
  const std::uint8_t* flags_[2] = {nullptr, nullptr};
  const float* logs_[4] = {nullptr, nullptr, nullptr, nullptr};  // nodes -1 .. 2 along y
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
      if (well_exposed)
        logs += w * (logs_[j + 1] ? static_cast<double>(logs_[j + 1][sx])
                                  : std::log(static_cast<double>(v)));
    }
  }
  if (saturated) return kInf;
  if (!well_exposed) return static_cast<float>(linear);
  return static_cast<float>(std::exp(curved(x, logs)));
}

// The first curved kind's interpolation of the logarithm whose nodes all have one, or `nearest`.
inline double DisplacedRow::curved(int x, double nearest) const {
  if (logs_[1] == nullptr) return nearest;
  for (int kind = 0; kind < kCurvedKinds; ++kind) {
    const double *cx = d_.curved_x[kind], *cy = d_.curved_y[kind];
    double sum = 0;
    bool known = true;
    for (int j = 0; j < 4 && known; ++j) {
      if (cy[j] == 0) continue;
      known = logs_[j] != nullptr;
      for (int i = 0; i < 4 && known; ++i) {
        if (cx[i] == 0) continue;
        const int sx = x + d_.dx + (i - 1) * d_.period;
        known = sx >= 0 && sx < width_ && !std::isnan(logs_[j][sx]);
        if (known) sum += cx[i] * cy[j] * static_cast<double>(logs_[j][sx]);
      }
    }
    if (known) return sum;
  }
  return nearest;
}

}  // namespace pyrocam::bracket_motion
