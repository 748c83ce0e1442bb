#include "pyrocam/runtime/above_range.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>

#include "pyrocam/core/noise_model.h"
#include "runtime/shared_model.h"

namespace pyrocam {
namespace {

std::shared_ptr<const ThermalModel> extended_model(const std::shared_ptr<const ThermalModel>& m) {
  auto extended = std::make_shared<ThermalModel>(require_model(m, "the above-range check"));
  extended->max_temperature_c = kAboveRangeTopC;
  return extended;
}

}  // namespace

AboveRangeCheck::AboveRangeCheck(std::shared_ptr<const ThermalModel> model)
    : extended_(extended_model(model)),
      fit_(make_estimator(extended_, Method::kLikelihood)),
      misfit_(extended_, kAboveRangeMisfitProbability, kAboveRangeModelError),
      locus_(make_locus(extended_->camera, model->max_temperature_c - kCurvatureStepC,
                        kAboveRangeTopC, kLocusStepC)),
      max_c_(model->max_temperature_c),
      dim_dn_(model->profile().thresholds.inference_dim_dn),
      bands_(model->profile().band_count()) {}

double AboveRangeCheck::reading_above(const double* signals) const {
  for (int b = 0; b < bands_; ++b)
    if (!(signals[b] >= dim_dn_ && std::isfinite(signals[b]))) return NAN;
  const double t = fit_->temperature_c(signals);  // NaN at either end of the extended locus
  if (!(t > max_c_)) return NAN;
  if (!(t - kAboveRangeSigmas * noise_sd_c(signals, t) > max_c_)) return NAN;
  int counted = 0;
  const double chi2 = misfit_.chi2(signals, t, &counted);
  return chi2 <= misfit_.threshold(counted) ? t : NAN;
}

double AboveRangeCheck::noise_sd_c(const double* signals, double t_c) const {
  // chi2(T) = sum w (s - a m(T))^2 with the scale profiled out, at the locus sample nearest T
  // and kCurvatureStepC either side.
  const Eigen::Index step = static_cast<Eigen::Index>(kCurvatureStepC / kLocusStepC);
  const Eigen::Index i = std::clamp<Eigen::Index>(
      static_cast<Eigen::Index>(std::lround((t_c - locus_.temperature_c[0]) / kLocusStepC)), step,
      locus_.size() - 1 - step);
  const double h = kCurvatureStepC;
  const auto chi2_at = [&](Eigen::Index k) {
    const auto m = locus_.rates.row(k);
    double ss = 0, sm = 0, mm = 0;
    for (int b = 0; b < bands_; ++b) {
      const double w =
          1 / signal_variance_dn2(extended_->profile(), b, signals[b], 1, analogue_gain_);
      ss += w * signals[b] * signals[b];
      sm += w * signals[b] * m[b];
      mm += w * m[b] * m[b];
    }
    return ss - sm * sm / mm;
  };
  const double curvature = (chi2_at(i - step) - 2 * chi2_at(i) + chi2_at(i + step)) / (h * h);
  return curvature > 0 ? std::sqrt(2 / curvature) : INFINITY;
}

void AboveRangeCheck::set_analogue_gain(double factor) {
  fit_->set_analogue_gain(factor);
  misfit_.set_analogue_gain(factor);
  analogue_gain_ = factor;
}

SaturatedSamples above_range_spots(const std::vector<cv::Point>& found, cv::Size size,
                                   std::vector<cv::Point>* kept_pixels) {
  SaturatedSamples spots;
  if (kept_pixels) kept_pixels->clear();
  const cv::Rect frame(cv::Point(0, 0), size);
  cv::Rect bounds;
  for (const cv::Point& p : found)
    if (frame.contains(p)) bounds |= cv::Rect(p.x, p.y, 1, 1);
  if (bounds.empty()) return spots;
  // A mask with a border of one pixel, so that each neighbourhood needs no bounds checks.
  cv::Mat mask = cv::Mat::zeros(bounds.height + 2, bounds.width + 2, CV_8U);
  for (const cv::Point& p : found)
    if (frame.contains(p)) mask.at<std::uint8_t>(p.y - bounds.y + 1, p.x - bounds.x + 1) = 1;
  cv::Rect kept;
  for (int y = 1; y <= bounds.height; ++y)
    for (int x = 1; x <= bounds.width; ++x) {
      if (!mask.at<std::uint8_t>(y, x)) continue;
      int around = 0;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) around += mask.at<std::uint8_t>(y + dy, x + dx) != 0;
      if (around < 5) continue;
      const cv::Point p(x - 1 + bounds.x, y - 1 + bounds.y);
      ++spots.count;
      kept |= cv::Rect(p.x, p.y, 1, 1);
      if (kept_pixels) kept_pixels->push_back(p);
      spots.tiles[static_cast<std::size_t>(saturation_tile_of(p.y, size.height))] |=
          std::uint64_t{1} << saturation_tile_of(p.x, size.width);
    }
  spots.bounds = kept;
  return spots;
}

}  // namespace pyrocam
