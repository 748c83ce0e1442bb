#include "pyrocam/runtime/curvature_check.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

CurvatureCheck::CurvatureCheck(const ThermalModel& model, const MosaicLayout& layout,
                               double limit_c)
    : layout_(layout), limit_c_(limit_c) {
  if (layout.kind != MosaicLayout::Kind::kBayer)
    throw InputError("the curvature check reads a Bayer mosaic's samples 2 pixels apart");
  if (!(limit_c > 0)) throw InputError("the curvature check's limit must be > 0 degC");
  const Locus locus = make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, 1);
  const Eigen::Index n = locus.size();
  bands_ = static_cast<int>(locus.rates.cols());
  if (n < 3) throw InputError("the curvature check needs a locus of 3 samples or more");
  const double step_c = locus.temperature_c[1] - locus.temperature_c[0];
  min_code_ = (locus.temperature_c[0] + kZeroCelsius) * kCodesPerKelvin;
  codes_per_step_ = step_c * kCodesPerKelvin;
  slope_.assign(static_cast<std::size_t>(n * bands_), NAN);
  double least = INFINITY;
  for (Eigen::Index i = 1; i + 1 < n; ++i)
    for (Eigen::Index b = 0; b < bands_; ++b) {
      const double lo = locus.rates(i - 1, b), hi = locus.rates(i + 1, b);
      if (!(lo > 0 && hi > 0)) continue;
      const double k = (std::log(hi) - std::log(lo)) / (2 * step_c);
      slope_[static_cast<std::size_t>(i * bands_ + b)] = k;
      if (k > 0) least = std::min(least, k);
    }
  const double clear_log = std::isfinite(least) ? 8 * limit_c_ * least / variance_px2_ : 0;
  lo_ = static_cast<float>(std::exp(-clear_log)), hi_ = static_cast<float>(std::exp(clear_log));
}

double CurvatureCheck::share_c(std::uint16_t code, int band, double laplacian) const {
  const std::size_t n = slope_.size() / static_cast<std::size_t>(bands_);
  const double at = std::round((code - min_code_) / codes_per_step_);
  const auto i = static_cast<std::size_t>(std::clamp(at, 1.0, static_cast<double>(n - 2)));
  const double k = slope_[i * static_cast<std::size_t>(bands_) + static_cast<std::size_t>(band)];
  return k > 0 ? 0.5 * variance_px2_ * laplacian / k : NAN;
}

namespace {

// 1 where a pixel reads, its five samples are above 0.5 DN and finite, and the four around it
// over the fourth power of its own leave [lo, hi]: the few that need a logarithm. Branch-free,
// so that the loop vectorises; without fused multiply-adds both versions give the same bits.
// Returns how many it flagged.
PYROCAM_VECTOR_CLONES
int flag_run(const float* __restrict above, const float* __restrict mid,
             const float* __restrict below, const std::uint16_t* __restrict codes, int x0, int x1,
             float lo, float hi, std::uint8_t* __restrict flag) {
  constexpr float kLeast = 0.5f, kMost = std::numeric_limits<float>::max();  // NaN, INF fail
  int flagged = 0;
  for (int x = x0; x < x1; ++x) {
    const float c = mid[x], e = mid[x + 2], w = mid[x - 2], up = above[x], down = below[x];
    const bool valid = (c > kLeast) & (c <= kMost) & (e > kLeast) & (e <= kMost) & (w > kLeast) &
                       (w <= kMost) & (up > kLeast) & (up <= kMost) & (down > kLeast) &
                       (down <= kMost);
    const float around = (e * w) * (up * down), own = (c * c) * (c * c);
    const bool curved = (around < lo * own) | (around > hi * own);
    const bool check = (codes[x] != kNoReadingCode) & valid & curved;
    flag[x - x0] = static_cast<std::uint8_t>(check);
    flagged += check;
  }
  return flagged;
}

}  // namespace

void CurvatureCheck::apply_run(const cv::Mat& signal, std::uint16_t* codes_row, int y, int x0,
                               int x1) const {
  x0 = std::max(x0, 2), x1 = std::min(x1, signal.cols - 2);
  if (y < 2 || y + 2 >= signal.rows || x1 <= x0) return;
  const float* above = signal.ptr<float>(y - 2);
  const float* mid = signal.ptr<float>(y);
  const float* below = signal.ptr<float>(y + 2);
  // A run is at most a strip's width; the flags on the stack in pieces.
  constexpr int kPiece = 256;
  std::uint8_t flag[kPiece];
  for (int from = x0; from < x1; from += kPiece) {
    const int to = std::min(x1, from + kPiece);
    if (flag_run(above, mid, below, codes_row, from, to, lo_, hi_, flag) == 0) continue;
    for (int x = from; x < to; ++x) {
      if (!flag[x - from]) continue;
      const double around = (static_cast<double>(mid[x + 2]) * mid[x - 2]) *
                            (static_cast<double>(above[x]) * below[x]);
      const double own = static_cast<double>(mid[x]) * mid[x];
      const double share =
          share_c(codes_row[x], layout_.band_at(x, y), std::log(around / (own * own)) / 4);
      if (std::abs(share) > limit_c_) codes_row[x] = kNoReadingCode;
    }
  }
}

void CurvatureCheck::apply_codes(const cv::Mat& signal, cv::Mat& codes) const {
  if (signal.type() != CV_32F || codes.type() != CV_16U || signal.size() != codes.size())
    throw InputError("curvature check: a CV_32F mosaic and CV_16U codes of one size");
  cv::parallel_for_(cv::Range(0, codes.rows), [&](const cv::Range& rows) {
    for (int y = rows.start; y < rows.end; ++y)
      apply_run(signal, codes.ptr<std::uint16_t>(y), y, 0, codes.cols);
  });
}

void CurvatureCheck::apply(const cv::Mat& signal, cv::Mat& temperature_c) const {
  if (temperature_c.type() != CV_32F)
    throw InputError("curvature check: temperatures must be float32 degC");
  cv::Mat codes = encode_decikelvin(temperature_c);
  const cv::Mat before = codes.clone();
  apply_codes(signal, codes);
  temperature_c.setTo(std::numeric_limits<float>::quiet_NaN(), codes != before);
}

}  // namespace pyrocam
