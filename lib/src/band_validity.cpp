#include "pyrocam/band_validity.h"

#include <cmath>
#include <cstdint>
#include <string>

#include "pyrocam/spectrum.h"

namespace pyrocam {

cv::Mat complete_band_mask(const std::vector<cv::Mat>& planes, double dim_dn) {
  if (planes.empty()) throw InputError("no band planes");
  const cv::Size size = planes[0].size();
  for (const cv::Mat& p : planes)
    if (p.type() != CV_32F || p.size() != size)
      throw InputError("band planes must be CV_32F of equal size");
  cv::Mat mask(size, CV_8U, cv::Scalar(255));
  const auto dim = static_cast<float>(dim_dn);
  for (int y = 0; y < size.height; ++y) {
    std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (const cv::Mat& p : planes) {
      const float* v = p.ptr<float>(y);
      // NaN fails the comparison, +INF the finiteness test.
      for (int x = 0; x < size.width; ++x)
        if (!(v[x] >= dim) || !std::isfinite(v[x])) m[x] = 0;
    }
  }
  return mask;
}

}  // namespace pyrocam
