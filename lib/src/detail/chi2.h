// The chi2 distribution's quantiles, for the fits' model tests (the QE fit's leak terms, the
// rates' offsets).
#pragma once

#include <cmath>

namespace pyrocam::detail {

// The level quantile of chi2 with k degrees of freedom (Wilson and Hilferty's cube-root normal
// approximation, within 1 % from k = 3 on).
inline double chi2_quantile(int k, double level) {
  // The standard normal quantile by bisection of its tail.
  double lo = -10, hi = 10;
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::sqrt(2.0)) > 1 - level ? lo : hi) = mid;
  }
  const double z = 0.5 * (lo + hi), a = 2.0 / (9.0 * k);
  return k * std::pow(1 - a + z * std::sqrt(a), 3);
}

}  // namespace pyrocam::detail
