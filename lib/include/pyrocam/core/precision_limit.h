// The precision no estimator can beat: the Cramer-Rao bound of one pixel's temperature from its
// band signals, for the benchmarks to hold the estimators' scatter against (METHOD.md section 7,
// the shot-noise limit).
#pragma once

#include <Eigen/Core>

#include "pyrocam/core/locus.h"

namespace pyrocam {

// Standard deviation, K, below which no unbiased reading of a graybody at t_c can scatter, from
// band signals of means `mean_dn` (DN after dark subtraction; a graybody of the camera's
// spectra at t_c, at any scale) and independent Gaussian noise of variances `variance_dn2`,
// the scale unknown (exposure, emissivity, distance): the Fisher information of the means
// a * s_b(T) in T with a profiled out, 1 / (I_TT - I_Ta^2 / I_aa). With shot noise only (the
// variance K_b * mean_b: N_b photoelectrons) it is the shot-noise limit
// var(T) = T^4 / (c2^2 N Var_w(1 / lambda_eff)) of METHOD.md, its d ln s_b / dT from Planck's
// law through each band's spectrum rather than Wien's at one wavelength. Bands with a
// non-finite or non-positive mean or variance carry no information. +inf when fewer than two
// bands do (a single band cannot tell temperature from scale).
double temperature_precision_limit_k(const CameraModel& camera, double t_c,
                                     const Eigen::VectorXd& mean_dn,
                                     const Eigen::VectorXd& variance_dn2);

}  // namespace pyrocam
