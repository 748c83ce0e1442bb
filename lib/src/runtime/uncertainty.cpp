#include "pyrocam/runtime/uncertainty.h"

#include <algorithm>
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

double SystematicUncertaintyTable::at(double t_c) const {
  const std::size_t n = std::min(temperature_c.size(), expanded_u_c.size());
  if (n == 0 || !(t_c >= temperature_c.front() && t_c <= temperature_c[n - 1])) return NAN;
  const auto hi = static_cast<std::size_t>(
      std::upper_bound(temperature_c.begin(), temperature_c.begin() + static_cast<long>(n), t_c) -
      temperature_c.begin());
  if (hi >= n) return expanded_u_c[n - 1];
  const std::size_t lo = hi - 1;  // hi >= 1: t_c >= the first sample
  const double f = (t_c - temperature_c[lo]) / (temperature_c[hi] - temperature_c[lo]);
  return expanded_u_c[lo] + f * (expanded_u_c[hi] - expanded_u_c[lo]);
}

SystematicUncertaintyTable systematic_uncertainty_table(const TemperatureEstimator& estimator,
                                                        int samples) {
  const ThermalModel& m = estimator.model();
  SystematicUncertaintyTable table;
  table.coverage_factor = m.uncertainty.coverage_factor;
  samples = std::max(samples, 2);
  for (int i = 0; i < samples; ++i) {
    const double t =
        m.min_temperature_c + (m.max_temperature_c - m.min_temperature_c) * i / (samples - 1);
    table.temperature_c.push_back(t);
    table.expanded_u_c.push_back(table.coverage_factor * estimator.systematic_u_c(t));
  }
  return table;
}

}  // namespace pyrocam
