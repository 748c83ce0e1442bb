// Calibration stage 5 (METHOD.md section 7, the paper's Table 4): every estimator, the model's and
// the baselines, scored on the calibration settings' ROI means against the furnace temperatures.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "pyrocam/calibration/calibration_outcome.h"

namespace pyrocam {

// Settings whose ROI means are inside the inference window in every band, as evaluated.
std::vector<std::size_t> evaluable_settings(const RateTable& rates, const CameraProfile& profile);

// One row of Table 4: `estimate` (net mean DN per band -> degC, NaN = no reading) on `settings`
// (indices into rt.settings).
EstimatorScore score_estimator(const std::string& name, const RateTable& rt,
                               const std::vector<std::size_t>& settings,
                               const std::function<double(const Eigen::VectorXd&)>& estimate);

// Table 4: the model's MLP and likelihood fit, Ohno on the model's locus and on the datasheet
// camera's (made at locus_step_c), and, for colour cameras, the two-colour method fitted to the
// datasheet QE. locus: the model's, as the network was trained on.
std::vector<EstimatorScore> evaluate_estimators(const ThermalModel& model, const RateTable& rates,
                                                const Locus& locus,
                                                const CameraModel& datasheet_camera,
                                                double locus_step_c);

}  // namespace pyrocam
