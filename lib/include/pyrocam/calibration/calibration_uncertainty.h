// Calibration stage 6 (METHOD.md section 7): the model's systematic uncertainty as a function of
// temperature, from an emissivity slope the ratios do not cancel and from the thermocouple's
// tolerance (Monte-Carlo refits of the QE with perturbed furnace temperatures).
#pragma once

#include <limits>
#include <vector>

#include "pyrocam/calibration/calibration_outcome.h"
#include "pyrocam/calibration/qe_fit.h"
#include "pyrocam/runtime/emissivity.h"  // with_emissivity_slope

namespace pyrocam {

// The uncertainty table of a model whose camera, network and qe_solver are set: every 50 degC
// over the model's range. rates: temperatures x bands, DN/s, at the furnace temperatures t_c;
// references: the dataset's reference sources, in every refit as in the model's fit.
// Refits only for fitted QE (none for "datasheet"); without refits u_calibration is the
// thermocouple's own standard uncertainty. fit_choices: those of the model's fit
// (QeChoice::fit_choices), which the refits keep.
UncertaintyModel uncertainty_model(const ThermalModel& model, const std::vector<double>& t_c,
                                   const Eigen::MatrixXd& rates, const CalibrationOptions& options,
                                   const StageProgress& progress = {},
                                   const std::vector<ReferenceRates>& references = {},
                                   const QeFitChoices& fit_choices = {});

// Standard uncertainty at every temperature of what the QE leaves open: the spread (std) of the
// readings that `fitted`'s likelihood fit gives for a well exposed pixel of each plausible
// camera in `posterior` (QeFitResult::posterior), combined in quadrature with the largest change
// of that reading between `fitted` and the fits of `prior_fits` (prior_sensitivity_fits: the
// posterior is drawn around one choice of priors, and the data above the furnace range do not
// tell which is right); that change is taken as its envelope outward from the temperature
// where it is least, as a crossing of the curves is no knowledge, and so is the whole term
// (the samples' readings pivot too). That temperature is sought at or below
// hottest_calibrated_c (the furnace's hottest step) where it is given: above the furnace the
// term never shrinks going up. Small inside the furnace range, growing where the data do not
// constrain the QE. Empty without samples. The readings are those of a model calibrated up to
// calibrated_up_to_c (ThermalModel::calibrated_up_to_c: above it a colour model reads one
// ratio, handing back to every band below range_top_c, the model's top; NaN: beyond these
// temperatures); NaN: with every band everywhere.
std::vector<double> qe_model_uncertainty(
    const CameraModel& fitted, const std::vector<QeSample>& posterior,
    const std::vector<double>& temperatures_c, const std::vector<QeSample>& prior_fits = {},
    double hottest_calibrated_c = std::numeric_limits<double>::infinity(),
    double calibrated_up_to_c = std::numeric_limits<double>::quiet_NaN(),
    double range_top_c = std::numeric_limits<double>::quiet_NaN());

// |network reading - network reading of the graybody| for a body whose emissivity has the slope
// u.emissivity_slope_u or its opposite, the larger of the two, at every u.temperature_c: 0 for
// a slope of 0.
std::vector<double> emissivity_uncertainty(const ThermalModel& model, const UncertaintyModel& u);

// Standard uncertainty at every u.temperature_c of the temperature the model's rates imply,
// over u.monte_carlo_refits QE refits (solver model.qe_solver) with the furnace temperatures
// moved by a thermocouple deviation linear in temperature, uniform within
// +-u.thermocouple_tolerance_c at the coldest and at the hottest (drawn from `seed`), and each
// reference's
// temperature off by a normal draw of its temperature_uncertainty_c (a stream of its own, so
// that the furnace draws do not depend on the references). The regularised refits have the
// leak terms and prior widths `fit_choices` say.
std::vector<double> thermocouple_uncertainty(const ThermalModel& model, const UncertaintyModel& u,
                                             const std::vector<double>& t_c,
                                             const Eigen::MatrixXd& rates, std::uint64_t seed,
                                             const StageProgress& progress = {},
                                             const std::vector<ReferenceRates>& references = {},
                                             const QeFitChoices& fit_choices = {});

}  // namespace pyrocam
