// Calibration stage 2 (METHOD.md section 4): the system QE the model is built on, chosen among
// the requested solvers by their held-out (cross-validation) residual, with the datasheet's as
// the fallback; and the rate residuals that show how well a QE explains the furnace rates.
#pragma once

#include <string>
#include <vector>

#include "pyrocam/calibration/calibration_outcome.h"
#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam {

struct QeChoice {
  std::string solver = "datasheet";     // the chosen solver, or "datasheet" if none beat it
  Eigen::MatrixXd system_qe;            // bands x wavelengths
  Eigen::VectorXd band_scale;           // k_b
  std::vector<QeSolverReport> reports;  // every solver tried, in the order tried
  Eigen::MatrixXd qe_spread;            // the chosen fit's cross-validation std (may be empty)
  std::vector<QeSample> posterior;      // plausible QE solutions (regularised fit only)
  std::vector<QeSample> prior_fits;     // prior_sensitivity_fits (regularised fit only)
  // The chosen fit's leak terms and prior widths (held_fit_choices; the defaults for the paper's
  // fit or the datasheet): the Monte-Carlo refits of the uncertainty model fit the same model.
  QeFitChoices fit_choices;
  // Per reference row: its reading minus its temperature, datasheet QE and chosen QE.
  std::vector<double> reference_error_before_c, reference_error_after_c;
};

// `auto` ranks the paper and regularised solvers by their held-out residual, but the paper's must
// be lower by more than kPaperSolverMargin to be chosen: the residual is measured inside the
// furnace range, and outside it the paper's unregularised fit can be far off where the
// regularised one is not (simulated hostile 5x5 units: -500 to -780 degC at 2400-2600 degC
// against -9 to +28), while in range the two often tie to a few percent (the held-out rms of a
// few hundred rates is itself uncertain by about 5 %). The paper's fit also has no posterior,
// so its model would carry no QE-model uncertainty.
inline constexpr double kPaperSolverMargin = 0.1;
// The held-out residual `auto` ranks `solver` by.
double ranked_held_out_residual(const std::string& solver, double held_out_residual);

// qe_solver: "paper", "regularised", "datasheet" or "auto" (paper and regularised). rates:
// temperatures x bands, DN/s (NaN missing), at the temperatures t_c. references: the dataset's
// reference sources (RateTable::reference_rates()), handed to every fit with the furnace rates.
QeChoice choose_system_qe(const CameraProfile& profile, const Eigen::MatrixXd& datasheet_qe,
                          const std::vector<double>& t_c, const Eigen::MatrixXd& rates,
                          const std::string& qe_solver, const StageProgress& progress = {},
                          const std::vector<ReferenceRates>& references = {},
                          const QeFitChoices& fit_choices = {});

// k_b = measured / modelled rate at the hottest temperature the band has a slope for.
Eigen::VectorXd band_scale(const CameraProfile& p, const Eigen::MatrixXd& q,
                           const std::vector<double>& t_c, const Eigen::MatrixXd& rates);

// Relative error of modelled vs measured rates after the scale k_b (T x bands, NaN missing).
Eigen::MatrixXd rate_residuals(const CameraModel& cam, const std::vector<double>& t_c,
                               const Eigen::MatrixXd& rates);

}  // namespace pyrocam
