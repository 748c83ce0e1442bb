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

}  // namespace pyrocam
