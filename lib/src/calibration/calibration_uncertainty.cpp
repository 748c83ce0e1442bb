#include "pyrocam/calibration/calibration_uncertainty.h"

#include <algorithm>
#include <cmath>

#include "calibration/stage_support.h"
#include "detail/random.h"
#include "pyrocam/calibration/baselines.h"
#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam {

using calibration_detail::report_stage;

std::vector<double> emissivity_uncertainty(const ThermalModel& m, const UncertaintyModel& u) {
  const CameraProfile& profile = m.profile();
  const CameraModel tilted{profile,
                           with_emissivity_slope(profile, m.camera.system_qe, u.emissivity_slope_u),
                           m.camera.band_scale};
  std::vector<double> u_emissivity_c;
  for (double t : u.temperature_c) {
    const Eigen::VectorXd x = normalised_ratios(profile.normalisation, tilted.rates(t));
    const double shifted = m.mlp.predict(x.data());
    u_emissivity_c.push_back(std::abs(shifted - t));
  }
  return u_emissivity_c;
}

std::vector<double> thermocouple_uncertainty(const ThermalModel& m, const UncertaintyModel& u,
                                             const std::vector<double>& t_c,
                                             const Eigen::MatrixXd& rates, std::uint64_t seed,
                                             const StageProgress& progress) {
  std::vector<std::vector<double>> refit_t(u.temperature_c.size());
  Random rng(seed ^ 0x7C0FFEEull);
  const auto tc_error = [&](Random& r) {
    return r.uniform(-u.thermocouple_tolerance_c, u.thermocouple_tolerance_c);
  };
  for (int k = 0; k < u.monte_carlo_refits; ++k) {
    report_stage(progress, "Monte-Carlo refits", static_cast<std::size_t>(k),
                 static_cast<std::size_t>(u.monte_carlo_refits));
    std::vector<double> t_perturbed = t_c;
    for (double& t : t_perturbed) t += tc_error(rng);
    QeFitOptions qo;
    qo.solver = m.qe_solver == "paper" ? QeSolver::kPaper : QeSolver::kRegularised;
    const QeFitResult fit =
        fit_qe(m.profile(), CalibrationRates{t_perturbed, rates.transpose(), {}}, qo);
    const CameraModel cam{m.profile(), fit.system_qe, fit.gains};
    const OhnoEstimator inv(
        make_locus(cam, m.min_temperature_c - 100, m.max_temperature_c + 100, 1));
    for (std::size_t i = 0; i < u.temperature_c.size(); ++i)
      refit_t[i].push_back(inv.temperature_c(m.camera.rates(u.temperature_c[i])));
  }
  report_stage(progress, "Monte-Carlo refits", static_cast<std::size_t>(u.monte_carlo_refits),
               static_cast<std::size_t>(u.monte_carlo_refits));
  std::vector<double> u_calibration_c;
  for (std::size_t i = 0; i < u.temperature_c.size(); ++i) {
    double mean = 0, var = 0;
    const auto& v = refit_t[i];
    for (double x : v) mean += x;
    if (!v.empty()) mean /= static_cast<double>(v.size());
    for (double x : v) var += (x - mean) * (x - mean);
    // With no refits the thermocouple's own standard uncertainty is the floor.
    const double floor_u = u.thermocouple_tolerance_c / std::sqrt(3.0);
    u_calibration_c.push_back(v.size() > 1 ? std::max(std::sqrt(var / (v.size() - 1)), 0.0)
                                           : floor_u);
  }
  return u_calibration_c;
}

UncertaintyModel uncertainty_model(const ThermalModel& m, const std::vector<double>& t_c,
                                   const Eigen::MatrixXd& rates, const CalibrationOptions& opt,
                                   const StageProgress& progress) {
  // Uncertainty model: emissivity slope and thermocouple tolerance as functions of T.
  UncertaintyModel u;
  u.thermocouple_tolerance_c = opt.thermocouple_tolerance_c;
  u.monte_carlo_refits = m.qe_solver == "datasheet" ? 0 : opt.monte_carlo_refits;
  for (double t = opt.min_temperature_c; t <= opt.max_temperature_c + 1e-9; t += 50)
    u.temperature_c.push_back(t);
  u.u_emissivity_c = emissivity_uncertainty(m, u);
  u.u_calibration_c = thermocouple_uncertainty(m, u, t_c, rates, opt.seed, progress);
  return u;
}

}  // namespace pyrocam
