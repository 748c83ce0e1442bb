// Agreement of two temperature estimators on a model's own locus: the check that a fast
// estimator (the lookup table) gives its reference's answer (the network's) for this model
// before it is trusted with images.
#pragma once

#include <cmath>
#include <cstddef>

#include "pyrocam/runtime/estimators.h"

namespace pyrocam {

struct LocusAgreement {
  std::size_t samples = 0;           // locus temperatures compared
  std::size_t both_valid = 0;        // where both gave a reading
  std::size_t validity_differs = 0;  // where exactly one gave a reading
  double max_difference_c = 0;       // largest |a - b| where both gave a reading
  double worst_temperature_c = NAN;  // the locus temperature where it occurs
};

// Feeds both estimators noise-free graybody signals of the model's camera from its minimum to
// its maximum temperature every step_c, scaled so that the brightest band reads peak_dn, and
// compares their answers. Both estimators must belong to `model`.
LocusAgreement compare_on_locus(const ThermalModel& model, const TemperatureEstimator& a,
                                const TemperatureEstimator& b, double step_c = 1,
                                double peak_dn = 150);

}  // namespace pyrocam
