#include "pyrocam/runtime/uncertainty.h"

#include <cmath>

#include "pyrocam/core/noise_model.h"
#include "runtime/estimator_kinds.h"

namespace pyrocam {

double expanded_uncertainty_c(const TemperatureEstimator& est, const double* signals, double t_c,
                              int frames, const double* variance_factor) {
  if (!std::isfinite(t_c)) return NAN;
  const ThermalModel& m = est.model();
  const int bands = m.profile().band_count();
  double s[kMaxBands];
  for (int b = 0; b < bands; ++b) s[b] = signals[b];
  double var = 0;
  for (int b = 0; b < bands; ++b) {
    if (!std::isfinite(s[b])) continue;
    const double keep = s[b];
    s[b] = keep + 1;
    const double tp = est.temperature_c(s);
    s[b] = keep - 1;
    const double tm = est.temperature_c(s);
    s[b] = keep;
    double dt_ds;
    if (std::isfinite(tp) && std::isfinite(tm))
      dt_ds = (tp - tm) / 2;
    else if (std::isfinite(tp))
      dt_ds = tp - t_c;
    else if (std::isfinite(tm))
      dt_ds = t_c - tm;
    else
      continue;
    var += dt_ds * dt_ds * signal_variance_dn2(m.profile(), b, keep, frames, est.analogue_gain()) *
           (variance_factor ? variance_factor[b] : 1.0);
  }
  const double sys = est.systematic_u_c(t_c);
  return m.uncertainty.coverage_factor * std::sqrt(var + sys * sys);
}

}  // namespace pyrocam
