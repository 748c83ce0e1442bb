#include "pyrocam/runtime/region_stats.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace pyrocam {

RegionStats region_stats(const cv::Mat& t, const cv::Mat& mask) {
  RegionStats s;
  std::vector<float> values;
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) {
      if (!mask.empty() && !mask.at<std::uint8_t>(y, x)) continue;
      ++s.pixels;
      const float v = t.at<float>(y, x);
      if (std::isfinite(v)) values.push_back(v);
    }
  s.valid = values.size();
  s.valid_fraction = s.pixels ? static_cast<double>(s.valid) / static_cast<double>(s.pixels) : 0;
  if (values.empty()) return s;
  double sum = 0;
  for (float v : values) sum += v;
  s.mean_c = sum / static_cast<double>(values.size());
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  s.min_c = *lo;
  s.max_c = *hi;
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  s.median_c = *mid;
  if (values.size() % 2 == 0) {
    const float below = *std::max_element(values.begin(), mid);
    s.median_c = 0.5 * (s.median_c + below);
  }
  return s;
}

}  // namespace pyrocam
