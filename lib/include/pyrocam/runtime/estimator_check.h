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

// Where an estimator reads graybodies hotter than the model's range as temperatures inside it: a
// network trained only up to a narrow range's end reads the ratios beyond it as some temperature
// it knows (the colour camera's ratios turn over, so 2600 degC can look to a network trained up
// to 2000 like 1800 degC: a test model cut so read a 2600 degC plate 1812 degC), a wrong reading
// that looks right, where the likelihood fit gives none and the above-range check finds them.
// Noise-free graybody signals of the model's camera from max_temperature_c + step_c up to
// span_c above it (at most 6000 degC), every step_c, brightest band at
// peak_dn; a reading inside the range more than kFoldToleranceC below the truth counts.
// 500 degC: far enough for a narrow range's turnover (a network trained to 2000 degC reads
// 2410 degC and up inside its range), near enough that the full range's networks pass (the test
// model's reads 4500 degC as 3498 degC: ratios change little so far up, and graybodies that hot
// are rare).
inline constexpr double kFoldSpanC = 500;
struct AboveRangeFold {
  static constexpr double kFoldToleranceC = 50;
  std::size_t samples = 0, read_inside = 0;
  double worst_true_c = NAN, worst_read_c = NAN;  // the largest such error
};
AboveRangeFold fold_above_range(const ThermalModel& model, const TemperatureEstimator& e,
                                double span_c = kFoldSpanC, double step_c = 10,
                                double peak_dn = 150);

}  // namespace pyrocam
