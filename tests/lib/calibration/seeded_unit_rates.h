// A seeded simulated unit at the level of signal rates (no images): its profile, true QE and
// furnace campaign, with the unit and campaign seeds of bench_extrapolation, and how a fit of it
// reads at 2600 degC. For the QE fit's tests of its choices (leak terms, prior widths).
#pragma once

#include <cstdint>

#include "pyrocam/calibration/extrapolation_study.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::test {

struct SeededUnit {
  CameraProfile profile;
  Eigen::MatrixXd truth;
  CalibrationRates data;
};

inline SeededUnit seeded_unit(const char* profile, const char* family, int seed) {
  SeededUnit u{load_profile_by_name(profile), {}, {}};
  u.truth = true_system_qe(u.profile, UnitPerturbation::parse(family, seed));
  RateCampaign campaign;
  campaign.seed = 100 + static_cast<std::uint64_t>(seed);
  u.data = simulate_calibration_rates(u.profile, u.truth, campaign);
  return u;
}

// The fitted model's reading error at 2600 degC (likelihood fit of a well exposed pixel).
inline double error_at_2600(const SeededUnit& u, const QeFitResult& f) {
  return extrapolation_errors(u.profile, u.truth, CameraModel{u.profile, f.system_qe, f.gains},
                              {2600})[0];
}

}  // namespace pyrocam::test
