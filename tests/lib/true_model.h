// A model whose camera is a simulated unit's true system QE (unit band scales): tests that
// measure a reading (demosaicking, edges, fusion) rather than the calibration read with it.
#pragma once

#include <Eigen/Core>
#include <memory>

#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::test {

inline std::shared_ptr<ThermalModel> true_model(const CameraProfile& profile,
                                                const UnitPerturbation& unit) {
  auto model = std::make_shared<ThermalModel>();
  model->camera = CameraModel{profile, true_system_qe(profile, unit),
                              Eigen::VectorXd::Ones(profile.band_count())};
  return model;
}

}  // namespace pyrocam::test
