// How well a QE fit extrapolates, studied at the level of signal rates (no images): the rates a
// furnace campaign (and optional reference sources) would give for a known "true" QE, and the
// reading error of a fitted camera model at temperatures the furnace never reached. Fast enough
// to run over many simulated units; the end-to-end figures come from images (targets suite).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <vector>

#include "pyrocam/calibration/qe_fit.h"
#include "pyrocam/core/locus.h"

namespace pyrocam {

struct RateCampaign {
  std::vector<double> temperatures_c;            // empty: 700..1100 step 10 (colour), 800..1100
  std::vector<double> reference_temperatures_c;  // e.g. {1324, 1738, 2474}
  double reference_uncertainty_c = 0.5;          // k=1; the true value is drawn around the nominal
  // rms relative error of one extracted rate: a slope over many exposures of an ROI mean of
  // thousands of pixels. Conservative: image campaigns of 3 frames a setting reach about 2e-4
  // (5x5) and 1.3e-4 (colour) per band since the sweeps share one offset per band (3-7e-4 and
  // 2-3e-4 with one offset per temperature).
  double relative_noise = 3e-4;
  double furnace_error_sigma_c = 1.0;  // true plate temperature off the nominal
  double first_exposure_us = 0;        // 0: 100 us colour, 10000 us multispectral
  double exposure_factor = 1.26;
  int exposure_count = 30;
  std::uint64_t seed = 11;
};

// Rates (DN/s) as extract_rates would give them: NaN where a band has fewer than two exposures
// of the sweep between the dim and saturation thresholds; references at an unknown scale.
CalibrationRates simulate_calibration_rates(const CameraProfile& profile,
                                            const Eigen::MatrixXd& true_system_qe,
                                            const RateCampaign& campaign);

// Reading error (degC) of `fitted` at each temperature for a graybody seen by the true QE:
// the nearest point of the fitted model's locus (a baseline inverse, not the network), so the
// figure is the QE model's error alone. calibrated_up_to_c: as ThermalModel's (the hottest
// furnace or reference temperature the fit saw: above it a colour model reads one ratio); NaN
// reads with every band everywhere.
std::vector<double> extrapolation_errors(const CameraProfile& profile,
                                         const Eigen::MatrixXd& true_system_qe,
                                         const CameraModel& fitted,
                                         const std::vector<double>& temperatures_c,
                                         double calibrated_up_to_c = NAN);

// The hottest temperature of a campaign's rates: furnace steps and reference sources.
double hottest_calibrated_c(const CalibrationRates& data);

}  // namespace pyrocam
