// Calibration stage 7: what the model file and the report say about the calibration: its
// provenance, a verdict in plain words and the JSON summary (outcome_summary, in calibrate.h).
#pragma once

#include <string>

#include "pyrocam/calibration/calibration_outcome.h"
#include "pyrocam/core/dataset.h"

namespace pyrocam {

// Tool, version, time, profile, dataset (path and manifest fingerprint) and seed.
nlohmann::json model_provenance(const Dataset& dataset, const CameraProfile& profile,
                                std::uint64_t seed);

// Rate residuals, the MLP's Table 4 rms, skipped band points and warnings, in one line.
std::string calibration_verdict(const CalibrationOutcome& outcome);

// Root mean square of the finite entries (NaN when there are none).
double rms_finite(const Eigen::MatrixXd& m);

// A plain-language and JSON account of the outcome (the report's JSON summary).
nlohmann::json outcome_summary(const CalibrationOutcome& outcome);

}  // namespace pyrocam
