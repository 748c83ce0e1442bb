#include "pyrocam/calibration/calibration_qe.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "calibration/stage_support.h"
#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam {

using calibration_detail::Clock;
using calibration_detail::report_stage;
using calibration_detail::since;

// Enough for a standard deviation good to about 10 % (chi distribution, 1 / sqrt(2 (n - 1))).
constexpr int kPosteriorSamples = 48;

Eigen::VectorXd band_scale(const CameraProfile& p, const Eigen::MatrixXd& q,
                           const std::vector<double>& t_c, const Eigen::MatrixXd& rates) {
  Eigen::VectorXd k(p.band_count());
  for (int b = 0; b < p.band_count(); ++b) {
    k[b] = NAN;
    for (Eigen::Index i = rates.rows() - 1; i >= 0; --i)
      if (std::isfinite(rates(i, b))) {
        k[b] = rates(i, b) /
               signal_rates(p, q, celsius_to_kelvin(t_c[static_cast<std::size_t>(i)]))[b];
        break;
      }
  }
  return k;
}

Eigen::MatrixXd rate_residuals(const CameraModel& cam, const std::vector<double>& t_c,
                               const Eigen::MatrixXd& rates) {
  Eigen::MatrixXd r(rates.rows(), rates.cols());
  for (Eigen::Index i = 0; i < rates.rows(); ++i) {
    const Eigen::VectorXd m = cam.rates(t_c[static_cast<std::size_t>(i)]);
    for (Eigen::Index b = 0; b < rates.cols(); ++b) r(i, b) = m[b] / rates(i, b) - 1;
  }
  return r;
}

double ranked_held_out_residual(const std::string& solver, double held_out_residual) {
  return solver == "paper" ? held_out_residual / (1 - kPaperSolverMargin) : held_out_residual;
}

QeChoice choose_system_qe(const CameraProfile& profile, const Eigen::MatrixXd& datasheet,
                          const std::vector<double>& t_c, const Eigen::MatrixXd& rates,
                          const std::string& qe_solver, const StageProgress& progress,
                          const std::vector<ReferenceRates>& references,
                          const QeFitChoices& fit_choices) {
  // QE optimisation: every requested solver, chosen by held-out (cross-validation) residual
  // (ranked_held_out_residual).
  std::vector<std::string> solvers;
  if (qe_solver == "auto")
    solvers = {"paper", "regularised"};
  else
    solvers = {qe_solver};
  const CalibrationRates data{t_c, rates.transpose(), references};
  QeChoice best;
  best.system_qe = datasheet;
  best.band_scale = band_scale(profile, datasheet, t_c, rates);
  double best_held_out = INFINITY;
  for (std::size_t s = 0; s < solvers.size(); ++s) {
    report_stage(progress, "optimising QE (" + solvers[s] + ")", s, solvers.size());
    const auto t0 = Clock::now();
    QeSolverReport rep;
    rep.solver = solvers[s];
    if (solvers[s] == "datasheet") {
      rep.calibration_residual =
          std::sqrt(normalised_rate_residuals(profile, datasheet, data).array().square().mean());
      rep.held_out_residual = rep.calibration_residual;
      rep.qe_change_rms = 0;
      rep.seconds = since(t0);
      best.reports.push_back(rep);
      continue;
    }
    QeFitOptions qo;
    qo.solver = solvers[s] == "paper" ? QeSolver::kPaper : QeSolver::kRegularised;
    qo.regularised.posterior_samples = kPosteriorSamples;
    qo = with_fit_choices(qo, fit_choices);
    const QeFitResult fit = fit_qe(profile, data, qo);
    const auto rms_of = [](const Eigen::VectorXd& v) {
      return std::sqrt(v.array().square().mean());
    };
    rep.calibration_residual = rms_of(fit.diagnostics.residual_after);
    rep.leak_terms = leak_terms_summary(fit);
    rep.prior_widths = prior_widths_summary(fit);
    // The folds and the prior-sensitivity fits vary the model this fit chose.
    qo = holding_fit_choices(qo, fit);
    rep.qe_change_rms = rms_of(fit.diagnostics.qe_change_rms);
    report_stage(progress, "cross-validating QE (" + solvers[s] + ")", s, solvers.size());
    QeFitOptions folds = qo;
    folds.regularised.posterior_samples = 0;  // the folds' spread is all that is used
    // Five folds, or one a temperature where a campaign has fewer (calibrate lets no fitted QE
    // through with fewer than three).
    const int groups = static_cast<int>(std::min<std::size_t>(5, data.temperatures_c.size()));
    CrossValidation cv = cross_validate(profile, data, folds, groups);
    rep.held_out_residual = rms_of(cv.heldout_residual);
    rep.seconds = since(t0);
    best.reports.push_back(rep);
    const double ranked = ranked_held_out_residual(solvers[s], rep.held_out_residual);
    if (ranked < best_held_out) {
      best_held_out = ranked;
      best.system_qe = fit.system_qe;
      best.band_scale = fit.gains;
      best.solver = solvers[s];
      best.qe_spread = cv.qe_spread;
      best.posterior = fit.posterior;
      if (qo.solver == QeSolver::kRegularised)
        report_stage(progress, "prior sensitivity (" + solvers[s] + ")", s, solvers.size());
      const PriorSensitivity sensitivity = prior_sensitivity(profile, data, qo, fit);
      best.prior_fits = sensitivity.counted_fits();  // none for the paper's
      best.reports.back().prior_sensitivity = prior_sensitivity_summary(sensitivity);
      best.fit_choices = held_fit_choices(fit);
      best.reference_error_before_c = fit.diagnostics.reference_error_before_c;
      best.reference_error_after_c = fit.diagnostics.reference_error_after_c;
    }
  }
  report_stage(progress, "optimising QE", solvers.size(), solvers.size());
  return best;
}

}  // namespace pyrocam
