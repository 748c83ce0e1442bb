// Statistics of a temperature image over a region, for the elements' messages and
// `pyrocam-calib measure`.
#pragma once

#include <cmath>
#include <cstddef>
#include <opencv2/core.hpp>

namespace pyrocam {

struct RegionStats {
  std::size_t pixels = 0, valid = 0;
  double valid_fraction = 0;
  double min_c = NAN, max_c = NAN, mean_c = NAN, median_c = NAN;
};
// Statistics of the finite pixels of a CV_32F temperature image inside mask (empty = all).
RegionStats region_stats(const cv::Mat& temperature_c, const cv::Mat& mask = cv::Mat());

// The hottest place of a region, robust to single wild pixels (mixed pixels at sharp edges):
// the largest median over the square windows of `window` x `window` pixels centred on each
// pixel. One outlier cannot move the median of 25 values beyond its neighbours, so a plate
// with wild edge pixels peaks at the plate's temperature.
struct RegionPeak {
  double c = NAN;      // the largest window median (degC); NaN when no window qualifies
  int x = -1, y = -1;  // the centre of that window (pixels of temperature_c); -1 when none
  bool found() const { return x >= 0; }
};
inline constexpr int kDefaultPeakWindow = 5;
inline constexpr int kMaxPeakWindow = 255;
// Peak of the finite pixels of a CV_32F temperature image inside mask (CV_8U, empty = all).
// A window counts only when at least half of its window x window pixels have a reading (pixels
// outside the image or the mask count as none), so a few stray readings in a region without
// readings make no peak. The median of an even count is the mean of the middle two; among equal
// medians the first found wins. Throws InputError unless window is odd, 1..kMaxPeakWindow and
// no larger than the image. Costs a few passes of box filtering over the image plus exact
// medians of the few windows that can beat the best found so far.
RegionPeak region_peak(const cv::Mat& temperature_c, int window = kDefaultPeakWindow,
                       const cv::Mat& mask = cv::Mat());

}  // namespace pyrocam
