// The estimators' common part: the methods by name, the base class and the factory (each method
// in a file of its own: mlp_estimator.cpp, lut_estimator.cpp, likelihood_estimator.cpp).
#include "pyrocam/runtime/estimators.h"

#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>

#include "pyrocam/core/error.h"
#include "runtime/estimator_kinds.h"
#include "runtime/shared_model.h"

namespace pyrocam {

Method parse_method(const std::string& name) {
  if (name == "mlp") return Method::kMlp;
  if (name == "lut") return Method::kLut;
  if (name == "likelihood") return Method::kLikelihood;
  throw InputError("unknown method '" + name + "' (use mlp, lut or likelihood)");
}

std::string method_name(Method m) {
  switch (m) {
    case Method::kMlp:
      return "mlp";
    case Method::kLut:
      return "lut";
    case Method::kLikelihood:
      return "likelihood";
  }
  return "?";
}

TemperatureEstimator::TemperatureEstimator(std::shared_ptr<const ThermalModel> model)
    : model_(std::move(model)),
      bands_(require_model(model_, "temperature estimator").profile().band_count()),
      dim_dn_(model_->profile().thresholds.inference_dim_dn),
      min_bands_(bands_) {
  if (bands_ > kMaxBands) throw InputError("at most 64 bands are supported");
}

bool TemperatureEstimator::all_bands_valid(const double* s) const {
  for (int b = 0; b < bands_; ++b)
    if (!std::isfinite(s[b]) || s[b] < dim_dn_) return false;
  return true;
}

double TemperatureEstimator::in_range(double t_c) const {
  return t_c >= model_->min_temperature_c && t_c <= model_->max_temperature_c ? t_c : NAN;
}

double TemperatureEstimator::systematic_u_c(double t_c) const {
  return model_->uncertainty.systematic_u_c(t_c);
}

void TemperatureEstimator::estimate(const float* const* planes, std::size_t n, float* out) const {
  double s[kMaxBands];
  for (std::size_t i = 0; i < n; ++i) {
    for (int b = 0; b < bands_; ++b) s[b] = planes[b][i];
    out[i] = static_cast<float>(temperature_c(s));
  }
}

void TemperatureEstimator::set_analogue_gain(double factor) {
  if (!(factor > 0) || !std::isfinite(factor))
    throw InputError("the analogue gain must be a positive factor, not " + std::to_string(factor));
  analogue_gain_ = factor;
}

std::unique_ptr<TemperatureEstimator> make_estimator(std::shared_ptr<const ThermalModel> model,
                                                     Method method) {
  switch (method) {
    case Method::kMlp:
      return std::make_unique<MlpEstimator>(std::move(model));
    case Method::kLikelihood:
      return make_likelihood_estimator(std::move(model));
    case Method::kLut:
      return make_lut_estimator(std::move(model));
  }
  throw InputError("unknown estimator method");
}

std::size_t TemperatureEstimator::save_tables(const std::string&) const { return 0; }
std::size_t TemperatureEstimator::load_tables(const std::string&) const { return 0; }
void TemperatureEstimator::set_tables_verdict(const std::string&) const {}
std::size_t TemperatureEstimator::fill_tables(const std::vector<std::uint32_t>&) const { return 0; }

}  // namespace pyrocam
