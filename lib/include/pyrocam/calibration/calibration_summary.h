// Calibration stage 7: what the model file and the report say about the calibration: its
// provenance, a verdict in plain words and the JSON summary (outcome_summary, in calibrate.h).
#pragma once

#include <string>
#include <vector>

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

// A model that does not explain its own furnace data still reads, and plausibly: what the
// outcome says about its data, in words (none for a sound calibration). The fitted QE leaving
// more than kResidualWarn of the furnace rates unexplained (rms; about 1 % on sound campaigns)
// or the network reading the furnace settings more than kSettingsWarnC off (rms; about 1 degC):
// temperatures in kelvin, exposures in other units, files listed at the wrong setting. Throws
// InputError when the network could read none of the furnace settings (every one with a band
// saturated or dim, or data the profile does not describe): such a model is not validated.
inline constexpr double kResidualWarn = 0.05, kSettingsWarnC = 10;
std::vector<std::string> calibration_quality_warnings(const CalibrationOutcome& outcome);

// How the model reads above the hottest temperature its calibration saw (extrapolation_pair.h),
// in one sentence: from which band ratio and from where; "" for a model that reads every band
// everywhere.
std::string above_calibration_summary(const ThermalModel& model);

// A plain-language and JSON account of the outcome (the report's JSON summary).
nlohmann::json outcome_summary(const CalibrationOutcome& outcome);

}  // namespace pyrocam
