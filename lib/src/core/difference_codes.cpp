#include "pyrocam/core/difference_codes.h"

#include <cmath>
#include <cstdint>

namespace pyrocam {

cv::Mat encode_decikelvin_difference(const cv::Mat& d) {
  CV_Assert(d.type() == CV_32F);
  cv::Mat out(d.size(), CV_16U);
  for (int y = 0; y < d.rows; ++y) {
    const float* in = d.ptr<float>(y);
    std::uint16_t* o = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < d.cols; ++x) {
      const float v = in[x];
      if (!std::isfinite(v) || v < 0) {
        o[x] = 0;
        continue;
      }
      const double code = std::round(static_cast<double>(v) * 10);
      o[x] = static_cast<std::uint16_t>(code < 1 ? 1 : code > 65535 ? 65535 : code);
    }
  }
  return out;
}

cv::Mat decode_decikelvin_difference(const cv::Mat& codes) {
  CV_Assert(codes.type() == CV_16U);
  cv::Mat out(codes.size(), CV_32F);
  for (int y = 0; y < codes.rows; ++y) {
    const std::uint16_t* in = codes.ptr<std::uint16_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < codes.cols; ++x) o[x] = in[x] ? static_cast<float>(in[x] / 10.0) : NAN;
  }
  return out;
}

}  // namespace pyrocam
