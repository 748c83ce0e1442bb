// Per-pixel GUM uncertainty of a temperature reading (METHOD.md section 7).
#pragma once

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

}  // namespace pyrocam
