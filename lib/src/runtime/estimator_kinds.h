// What the estimator files share (not installed): the network estimator, which the lookup table
// asks about the pixels it does not tabulate, and the factories of the other methods, which
// make_estimator calls.
#pragma once

#include <memory>

#include "detail/portable_math.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/extrapolation_pair.h"

namespace pyrocam {

// Bands an estimator reads at most (per-pixel arrays on the stack).
inline constexpr int kMaxBands = 64;

// The paper's network on normalised ratios (Method::kMlp; mlp_estimator.cpp). The network is
// trained on readings of every band; above the model's calibration a colour model's reading
// then passes to the pair's as the likelihood fit's does (extrapolation_pair.h), a function of
// the same ratios, so that the lookup table tabulates it too.
class MlpEstimator : public TemperatureEstimator {
 public:
  explicit MlpEstimator(std::shared_ptr<const ThermalModel> model);
  double temperature_c(const double* s) const override;
  // The network's reading t_c of normalised ratios x, moved to the pair's above the
  // calibration; not checked against the range.
  double above_calibration(double t_c, const double* x) const {
    if (!pair_.active() || !(t_c > pair_.from_c)) return t_c;
    const double num = pair_.numerator_ratio < 0 ? 1.0 : x[pair_.numerator_ratio];
    const double den = pair_.denominator_ratio < 0 ? 1.0 : x[pair_.denominator_ratio];
    return num > 0 && den > 0 ? pair_.read(t_c, portable::log(num / den)) : t_c;
  }

 private:
  ExtrapolationPair pair_;
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
