#include "pyrocam/runtime/blur_bias.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

BlurBiasCorrection::BlurBiasCorrection(const ThermalModel& model, DemosaicMethod method) {
  const MosaicLayout& layout = model.profile().mosaic;
  if (resolve_demosaic_method(method, layout) != DemosaicMethod::kMatched)
    throw InputError(
        "the blur correction needs matched demosaicking (every band through a kernel of the "
        "same spread); the planes come from another method");
  variance_px2_ = layout.kind == MosaicLayout::Kind::kBayer ? 1.0 : 0.25;
  const Locus locus = make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, 1);
  const Eigen::Index n = locus.size(), bands = locus.rates.cols();
  min_c_ = locus.temperature_c[0];
  step_c_ = n > 1 ? locus.temperature_c[1] - locus.temperature_c[0] : 1;
  kappa_.assign(static_cast<std::size_t>(n), 0.0);
  constexpr Eigen::Index kH = 2;  // samples each side of the finite differences
  for (Eigen::Index i = kH; i + kH < n; ++i) {
    Eigen::VectorXd k(bands), c(bands);
    bool positive = true;
    for (Eigen::Index b = 0; b < bands; ++b) {
      const double lo = locus.rates(i - kH, b), mid = locus.rates(i, b),
                   hi = locus.rates(i + kH, b);
      positive = positive && lo > 0 && mid > 0 && hi > 0;
      const double h = kH * step_c_;
      k[b] = (std::log(hi) - std::log(lo)) / (2 * h);
      c[b] = (hi - 2 * mid + lo) / (h * h * mid);
    }
    if (!positive) continue;
    const Eigen::ArrayXd dk = k.array() - k.mean(), dc = c.array() - c.mean();
    const double var = (dk * dk).sum();
    kappa_[static_cast<std::size_t>(i)] = var > 0 ? (dk * dc).sum() / var : 0.0;
  }
  for (Eigen::Index i = 0; i < std::min(kH, n); ++i) {  // the ends take their neighbours'
    kappa_[static_cast<std::size_t>(i)] = kappa_[static_cast<std::size_t>(std::min(kH, n - 1))];
    kappa_[static_cast<std::size_t>(n - 1 - i)] =
        kappa_[static_cast<std::size_t>(std::max<Eigen::Index>(n - 1 - kH, 0))];
  }
  // The row kernel's copy, with the last value once more for its interpolation's upper corner.
  row_kappa_.assign(kappa_.begin(), kappa_.end());
  row_kappa_.push_back(row_kappa_.empty() ? 0.f : row_kappa_.back());
}

double BlurBiasCorrection::kappa_per_c(double t_c) const {
  if (kappa_.empty() || !std::isfinite(t_c)) return 0.0;
  const double at =
      std::clamp((t_c - min_c_) / step_c_, 0.0, static_cast<double>(kappa_.size() - 1));
  const auto i = static_cast<std::size_t>(at);
  const std::size_t j = std::min(i + 1, kappa_.size() - 1);
  const double f = at - static_cast<double>(i);
  return kappa_[i] + f * (kappa_[j] - kappa_[i]);
}

