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
// The same on a grid a table file of the model names (TemperatureEstimator::table_grid of the
// table that wrote it) instead of the one derived from the model's locus and network (a third of
// the table's start, and the same grid for a file this build wrote for the model); throws
// InputError for a grid no model gives.
std::unique_ptr<TemperatureEstimator> make_lut_estimator_on_grid(
    std::shared_ptr<const ThermalModel> model, const TemperatureEstimator::TableGrid& grid);
// likelihood_estimator.cpp: the fast fit.
std::unique_ptr<TemperatureEstimator> make_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model);
// Whether a fit of make_likelihood_estimator reads pixels whose bands all read by the descent
// (likelihood_descent.h): its model's ratio rises steadily and the two paths agreed when it was
// made. with_dropped_bands: whether it also reads so the pixels with a few bands dropped (dim,
// saturated or invalid; partial readings), where they agreed on such pixels too.
bool likelihood_fit_descends(const TemperatureEstimator& estimator,
                             bool with_dropped_bands = false);

}  // namespace pyrocam
