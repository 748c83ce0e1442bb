#include "pyrocam/core/temperature_codes.h"

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"

namespace pyrocam {

// Compiled for x86-64-v3 too, where the rounding vectorises.
PYROCAM_VECTOR_CLONES
void encode_temperature_row(const float* __restrict in, std::uint16_t* __restrict out, int n) {
  for (int x = 0; x < n; ++x) out[x] = temperature_code(in[x]);
}

namespace {

template <typename Decode>
cv::Mat decode(const cv::Mat& codes, Decode to_celsius) {
  if (codes.type() != CV_16U) throw InputError("temperature codes must be CV_16U");
  cv::Mat out(codes.size(), CV_32F);
  for (int y = 0; y < codes.rows; ++y) {
    const std::uint16_t* in = codes.ptr<std::uint16_t>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < codes.cols; ++x) o[x] = static_cast<float>(to_celsius(in[x]));
  }
  return out;
}

}  // namespace

void encode_decikelvin(const cv::Mat& t, cv::Mat& codes) {
  if (t.type() != CV_32F) throw InputError("temperature images must be CV_32F");
  codes.create(t.size(), CV_16U);
  auto rows = [&](const cv::Range& r) {
    for (int y = r.start; y < r.end; ++y)
      encode_temperature_row(t.ptr<float>(y), codes.ptr<std::uint16_t>(y), t.cols);
  };
  if (t.total() < 512u * 512u)
    rows(cv::Range(0, t.rows));
  else
    cv::parallel_for_(cv::Range(0, t.rows), rows, 2.0);
}

cv::Mat encode_decikelvin(const cv::Mat& t) {
  cv::Mat out;
  encode_decikelvin(t, out);
  return out;
}

cv::Mat decode_decikelvin(const cv::Mat& codes) { return decode(codes, code_to_celsius); }

cv::Mat encode_decikelvin_difference(const cv::Mat& d) {
  if (d.type() != CV_32F) throw InputError("temperature differences must be CV_32F");
  cv::Mat out(d.size(), CV_16U);
  for (int y = 0; y < d.rows; ++y) {
    const float* in = d.ptr<float>(y);
    std::uint16_t* o = out.ptr<std::uint16_t>(y);
    for (int x = 0; x < d.cols; ++x) o[x] = difference_code(in[x]);
  }
  return out;
}

cv::Mat decode_decikelvin_difference(const cv::Mat& codes) {
  return decode(codes, difference_code_to_celsius);
}

}  // namespace pyrocam
