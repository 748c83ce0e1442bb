// Statistics of a temperature image over a region, for the elements' messages and
// `pyrocam-calib measure`.
#pragma once

#include <cmath>
#include <cstddef>
#include <opencv2/core.hpp>
#include <vector>

namespace pyrocam {

struct RegionStats {
  std::size_t pixels = 0, valid = 0;
  double valid_fraction = 0;
  double min_c = NAN, max_c = NAN, mean_c = NAN, median_c = NAN;
};
// Statistics of the finite pixels of a CV_32F temperature image inside mask (empty = all).
RegionStats region_stats(const cv::Mat& temperature_c, const cv::Mat& mask = cv::Mat());

// The hottest place of a region, robust to single wild pixels (mixed pixels at sharp edges):
// the largest median over the square windows of `window` x `window` pixels wholly inside the
// image (one cut by the edge holds fewer readings, whose median scatters further). One outlier
// cannot move the median of 25 values beyond its neighbours, so a plate with wild edge pixels peaks
// at the plate's temperature.
struct RegionPeak {
  double c = NAN;      // the largest window median (degC); NaN when no window qualifies
  int x = -1, y = -1;  // the centre of that window (pixels of temperature_c); -1 when none
  bool found() const { return x >= 0; }
};
inline constexpr int kDefaultPeakWindow = 5;
inline constexpr int kMaxPeakWindow = 255;
// Peak of the finite pixels of a CV_32F temperature image inside mask (CV_8U, empty = all).
// A window counts only when at least half of its window x window pixels have a reading (pixels
// outside the mask count as none), so a few stray readings in a region without
// readings make no peak. The median of an even count is the mean of the middle two; among equal
// medians the first found wins. Throws InputError unless window is odd, 1..kMaxPeakWindow and
// no larger than the image. Costs a few passes of box filtering over the image plus exact
// medians of the few windows that can beat the best found so far.
RegionPeak region_peak(const cv::Mat& temperature_c, int window = kDefaultPeakWindow,
                       const cv::Mat& mask = cv::Mat());

// Where light saturated the camera: a pixel without a reading there may be the hottest of the
// scene, so a peak or maximum read around it is only a lower bound. As a CV_8U mask (1 = a band
// without a value from the camera), from band planes (CV_32F, all of one size): some band +INF
// (a saturated sample), or NaN within 2 pixels of such a pixel (saturated samples of opposite
// signs in a demosaicking kernel); a NaN elsewhere (demosaic25's mixed-pixel mark, a sample
// darksub left without a value) is not light that saturated. Throws InputError for no planes or
// planes of another type or size.
cv::Mat saturated_band_mask(const std::vector<cv::Mat>& planes);
// The same from a dark-subtracted mosaic (CV_32F) that is demosaicked into pixels of its own
// size: the pixels within `radius` samples (a square, the kernels' reach) of a +INF or NaN one.
cv::Mat saturated_sample_mask(const cv::Mat& mosaic, int radius);
// How many pixels of a CV_32F temperature image have no reading (NaN) where mask (CV_8U of the
// same size) is non-zero.
std::size_t count_without_reading(const cv::Mat& temperature_c, const cv::Mat& mask);

// The variance of the median of the readings under `used` (CV_8U, non-zero: a reading), as a
// share of one reading's, when each one's noise is shared with its neighbours over `noise_area`
// pixels (demosaic_noise_area): each reading taken as a Gaussian-weighted mean of independent
// noise whose squared weights sum to 1 / noise_area, the noise jointly normal. n readings far
// apart give pi/2 / n (the median of independent readings), a single reading 1, and a region
// much larger than the footprint about pi/2 / n times the footprint's area, less where the
// readings share much of their noise (their median loses less to their mean). Of one or two
// readings the median is their mean, and so is the share. NaN for none. Throws InputError for a
// mask of another type or a noise_area below 1.
double median_noise_share(const cv::Mat& used, double noise_area);

}  // namespace pyrocam
