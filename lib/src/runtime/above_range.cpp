#include "pyrocam/runtime/above_range.h"

#include <cmath>
#include <cstdint>
#include <utility>

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
      max_c_(model->max_temperature_c),
      dim_dn_(model->profile().thresholds.inference_dim_dn),
      bands_(model->profile().band_count()) {}

double AboveRangeCheck::reading_above(const double* signals) const {
  for (int b = 0; b < bands_; ++b)
    if (!(signals[b] >= dim_dn_ && std::isfinite(signals[b]))) return NAN;
  const double t = fit_->temperature_c(signals);  // NaN at either end of the extended locus
  if (!(t > max_c_)) return NAN;
  int counted = 0;
  const double chi2 = misfit_.chi2(signals, t, &counted);
  return chi2 <= misfit_.threshold(counted) ? t : NAN;
}

void AboveRangeCheck::set_analogue_gain(double factor) {
  fit_->set_analogue_gain(factor);
  misfit_.set_analogue_gain(factor);
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
