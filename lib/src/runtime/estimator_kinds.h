// What the estimator files share (not installed): the network estimator, which the lookup table
// asks about the pixels it does not tabulate, and the factories of the other methods, which
// make_estimator calls.
#pragma once

#include <memory>

#include "pyrocam/runtime/estimators.h"

namespace pyrocam {

// Bands an estimator reads at most (per-pixel arrays on the stack).
inline constexpr int kMaxBands = 64;

// The paper's network on normalised ratios (Method::kMlp; mlp_estimator.cpp).
class MlpEstimator : public TemperatureEstimator {
 public:
  using TemperatureEstimator::TemperatureEstimator;
  double temperature_c(const double* s) const override;
};

// lut_estimator.cpp: throws InputError unless the model has exactly two ratios.
std::unique_ptr<TemperatureEstimator> make_lut_estimator(std::shared_ptr<const ThermalModel> model);
// likelihood_estimator.cpp: the fast fit.
std::unique_ptr<TemperatureEstimator> make_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model);

}  // namespace pyrocam
