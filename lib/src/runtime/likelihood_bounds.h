// Provable bounds on the likelihood fit's chi2 from the low-rank factors of its normalised locus
// (likelihood_estimator.cpp): where they tell two samples apart, the exact chi2 need not be
// evaluated.
#pragma once

namespace pyrocam {

// What bounds one pixel's chi2 = sss - ssm^2 / smm besides the factors' values: the error of
// ssm and smm from the factors (row residuals times |w s| and |w|, plus rounding) and a slack
// that covers the rounding of the exact chi2 (profiled_chi2) and of the bounds themselves.
struct FitBounds {
  double sss = 0, ssm_error = 0, smm_error = 0, slack = 0;
};

// Bounds of chi2 when ssm lies within ssm_radius of ssm and smm within smm_radius of smm (the
// factors' error added): every exact chi2 evaluated where that holds lies in [lower, upper].
inline double chi2_lower(double ssm, double ssm_radius, double smm, double smm_radius,
                         const FitBounds& f) {
  const double top = (ssm < 0 ? -ssm : ssm) + ssm_radius + f.ssm_error;
  const double bottom = smm - smm_radius - f.smm_error;
  if (!(bottom > 0)) return -1e300;
  return f.sss - top * top / bottom - f.slack;
}
inline double chi2_upper(double ssm, double smm, const FitBounds& f) {
  const double a = (ssm < 0 ? -ssm : ssm) - f.ssm_error;
  const double top = a > 0 ? a : 0.0;
  return f.sss - top * top / (smm + f.smm_error) + f.slack;
}

}  // namespace pyrocam
