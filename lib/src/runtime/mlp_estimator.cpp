// The network estimator (Method::kMlp): the paper's network on normalised ratios, the reference
// the lookup table is checked against.
#include <cmath>
#include <cstddef>

#include "runtime/estimator_kinds.h"

namespace pyrocam {

double MlpEstimator::temperature_c(const double* s) const {
  if (!all_bands_valid(s)) return NAN;
  const Normalisation& n = model_->profile().normalisation;
  double ref = 0;
  for (int b : n.reference) ref += s[b];
  ref /= static_cast<double>(n.reference.size());
  double x[kMaxBands];
  for (std::size_t i = 0; i < n.numerators.size(); ++i) x[i] = s[n.numerators[i]] / ref;
  return in_range(model_->mlp.predict(x));
}

}  // namespace pyrocam
