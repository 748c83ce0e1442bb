// Bridges calibrate.cpp to the QE solvers (private to the library).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pyrocam/profile.h"

namespace pyrocam {

struct QeFitInput {
  const CameraProfile& profile;
  std::vector<double> temperatures_c;
  Eigen::MatrixXd rates;  // temperatures x bands, DN/s, NaN = no slope
};

struct QeFitResult {
  Eigen::MatrixXd system_qe;
  double calibration_residual = NAN;
};

QeFitResult fit_system_qe(const QeFitInput& input, const std::string& solver);
double held_out_residual(const QeFitInput& input, const std::string& solver);
Eigen::MatrixXd cross_validation_spread(const QeFitInput& input, const std::string& solver);

}  // namespace pyrocam
