#include "pyrocam/runtime/blur_bias.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

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

void BlurBiasCorrection::apply(cv::Mat& temperature_c) const {
  if (temperature_c.type() != CV_32F)
    throw InputError("blur correction: temperatures must be float32 degC");
  const cv::Mat t = temperature_c.clone();  // the gradients come from the uncorrected readings
  const int rows = t.rows, cols = t.cols;
  auto at = [&](int y, int x) {
    return x < 0 || y < 0 || x >= cols || y >= rows ? NAN : t.at<float>(y, x);
  };
  // A Sobel difference (rows or columns weighted 1, 2, 1) over the pairs that both read; with
  // none, a one-sided difference on the pixel's own row or column; with neither, no gradient.
  auto gradient = [&](int y, int x, float centre, int ax, int ay) {
    constexpr double kWeights[3] = {1, 2, 1};
    double sum = 0, weight = 0;
    for (int k = -1; k <= 1; ++k) {
      const float ahead = at(y + ay + k * ax, x + ax + k * ay);
      const float behind = at(y - ay + k * ax, x - ax + k * ay);
      if (std::isnan(ahead) || std::isnan(behind)) continue;
      sum += kWeights[k + 1] * 0.5 * (static_cast<double>(ahead) - behind);
      weight += kWeights[k + 1];
    }
    if (weight > 0) return sum / weight;
    const float ahead = at(y + ay, x + ax), behind = at(y - ay, x - ax);
    if (!std::isnan(ahead)) return static_cast<double>(ahead) - centre;
    if (!std::isnan(behind)) return static_cast<double>(centre) - behind;
    return 0.0;
  };
  for (int y = 0; y < rows; ++y) {
    float* out = temperature_c.ptr<float>(y);
    for (int x = 0; x < cols; ++x) {
      const float centre = t.at<float>(y, x);
      if (std::isnan(centre)) continue;
      const double gx = gradient(y, x, centre, 1, 0), gy = gradient(y, x, centre, 0, 1);
      out[x] = static_cast<float>(centre - bias_c(centre, gx, gy));
    }
  }
}

void BlurBiasCorrection::apply_codes(cv::Mat& codes) const {
  if (codes.type() != CV_16U) throw InputError("blur correction: codes must be 16-bit");
  cv::Mat t = decode_decikelvin(codes);
  apply(t);
  encode_decikelvin(t, codes);
}

}  // namespace pyrocam
