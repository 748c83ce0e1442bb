#include "pyrocam/runtime/measure.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/runtime/darksub.h"

namespace pyrocam {

PlaneEstimator::PlaneEstimator(const ThermalModel& model, Method method, double misfit_probability)
    : model_(model), estimator_(make_estimator(model, method)), misfit_(nullptr) {
  set_misfit_probability(misfit_probability);
}

void PlaneEstimator::set_misfit_probability(double probability) {
  if (misfit_)
    misfit_->set_probability(probability);
  else if (probability != 0)  // the check's constructor refuses what set_probability refuses
    misfit_ = std::make_unique<MisfitCheck>(model_, probability);
}

void PlaneEstimator::estimate(const std::vector<cv::Mat>& planes, cv::Mat& t, cv::Mat* u) const {
  const int bands = model_.profile().band_count();
  if (static_cast<int>(planes.size()) != bands)
    throw InputError("the stream has " + std::to_string(planes.size()) + " bands, the model " +
                     std::to_string(bands) + " (" + model_.profile().name + ")");
  const cv::Size size = planes[0].size();
  for (const auto& p : planes)
    if (p.type() != CV_32F || p.size() != size)
      throw InputError("band planes must be CV_32F of equal size");
  t.create(size, CV_32F);
  if (u) u->create(size, CV_32F);
  // Rows in parallel: each estimator call is const and thread-safe.
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    std::vector<const float*> row_ptrs(static_cast<std::size_t>(bands));
    std::vector<double> s(static_cast<std::size_t>(bands));
    for (int y = rows.start; y < rows.end; ++y) {
      for (int b = 0; b < bands; ++b) row_ptrs[b] = planes[b].ptr<float>(y);
      float* out = t.ptr<float>(y);
      estimator_->estimate(row_ptrs.data(), static_cast<std::size_t>(size.width), out);
      if (misfit_) misfit_->apply(row_ptrs.data(), static_cast<std::size_t>(size.width), out);
      if (!u) continue;
      float* uo = u->ptr<float>(y);
      for (int x = 0; x < size.width; ++x) {
        if (!std::isfinite(out[x])) {
          uo[x] = NAN;
          continue;
        }
        for (int b = 0; b < bands; ++b) s[b] = row_ptrs[b][x];
        uo[x] = static_cast<float>(expanded_uncertainty_c(*estimator_, s.data(), out[x]));
      }
    }
  });
}

void PlaneEstimator::estimate_codes(const std::vector<cv::Mat>& planes, cv::Mat& codes) const {
  const int bands = model_.profile().band_count();
  if (static_cast<int>(planes.size()) != bands)
    throw InputError("the stream has " + std::to_string(planes.size()) + " bands, the model " +
                     std::to_string(bands) + " (" + model_.profile().name + ")");
  const cv::Size size = planes[0].size();
  for (const auto& p : planes)
    if (p.type() != CV_32F || p.size() != size)
      throw InputError("band planes must be CV_32F of equal size");
  codes.create(size, CV_16U);
  // Row by row: a row's temperatures are encoded while they are in cache.
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    std::vector<const float*> row_ptrs(static_cast<std::size_t>(bands));
    std::vector<float> t(static_cast<std::size_t>(size.width));
    for (int y = rows.start; y < rows.end; ++y) {
      for (int b = 0; b < bands; ++b) row_ptrs[b] = planes[b].ptr<float>(y);
      estimator_->estimate(row_ptrs.data(), static_cast<std::size_t>(size.width), t.data());
      if (misfit_) misfit_->apply(row_ptrs.data(), static_cast<std::size_t>(size.width), t.data());
      encode_temperature_row(t.data(), codes.ptr<std::uint16_t>(y), size.width);
    }
  });
}

FrameMeasurer::FrameMeasurer(const ThermalModel& model, const MeasureOptions& options)
    : model_(model),
      options_(options),
      planes_estimator_(model, options.method, options.misfit_probability) {
  planes_estimator_.set_allow_partial(options.allow_partial);
  if (options_.saturation_level_dn < 0)
    options_.saturation_level_dn = model.profile().thresholds.inference_saturation_dn;
}

cv::Size FrameMeasurer::output_size(cv::Size raw) const {
  return demosaic_output_size(model_.profile().mosaic, options_.demosaic, raw);
}

void FrameMeasurer::measure(const cv::Mat& raw, const cv::Mat& dark, cv::Mat& temperature_c,
                            cv::Mat* uncertainty_c) {
  // A frame of another camera would still give numbers, and plausible ones: refuse what can be
  // told from the frame alone.
  const CameraProfile& profile = model_.profile();
  profile.mosaic.check_whole_periods(raw.cols, raw.rows,
                                     "raw frame for a model of " + profile.name);
  const int depth = profile.bit_depth <= 8 ? CV_8U : CV_16U;
  if (raw.channels() != 1 || raw.depth() != depth)
    throw InputError("raw frame: " +
                     std::string(raw.depth() == CV_8U    ? "8-bit"
                                 : raw.depth() == CV_16U ? "16-bit"
                                                         : cv::depthToString(raw.depth())) +
                     " " + std::to_string(raw.channels()) +
                     "-channel image, but the model's camera (" + profile.name + ") gives " +
                     std::to_string(profile.bit_depth) + "-bit single-channel frames");
  const cv::Mat dark_f = dark.type() == CV_32F ? dark : dark_from_image(dark);
  subtract_dark(raw, dark_f, options_.saturation_level_dn, signal_);
  demosaic(signal_, model_.profile().mosaic, options_.demosaic, planes_);
  planes_estimator_.estimate(planes_, temperature_c, uncertainty_c);
}

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
