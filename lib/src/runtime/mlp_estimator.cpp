// The network estimator (Method::kMlp): the paper's network on normalised ratios, the reference
// the lookup table is checked against.
#include <cmath>
#include <cstddef>
#include <utility>

#include "pyrocam/core/locus.h"
#include "runtime/estimator_kinds.h"

namespace pyrocam {

MlpEstimator::MlpEstimator(std::shared_ptr<const ThermalModel> model)
    : TemperatureEstimator(std::move(model)) {
  const ThermalModel& m = *model_;
  if (std::isfinite(m.calibrated_up_to_c) && m.camera.system_qe.rows() == 3)
    pair_ = extrapolation_pair(m.camera,
                               make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0),
                               m.calibrated_up_to_c, m.pair_top_c);
}

double MlpEstimator::temperature_c(const double* s) const {
  if (!all_bands_valid(s)) return NAN;
  const Normalisation& n = model_->profile().normalisation;
  double ref = 0;
  for (int b : n.reference) ref += s[b];
  ref /= static_cast<double>(n.reference.size());
  double x[kMaxBands];
  for (std::size_t i = 0; i < n.numerators.size(); ++i) x[i] = s[n.numerators[i]] / ref;
  return in_range(above_calibration(model_->mlp.predict(x), x));
}

}  // namespace pyrocam
