#include "pyrocam/runtime/darksub.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

std::string size_text(const cv::Mat& m) {
  return std::to_string(m.cols) + "x" + std::to_string(m.rows);
}

constexpr float kInf = std::numeric_limits<float>::infinity();

// One row; __restrict lets the compiler vectorise the select.
template <typename T>
void subtract_row(const T* __restrict r, const float* __restrict d, float* __restrict o, int n,
                  float saturation) {
  for (int x = 0; x < n; ++x) {
    const float v = static_cast<float>(r[x]);
    o[x] = v >= saturation ? kInf : v - d[x];
  }
}

template <typename T>
void subtract_level_row(const T* __restrict r, float level, float* __restrict o, int n,
                        float saturation) {
  for (int x = 0; x < n; ++x) {
    const float v = static_cast<float>(r[x]);
    o[x] = v >= saturation ? kInf : v - level;
  }
}

// Runs row(y) for every row, over two threads for large frames.
template <typename Row>
void for_rows(const cv::Mat& m, Row row) {
  if (m.total() < 512u * 512u) {
    for (int y = 0; y < m.rows; ++y) row(y);
    return;
  }
  cv::parallel_for_(
      cv::Range(0, m.rows),
      [&](const cv::Range& r) {
        for (int y = r.start; y < r.end; ++y) row(y);
      },
      2.0);
}

void check_raw(const cv::Mat& raw) {
  if (raw.type() != CV_8U && raw.type() != CV_16U)
    throw InputError("dark subtraction: raw frame must be 8- or 16-bit single-channel");
}

}  // namespace

int full_scale_dn(int bit_depth) {
  if (bit_depth < 1 || bit_depth > 16)
    throw InputError("bit depth " + std::to_string(bit_depth) + " outside 1..16");
  return (1 << bit_depth) - 1;
}

double default_saturation_level(int bit_depth) {
  return std::round(220.0 / 255.0 * full_scale_dn(bit_depth));
}

void subtract_dark(const cv::Mat& raw, const cv::Mat& dark, double saturation_level, cv::Mat& out) {
  check_raw(raw);
  if (dark.type() != CV_32F) throw InputError("dark subtraction: dark frame must be CV_32F");
  if (dark.size() != raw.size())
    throw InputError("dark frame is " + size_text(dark) + " but the camera frame is " +
                     size_text(raw));
  out.create(raw.size(), CV_32F);
  // A level above what fits a float exactly still compares correctly against integer samples.
  const float saturation = static_cast<float>(saturation_level);
  const int n = raw.cols;
  if (raw.type() == CV_8U)
    for_rows(raw, [&](int y) {
      subtract_row(raw.ptr<std::uint8_t>(y), dark.ptr<float>(y), out.ptr<float>(y), n, saturation);
    });
  else
    for_rows(raw, [&](int y) {
      subtract_row(raw.ptr<std::uint16_t>(y), dark.ptr<float>(y), out.ptr<float>(y), n, saturation);
    });
}

void subtract_dark_level(const cv::Mat& raw, double level_dn, double saturation_level,
                         cv::Mat& out) {
  check_raw(raw);
  out.create(raw.size(), CV_32F);
  const float saturation = static_cast<float>(saturation_level);
  const float level = static_cast<float>(level_dn);
  const int n = raw.cols;
  if (raw.type() == CV_8U)
    for_rows(raw, [&](int y) {
      subtract_level_row(raw.ptr<std::uint8_t>(y), level, out.ptr<float>(y), n, saturation);
    });
  else
    for_rows(raw, [&](int y) {
      subtract_level_row(raw.ptr<std::uint16_t>(y), level, out.ptr<float>(y), n, saturation);
    });
}

cv::Mat dark_from_image(const cv::Mat& image) {
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw InputError("dark frame must be an 8- or 16-bit single-channel image");
  cv::Mat dark;
  image.convertTo(dark, CV_32F);
  return dark;
}

void DarkAccumulator::reset() {
  sum_.release();
  count_ = 0;
}

void DarkAccumulator::add(const cv::Mat& raw) {
  if (raw.type() != CV_8U && raw.type() != CV_16U)
    throw InputError("dark capture: frames must be 8- or 16-bit single-channel");
  if (count_ == 0) {
    sum_ = cv::Mat::zeros(raw.size(), CV_64F);
  } else if (raw.size() != sum_.size()) {
    throw InputError("dark capture: frame is " + size_text(raw) + " but the first was " +
                     size_text(sum_));
  }
  cv::add(sum_, raw, sum_, cv::noArray(), CV_64F);
  ++count_;
}

cv::Mat DarkAccumulator::mean() const {
  if (count_ == 0) throw InputError("dark capture: no frame captured");
  cv::Mat dark;
  sum_.convertTo(dark, CV_32F, 1.0 / count_);
  return dark;
}

}  // namespace pyrocam