namespace {

// One output row from the uncorrected rows above, at and below it, each padded with a NaN at
// both ends (p = x + 1; a missing row is all NaN). The gradient: a Sobel difference (rows or
// columns weighted 1, 2, 1) over the pairs that both read; with none, a one-sided difference
// on the pixel's own row or column; with neither, none. Branch-free selects, so that the loop
// vectorises (NaN fails every comparison).
struct RowKernel {
  const float* kappa;  // per locus sample, then one more (the last again)
  float min_c, inv_step, last_index, half_variance;
};

PYROCAM_VECTOR_CLONES
void correct_row(const float* __restrict up, const float* __restrict mid,
                 const float* __restrict down, int n, RowKernel k, float* __restrict out) {
  for (int x = 0; x < n; ++x) {
    const int p = x + 1;
    const float m = mid[p];
    // Rows above, at and below (x pairs) and columns left, at and right (y pairs).
    const float ax0 = up[p + 1], bx0 = up[p - 1], ax1 = mid[p + 1], bx1 = mid[p - 1];
    const float ax2 = down[p + 1], bx2 = down[p - 1];
    const float ay0 = down[p - 1], by0 = up[p - 1], ay1 = down[p], by1 = up[p];
    const float ay2 = down[p + 1], by2 = up[p + 1];
    const bool px0 = ax0 == ax0 && bx0 == bx0, px1 = ax1 == ax1 && bx1 == bx1,
               px2 = ax2 == ax2 && bx2 == bx2;
    const bool py0 = ay0 == ay0 && by0 == by0, py1 = ay1 == ay1 && by1 == by1,
               py2 = ay2 == ay2 && by2 == by2;
    const float sx = (px0 ? 0.5f * (ax0 - bx0) : 0.f) + (px1 ? ax1 - bx1 : 0.f) +
                     (px2 ? 0.5f * (ax2 - bx2) : 0.f);
    const float wx = (px0 ? 1.f : 0.f) + (px1 ? 2.f : 0.f) + (px2 ? 1.f : 0.f);
    const float sy = (py0 ? 0.5f * (ay0 - by0) : 0.f) + (py1 ? ay1 - by1 : 0.f) +
                     (py2 ? 0.5f * (ay2 - by2) : 0.f);
    const float wy = (py0 ? 1.f : 0.f) + (py1 ? 2.f : 0.f) + (py2 ? 1.f : 0.f);
    const float right = mid[p + 1], left = mid[p - 1], below = down[p], above = up[p];
    const float one_x = right == right ? right - m : left == left ? m - left : 0.f;
    const float one_y = below == below ? below - m : above == above ? m - above : 0.f;
    const float gx = wx > 0.f ? sx / (wx > 0.f ? wx : 1.f) : one_x;
    const float gy = wy > 0.f ? sy / (wy > 0.f ? wy : 1.f) : one_y;
    out[x] = gx * gx + gy * gy;
  }
  // The bias, kappa interpolated in its table (a loop of its own: the gathers).
  for (int x = 0; x < n; ++x) {
    const float m = mid[x + 1];
    const float at = m == m ? (m - k.min_c) * k.inv_step : 0.f;
    const float clamped = at < 0.f ? 0.f : at > k.last_index ? k.last_index : at;
    const int i = static_cast<int>(clamped);
    const float f = clamped - static_cast<float>(i);
    const float kappa = k.kappa[i] + f * (k.kappa[i + 1] - k.kappa[i]);
    out[x] = m - k.half_variance * kappa * out[x];  // NaN stays NaN
  }
}

PYROCAM_VECTOR_CLONES
void decode_row(const std::uint16_t* __restrict codes, int n, float* __restrict out) {
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  for (int x = 0; x < n; ++x)
    out[x] = codes[x] != kNoReadingCode
                 ? static_cast<float>(codes[x]) * (1.f / static_cast<float>(kCodesPerKelvin)) -
                       static_cast<float>(kZeroCelsius)
                 : kNan;
}

bool any_reading(const float* v, int n) {
  for (int x = 0; x < n; ++x)
    if (v[x] == v[x]) return true;
  return false;
}

}  // namespace

// Rows in a ring of three uncorrected rows (each padded), so each row is read once and written
// in place; rows without a reading are left as they are.
template <class LoadRow, class StoreRow>
void BlurBiasCorrection::correct_rows(int rows, int cols, LoadRow load, StoreRow store) const {
  constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
  const auto padded = static_cast<std::size_t>(cols) + 2;
  std::vector<float> buffer(4 * padded, kNan);  // three rows, then the output row
  const RowKernel k{row_kappa_.data(), static_cast<float>(min_c_), static_cast<float>(1 / step_c_),
                    static_cast<float>(std::max<std::size_t>(kappa_.size(), 1) - 1),
                    static_cast<float>(0.5 * variance_px2_)};
  const std::vector<float> nan_row(padded, kNan);
  float* ring[3] = {buffer.data(), buffer.data() + padded, buffer.data() + 2 * padded};
  float* out = buffer.data() + 3 * padded;
  bool has[3] = {false, false, false};
  auto fill = [&](int slot, int y) {
    has[slot] = y >= 0 && y < rows;
    if (has[slot]) {
      load(y, ring[slot] + 1);
      has[slot] = any_reading(ring[slot] + 1, cols);
    }
  };
  fill(0, -1);
  fill(1, 0);
  fill(2, 1);
  for (int y = 0; y < rows; ++y) {  // ring: rows y - 1, y, y + 1
    if (has[1]) {
      correct_row(has[0] ? ring[0] : nan_row.data(), ring[1], has[2] ? ring[2] : nan_row.data(),
                  cols, k, out);
      store(y, out);
    }
    std::rotate(ring, ring + 1, ring + 3);
    std::rotate(has, has + 1, has + 3);
    fill(2, y + 2);
  }
}

void BlurBiasCorrection::apply(cv::Mat& temperature_c) const {
  if (temperature_c.type() != CV_32F)
    throw InputError("blur correction: temperatures must be float32 degC");
  const int cols = temperature_c.cols;
  correct_rows(
      temperature_c.rows, cols,
      [&](int y, float* row) {
        const float* in = temperature_c.ptr<float>(y);
        std::copy(in, in + cols, row);
      },
      [&](int y, const float* row) { std::copy(row, row + cols, temperature_c.ptr<float>(y)); });
}

void BlurBiasCorrection::apply_codes(cv::Mat& codes) const {
  if (codes.type() != CV_16U) throw InputError("blur correction: codes must be 16-bit");
  correct_rows(
      codes.rows, codes.cols,
      [&](int y, float* row) { decode_row(codes.ptr<std::uint16_t>(y), codes.cols, row); },
      [&](int y, const float* row) {
        encode_temperature_row(row, codes.ptr<std::uint16_t>(y), codes.cols);
      });
}

}  // namespace pyrocam
