// Per-pixel GUM uncertainty of a temperature reading (METHOD.md section 7).
#pragma once

#include <vector>

#include "pyrocam/runtime/estimators.h"

namespace pyrocam {

// Expanded uncertainty (k from the model, 2 by default) of an estimate, degC: GUM with band
// sensitivities by central differences (dS = 1 DN) and the estimator's systematic terms
// (TemperatureEstimator::systematic_u_c: the model's, or those at a chosen emissivity slope).
// The signal noise is at the estimator's analogue gain (TemperatureEstimator::analogue_gain),
// each band's scaled by variance_factor[band] where given (what demosaicking did to it:
// DemosaicNoise; none: each band value is one sample's).
double expanded_uncertainty_c(const TemperatureEstimator& estimator, const double* signals,
                              double t_c, int frames = 1, const double* variance_factor = nullptr);

// What a reading's expanded uncertainty is without the pixel's noise: the coverage factor times
// the estimator's systematic standard uncertainty (calibration, QE model, emissivity slope) at
// temperatures evenly over the model's range, for what sees temperatures but not signals (a
// peak readout). Above the furnace it is the part that grows where the model extrapolates.
struct SystematicUncertaintyTable {
  double coverage_factor = 2;
  std::vector<double> temperature_c, expanded_u_c;  // ascending temperatures
  // Linear between the samples; NaN for NaN or outside them.
  double at(double t_c) const;
};
inline constexpr int kSystematicTableSamples = 64;
SystematicUncertaintyTable systematic_uncertainty_table(const TemperatureEstimator& estimator,
                                                        int samples = kSystematicTableSamples);

}  // namespace pyrocam
