#include "pyrocam/runtime/estimator_check.h"

#include <vector>

#include "pyrocam/core/locus.h"

namespace pyrocam {

LocusAgreement compare_on_locus(const ThermalModel& model, const TemperatureEstimator& a,
                                const TemperatureEstimator& b, double step_c, double peak_dn) {
  const Locus locus =
      make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, step_c);
  const auto bands = static_cast<std::size_t>(locus.rates.cols());
  std::vector<double> signals(bands);
  LocusAgreement r;
  for (Eigen::Index i = 0; i < locus.size(); ++i) {
    const double scale = peak_dn / locus.rates.row(i).maxCoeff();
    for (std::size_t k = 0; k < bands; ++k)
      signals[k] = locus.rates(i, static_cast<Eigen::Index>(k)) * scale;
    const double ta = a.temperature_c(signals.data()), tb = b.temperature_c(signals.data());
    ++r.samples;
    if (std::isfinite(ta) != std::isfinite(tb)) ++r.validity_differs;
    if (!std::isfinite(ta) || !std::isfinite(tb)) continue;
    ++r.both_valid;
    if (std::abs(ta - tb) > r.max_difference_c || r.both_valid == 1) {
      r.max_difference_c = std::abs(ta - tb);
      r.worst_temperature_c = locus.temperature_c[i];
    }
  }
  return r;
}

}  // namespace pyrocam
