// The whole calibration (METHOD.md sections 3-7): dataset -> rates -> optimised QE -> locus ->
// MLP -> evaluation (the paper's Table 4) -> uncertainty model -> ThermalModel. The options and
// the outcome are in calibration_outcome.h; the stages after rate extraction each have a header
// of their own (calibration_qe.h, calibration_evaluation.h, calibration_uncertainty.h,
// calibration_summary.h).
#pragma once

#include "pyrocam/calibration/calibration_evaluation.h"
#include "pyrocam/calibration/calibration_outcome.h"
#include "pyrocam/calibration/calibration_summary.h"

namespace pyrocam {

// Throws InputError for bad data (see extract_rates) and for profiles that do not fit.
CalibrationOutcome calibrate(const Dataset& dataset, const CameraProfile& profile,
                             const CalibrationOptions& options, const StageProgress& progress = {});

}  // namespace pyrocam
