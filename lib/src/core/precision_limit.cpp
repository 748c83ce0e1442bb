#include "pyrocam/core/precision_limit.h"

#include <cmath>
#include <limits>

#include "pyrocam/core/error.h"

namespace pyrocam {

double temperature_precision_limit_k(const CameraModel& camera, double t_c,
                                     const Eigen::VectorXd& mean_dn,
                                     const Eigen::VectorXd& variance_dn2) {
  const Eigen::Index bands = camera.profile.band_count();
  if (mean_dn.size() != bands || variance_dn2.size() != bands)
    throw InputError("precision limit: " + std::to_string(mean_dn.size()) + " means and " +
                     std::to_string(variance_dn2.size()) + " variances for a camera of " +
                     std::to_string(bands) + " bands");
  // d ln s_b / dT by central differences; 0.05 K keeps the step's error below 1e-6 of it.
  constexpr double kStepK = 0.05;
  const Eigen::VectorXd below = camera.rates(t_c - kStepK), above = camera.rates(t_c + kStepK);
  double i_tt = 0, i_ta = 0, i_aa = 0;
  int informative = 0;
  for (Eigen::Index b = 0; b < bands; ++b) {
    const double mu = mean_dn[b], v = variance_dn2[b];
    if (!(std::isfinite(mu) && mu > 0 && std::isfinite(v) && v > 0)) continue;
    if (!(below[b] > 0 && above[b] > 0)) continue;
    const double g = (std::log(above[b]) - std::log(below[b])) / (2 * kStepK);
    // d mu / dT = mu g, d mu / d ln a = mu.
    i_tt += mu * mu * g * g / v;
    i_ta += mu * mu * g / v;
    i_aa += mu * mu / v;
    ++informative;
  }
  const double information = informative >= 2 ? i_tt - i_ta * i_ta / i_aa : 0;
  return information > 0 ? 1 / std::sqrt(information) : std::numeric_limits<double>::infinity();
}

}  // namespace pyrocam
