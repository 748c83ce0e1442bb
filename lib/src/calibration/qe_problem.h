// What the QE solvers share (qe_fit.cpp, qe_regularised.cpp): the prepared problem, residuals
// and the diagnostics every fit ends with.
#pragma once

#include <Eigen/Core>
#include <chrono>
#include <vector>

#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam::qe_detail {

using Clock = std::chrono::steady_clock;

bool usable(double rate);

// Photon radiance per temperature and, per band, its usable rates and the hottest usable
// temperature (the normalisation point).
struct Problem {
  Eigen::MatrixXd radiance;  // temperatures x wavelengths: etendue * weighted photon radiance
  std::vector<std::vector<Eigen::Index>> valid;  // per band, usable temperature indices
  std::vector<Eigen::Index> reference;           // per band, hottest usable temperature index
};

Eigen::MatrixXd radiance_rows(const CameraProfile& profile, const std::vector<double>& temps_c);

// Checks shapes, temperatures and the references (InputError naming what is wrong).
Problem prepare(const CameraProfile& profile, const CalibrationRates& data);

// Per band rms of the normalised-rate residual.
Eigen::VectorXd residuals_for(const Problem& p, const Eigen::MatrixXd& qe,
                              const CalibrationRates& data);

// Least-squares gains of a QE against the furnace rates (relative residuals).
Eigen::VectorXd least_squares_gains(const CameraProfile& profile, const Problem& p,
                                    const Eigen::MatrixXd& qe, const CalibrationRates& data);

// `o` with every prior on the QE's shape `factor` times as wide (RegularisedOptions::
// prior_scales, prior_sensitivity_fits); the furnace temperatures' prior is kept.
RegularisedOptions with_prior_widths(RegularisedOptions o, double factor);

// Fills the diagnostics (residuals, QE change, reference readings, time).
void finish(const CameraProfile& profile, const Problem& p, const CalibrationRates& data,
            Clock::time_point start, QeFitResult& r);

}  // namespace pyrocam::qe_detail
