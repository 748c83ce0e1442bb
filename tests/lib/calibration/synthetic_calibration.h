// Noise-free inputs for the calibration stage tests: furnace rates of a known camera and a small
// model built on it, without a dataset on disk.
#pragma once

#include <cstdint>
#include <vector>

#include "pyrocam/calibration/calibration_outcome.h"
#include "pyrocam/calibration/extrapolation_study.h"
#include "pyrocam/calibration/mlp_training.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::test {

// temperatures x bands, DN/s: the camera's modelled rates.
inline Eigen::MatrixXd furnace_rates(const CameraModel& camera, const std::vector<double>& t_c) {
  Eigen::MatrixXd rates(static_cast<Eigen::Index>(t_c.size()), camera.profile.band_count());
  for (std::size_t i = 0; i < t_c.size(); ++i)
    rates.row(static_cast<Eigen::Index>(i)) = camera.rates(t_c[i]).transpose();
  return rates;
}

// A model of the datasheet camera over [min_c, max_c] with a small network (a few seconds'
// training): good to a few degC, enough to exercise the stages, not to judge accuracy.
inline ThermalModel small_model(const CameraProfile& profile, double min_c, double max_c) {
  ThermalModel m;
  m.datasheet_qe = profile.system_qe();
  m.qe_solver = "regularised";
  m.min_temperature_c = min_c;
  m.max_temperature_c = max_c;
  m.camera = CameraModel{profile, m.datasheet_qe, Eigen::VectorXd::Ones(profile.band_count())};
  const Locus locus = make_locus(m.camera, min_c, max_c, 5);
  MlpTrainingOptions options;
  options.hidden = {16, 12};
  options.epochs = 20;
  options.polish_iterations = 200;
  m.mlp = train_mlp(locus.ratios, locus.temperature_c, options);
  return m;
}

// A hostile unit's true QE and the furnace rates bench_extrapolation simulates for it (rate
// level, its campaign seed 100 + unit).
struct HostileCampaign {
  Eigen::MatrixXd truth;
  CalibrationRates data;
};

inline HostileCampaign hostile_campaign(const CameraProfile& profile, std::uint64_t unit) {
  HostileCampaign c;
  c.truth = true_system_qe(profile, UnitPerturbation::parse("hostile", unit));
  RateCampaign campaign;
  campaign.seed = 100 + unit;
  c.data = simulate_calibration_rates(profile, c.truth, campaign);
  return c;
}

}  // namespace pyrocam::test
