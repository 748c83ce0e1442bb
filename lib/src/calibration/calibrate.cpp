#include "pyrocam/calibration/calibrate.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <random>
#include <sstream>

#include "pyrocam/calibration/baselines.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/calibration/noisy_locus.h"
#include "pyrocam/calibration/qe_fit.h"
#include "pyrocam/core/error.h"
#include "detail/random.h"

namespace pyrocam {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// k_b = measured / modelled rate at the hottest temperature the band has a slope for.
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

// Relative error of modelled vs measured rates after the scale k_b (T x bands, NaN missing).
Eigen::MatrixXd rate_residuals(const CameraModel& cam, const std::vector<double>& t_c,
                               const Eigen::MatrixXd& rates) {
  Eigen::MatrixXd r(rates.rows(), rates.cols());
  for (Eigen::Index i = 0; i < rates.rows(); ++i) {
    const Eigen::VectorXd m = cam.rates(t_c[static_cast<std::size_t>(i)]);
    for (Eigen::Index b = 0; b < rates.cols(); ++b) r(i, b) = m[b] / rates(i, b) - 1;
  }
  return r;
}

double rms_finite(const Eigen::MatrixXd& m) {
  double s = 0;
  int n = 0;
  for (Eigen::Index i = 0; i < m.size(); ++i)
    if (std::isfinite(m.data()[i])) s += m.data()[i] * m.data()[i], ++n;
  return n ? std::sqrt(s / n) : NAN;
}

EstimatorScore score(const std::string& name, const RateTable& rt,
                     const std::vector<std::size_t>& settings,
                     const std::function<double(const Eigen::VectorXd&)>& estimate) {
  EstimatorScore s;
  s.name = name;
  std::vector<std::pair<double, double>> by_t;
  for (std::size_t i : settings) {
    const double t = estimate(rt.settings[i].net_mean_dn);
    if (!std::isfinite(t)) {
      ++s.missing;
      continue;
    }
    s.true_c.push_back(rt.settings[i].temperature_c);
    s.estimate_c.push_back(t);
  }
  const auto n = static_cast<double>(s.true_c.size());
  if (n == 0) return s;
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < s.true_c.size(); ++i) {
    const double e = s.estimate_c[i] - s.true_c[i];
    sum += e;
    sum2 += e * e;
  }
  s.mean = sum / n;
  s.rms = std::sqrt(sum2 / n);
  s.std = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  // Spread across exposures at each temperature, averaged over temperatures.
  double spread_sum = 0;
  int spread_n = 0;
  for (double t : rt.temperatures_c) {
    std::vector<double> e;
    for (std::size_t i = 0; i < s.true_c.size(); ++i)
      if (s.true_c[i] == t) e.push_back(s.estimate_c[i]);
    if (e.size() < 2) continue;
    double m = 0, v = 0;
    for (double x : e) m += x;
    m /= static_cast<double>(e.size());
    for (double x : e) v += (x - m) * (x - m);
    spread_sum += std::sqrt(v / static_cast<double>(e.size() - 1));
    ++spread_n;
  }
  if (spread_n) s.exposure_spread = spread_sum / spread_n;
  return s;
}

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// Spectral emissivity eps(lambda) = 1 + alpha (lambda - centre) / 100 nm folded into Q.
Eigen::MatrixXd with_emissivity_slope(const CameraProfile& p, const Eigen::MatrixXd& q,
                                      double alpha) {
  const double centre = 0.5 * (p.filter_pass_band_nm[0] + p.filter_pass_band_nm[1]);
  Eigen::MatrixXd out = q;
  for (Eigen::Index i = 0; i < p.grid.size(); ++i)
    out.col(i) *= std::max(0.0, 1 + alpha * (p.grid.nm()[i] - centre) / 100.0);
  return out;
}

// Manifest text and ROI size: enough to tell datasets apart in a model's provenance.
std::string dataset_fingerprint(const Dataset& d) {
  std::ifstream in(d.folder() / "manifest.csv");
  std::string text(std::istreambuf_iterator<char>(in), {});
  return fnv1a_hex(text + std::to_string(d.width()) + "x" + std::to_string(d.height()));
}

}  // namespace

std::vector<std::size_t> evaluable_settings(const RateTable& rt, const CameraProfile& p) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < rt.settings.size(); ++i) {
    const SettingMeans& s = rt.settings[i];
    bool ok = true;
    for (int b = 0; b < p.band_count(); ++b)
      ok &= s.raw_mean_dn[b] <= p.thresholds.inference_saturation_dn &&
            s.net_mean_dn[b] >= p.thresholds.inference_dim_dn && s.saturated_fraction[b] < 1e-3;
    if (ok) out.push_back(i);
  }
  return out;
}

CalibrationOutcome calibrate(const Dataset& dataset, const CameraProfile& profile,
                             const CalibrationOptions& opt, const StageProgress& progress) {
  const auto t_start = Clock::now();
  auto stage = [&](const std::string& name, std::size_t done, std::size_t total) {
    if (progress) progress(name, done, total);
  };
  // The model must cover what it is calibrated on: the locus, the network and Table 4 too.
  if (!dataset.mosaic_pattern().empty()) {
    std::string profile_pattern = profile.mosaic.pattern;
    std::transform(profile_pattern.begin(), profile_pattern.end(), profile_pattern.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (profile_pattern != dataset.mosaic_pattern())
      throw InputError((dataset.folder() / kMosaicFile).string() + ": the images are " +
                       dataset.mosaic_pattern() + ", the profile " + profile.name +
                       " describes a " + profile_pattern + " mosaic");
  }
  const std::vector<double> nominal_c = dataset.temperatures_c();
  if (nominal_c.empty()) throw InputError(dataset.folder().string() + ": no frames to calibrate");
  if (nominal_c.size() < 2) {
    std::ostringstream m;
    m << dataset.folder().string() << ": every frame in manifest.csv is at one temperature ("
      << nominal_c.front() << " degC); calibration needs frames at 2 or more temperatures";
    throw InputError(m.str());
  }
  if (!(opt.min_temperature_c >= kModelMinTemperatureC &&
        opt.max_temperature_c <= kModelMaxTemperatureC)) {
    std::ostringstream m;
    m << "the model's range " << opt.min_temperature_c << "-" << opt.max_temperature_c
      << " degC leaves the range a model file may hold, " << kModelMinTemperatureC << "-"
      << kModelMaxTemperatureC << " degC";
    throw InputError(m.str());
  }
  const auto [coolest, hottest] = std::minmax_element(nominal_c.begin(), nominal_c.end());
  if (!(opt.min_temperature_c < opt.max_temperature_c) || *coolest < opt.min_temperature_c ||
      *hottest > opt.max_temperature_c) {
    std::ostringstream m;
    m << dataset.folder().string() << ": calibration temperatures " << *coolest << "-" << *hottest
      << " degC are outside the model's range " << opt.min_temperature_c << "-"
      << opt.max_temperature_c << " degC (--min-temperature, --max-temperature)";
    throw InputError(m.str());
  }
  CalibrationOutcome out;
  ExtractOptions eo;
  eo.threads = opt.threads;
  out.rates = extract_rates(dataset, profile, eo,
                            [&](std::size_t d, std::size_t t) { stage("reading frames", d, t); });
  out.warnings = out.rates.warnings;
  const std::vector<double>& t_c = out.rates.temperatures_c;
  const Eigen::MatrixXd rates = out.rates.rates();
  const Eigen::MatrixXd datasheet = profile.system_qe();

  // QE optimisation: every requested solver, chosen by held-out (cross-validation) residual.
  std::vector<std::string> solvers;
  if (opt.qe_solver == "auto")
    solvers = {"paper", "regularised"};
  else
    solvers = {opt.qe_solver};
  const CalibrationRates data{t_c, rates.transpose()};
  Eigen::MatrixXd best_q = datasheet;
  Eigen::VectorXd best_k = band_scale(profile, datasheet, t_c, rates);
  double best_held_out = INFINITY;
  std::string best_solver = "datasheet";
  for (std::size_t s = 0; s < solvers.size(); ++s) {
    stage("optimising QE (" + solvers[s] + ")", s, solvers.size());
    const auto t0 = Clock::now();
    QeSolverReport rep;
    rep.solver = solvers[s];
    if (solvers[s] == "datasheet") {
      rep.calibration_residual =
          std::sqrt(normalised_rate_residuals(profile, datasheet, data).array().square().mean());
      rep.held_out_residual = rep.calibration_residual;
      rep.qe_change_rms = 0;
      rep.seconds = since(t0);
      out.solvers.push_back(rep);
      continue;
    }
    QeFitOptions qo;
    qo.solver = solvers[s] == "paper" ? QeSolver::kPaper : QeSolver::kRegularised;
    const QeFitResult fit = fit_qe(profile, data, qo);
    const auto rms_of = [](const Eigen::VectorXd& v) {
      return std::sqrt(v.array().square().mean());
    };
    rep.calibration_residual = rms_of(fit.diagnostics.residual_after);
    rep.qe_change_rms = rms_of(fit.diagnostics.qe_change_rms);
    stage("cross-validating QE (" + solvers[s] + ")", s, solvers.size());
    CrossValidation cv = cross_validate(profile, data, qo, 5);
    rep.held_out_residual = rms_of(cv.heldout_residual);
    rep.seconds = since(t0);
    out.solvers.push_back(rep);
    if (rep.held_out_residual < best_held_out) {
      best_held_out = rep.held_out_residual;
      best_q = fit.system_qe;
      best_k = fit.gains;
      best_solver = solvers[s];
      out.qe_spread = cv.qe_spread;
    }
  }
  stage("optimising QE", solvers.size(), solvers.size());

  ThermalModel& m = out.model;
  m.datasheet_qe = datasheet;
  m.qe_solver = best_solver;
  m.min_temperature_c = opt.min_temperature_c;
  m.max_temperature_c = opt.max_temperature_c;
  m.camera = CameraModel{profile, best_q, best_k};
  const CameraModel sheet_camera{profile, datasheet, band_scale(profile, datasheet, t_c, rates)};
  out.rate_residual_datasheet = rate_residuals(sheet_camera, t_c, rates);
  out.rate_residual_optimised = rate_residuals(m.camera, t_c, rates);

  // The synthetic locus and the network on it.
  const Locus locus =
      make_locus(m.camera, opt.min_temperature_c, opt.max_temperature_c, opt.locus_step_c);
  MlpTrainingOptions mo = opt.mlp;
  mo.seed = opt.seed;
  NoisyLocusOptions no = opt.noisy_locus;
  std::unique_ptr<NoisyLocus> noisy;
  if (no.copies > 0) {
    noisy = std::make_unique<NoisyLocus>(m, locus, no);
    mo.augment = [&noisy](const std::vector<Eigen::Index>& rows, std::uint64_t seed) {
      return noisy->sample(rows, seed);
    };
  }
  auto user_progress = opt.mlp.progress;
  // One pass per Adam epoch or polish iteration; the polish may stop early.
  const auto passes = static_cast<std::size_t>(mo.epochs + mo.polish_iterations);
  mo.progress = [&](int pass, double train, double test) {
    stage("training MLP", std::min(static_cast<std::size_t>(pass), passes), passes);
    if (user_progress) user_progress(pass, train, test);
  };
  m.mlp = Mlp::train(locus.ratios, locus.temperature_c, mo, &out.mlp_report);
  stage("training MLP", passes, passes);
  const Eigen::VectorXd locus_error = m.mlp.predict(locus.ratios) - locus.temperature_c;
  out.mlp_locus_max_error_c = locus_error.cwiseAbs().maxCoeff();
  out.mlp_locus_rms_error_c = std::sqrt(locus_error.squaredNorm() / locus_error.size());

  // Table 4: every estimator on the calibration settings' ROI means.
  stage("evaluating", 0, 1);
  const auto settings = evaluable_settings(out.rates, profile);
  const auto evaluated = std::make_shared<const ThermalModel>(m);  // a copy the estimators share
  const auto mlp_est = make_estimator(evaluated, Method::kMlp);
  const auto ml_est = make_estimator(evaluated, Method::kLikelihood);
  auto call = [](const TemperatureEstimator& e) {
    return [&e](const Eigen::VectorXd& s) { return e.temperature_c(s.data()); };
  };
  out.table4.push_back(score("MLP", out.rates, settings, call(*mlp_est)));
  out.table4.push_back(score("likelihood fit", out.rates, settings, call(*ml_est)));
  const OhnoEstimator ohno(locus);
  out.table4.push_back(score("Ohno, optimised QE", out.rates, settings,
                             [&](const Eigen::VectorXd& s) { return ohno.temperature_c(s); }));
  const OhnoEstimator ohno_sheet(
      make_locus(sheet_camera, opt.min_temperature_c, opt.max_temperature_c, opt.locus_step_c));
  out.table4.push_back(
      score("Ohno, datasheet QE", out.rates, settings,
            [&](const Eigen::VectorXd& s) { return ohno_sheet.temperature_c(s); }));
  const int r = profile.band_index("R"), g = profile.band_index("G"), b = profile.band_index("B");
  if (r >= 0 && g >= 0 && b >= 0 && !settings.empty()) {
    std::vector<Eigen::VectorXd> sig, sim;
    std::vector<double> tt;
    for (std::size_t i : settings) {
      const SettingMeans& st = out.rates.settings[i];
      sig.push_back(st.net_mean_dn);
      sim.push_back(signal_rates(profile, datasheet, celsius_to_kelvin(st.temperature_c)) *
                    st.exposure_us * 1e-6);
      tt.push_back(st.temperature_c);
    }
    const TwoColourEstimator two = TwoColourEstimator::fit(sig, sim, tt, r, g, b);
    out.table4.push_back(score("two-colour", out.rates, settings,
                               [&](const Eigen::VectorXd& s) { return two.temperature_c(s); }));
  }
  stage("evaluating", 1, 1);

  // Uncertainty model: emissivity slope and thermocouple tolerance as functions of T.
  UncertaintyModel& u = m.uncertainty;
  u.thermocouple_tolerance_c = opt.thermocouple_tolerance_c;
  u.monte_carlo_refits = best_solver == "datasheet" ? 0 : opt.monte_carlo_refits;
  for (double t = opt.min_temperature_c; t <= opt.max_temperature_c + 1e-9; t += 50)
    u.temperature_c.push_back(t);
  const CameraModel tilted{profile, with_emissivity_slope(profile, best_q, u.emissivity_slope_u),
                           m.camera.band_scale};
  for (double t : u.temperature_c) {
    const Eigen::VectorXd x = normalised_ratios(profile.normalisation, tilted.rates(t));
    const double shifted = m.mlp.predict(x.data());
    u.u_emissivity_c.push_back(std::abs(shifted - t));
  }
  std::vector<std::vector<double>> refit_t(u.temperature_c.size());
  Random rng(opt.seed ^ 0x7C0FFEEull);
  const auto tc_error = [&](Random& r) {
    return r.uniform(-opt.thermocouple_tolerance_c, opt.thermocouple_tolerance_c);
  };
  for (int k = 0; k < u.monte_carlo_refits; ++k) {
    stage("Monte-Carlo refits", static_cast<std::size_t>(k),
          static_cast<std::size_t>(u.monte_carlo_refits));
    std::vector<double> t_perturbed = t_c;
    for (double& t : t_perturbed) t += tc_error(rng);
    QeFitOptions qo;
    qo.solver = best_solver == "paper" ? QeSolver::kPaper : QeSolver::kRegularised;
    const QeFitResult fit = fit_qe(profile, CalibrationRates{t_perturbed, rates.transpose()}, qo);
    const CameraModel cam{profile, fit.system_qe, fit.gains};
    const OhnoEstimator inv(
        make_locus(cam, opt.min_temperature_c - 100, opt.max_temperature_c + 100, 1));
    for (std::size_t i = 0; i < u.temperature_c.size(); ++i)
      refit_t[i].push_back(inv.temperature_c(m.camera.rates(u.temperature_c[i])));
  }
  stage("Monte-Carlo refits", static_cast<std::size_t>(u.monte_carlo_refits),
        static_cast<std::size_t>(u.monte_carlo_refits));
  for (std::size_t i = 0; i < u.temperature_c.size(); ++i) {
    double mean = 0, var = 0;
    const auto& v = refit_t[i];
    for (double x : v) mean += x;
    if (!v.empty()) mean /= static_cast<double>(v.size());
    for (double x : v) var += (x - mean) * (x - mean);
    // With no refits the thermocouple's own standard uncertainty is the floor.
    const double floor_u = opt.thermocouple_tolerance_c / std::sqrt(3.0);
    u.u_calibration_c.push_back(v.size() > 1 ? std::max(std::sqrt(var / (v.size() - 1)), 0.0)
                                             : floor_u);
  }

  m.provenance = {{"tool", "pyrocam-calib"},
                  {"tool_version", PYROCAM_VERSION},
                  {"created_utc", utc_now()},
                  {"profile_source", profile.source.string()},
                  {"profile_name", profile.name},
                  {"dataset_path", std::filesystem::absolute(dataset.folder()).string()},
                  {"dataset_manifest_fnv1a64", dataset_fingerprint(dataset)},
                  {"seed", opt.seed}};
  out.seconds = since(t_start);

  // Verdict in plain words.
  std::ostringstream v;
  v.precision(2);
  v << std::fixed << "calibration residual " << 100 * rms_finite(out.rate_residual_optimised)
    << " % rms (datasheet QE: " << 100 * rms_finite(out.rate_residual_datasheet) << " %)";
  if (!out.table4.empty() && std::isfinite(out.table4[0].rms))
    v << "; MLP " << out.table4[0].rms << " degC rms on " << out.table4[0].true_c.size()
      << " calibration settings";
  int skipped_sat = 0, skipped_dim = 0;
  for (const auto& st : out.rates.status)
    for (PointStatus s : st)
      skipped_sat += s == PointStatus::kSaturated, skipped_dim += s == PointStatus::kDim;
  v << "; " << skipped_sat << " band points skipped as saturated, " << skipped_dim << " as dim";
  if (!out.warnings.empty()) v << "; " << out.warnings.size() << " warnings";
  out.verdict = v.str();
  m.summary = outcome_summary(out);
  return out;
}

nlohmann::json outcome_summary(const CalibrationOutcome& o) {
  using nlohmann::json;
  json j;
  j["verdict"] = o.verdict;
  j["qe_solver"] = o.model.qe_solver;
  json solvers = json::array();
  for (const auto& s : o.solvers)
    solvers.push_back({{"solver", s.solver},
                       {"calibration_residual_rms", s.calibration_residual},
                       {"held_out_residual_rms", s.held_out_residual},
                       {"qe_change_rms", s.qe_change_rms},
                       {"seconds", s.seconds}});
  j["solvers"] = solvers;
  j["rate_residual_rms"] = {{"datasheet", rms_finite(o.rate_residual_datasheet)},
                            {"optimised", rms_finite(o.rate_residual_optimised)}};
  json t4 = json::array();
  for (const auto& s : o.table4)
    t4.push_back({{"estimator", s.name},
                  {"n", s.true_c.size()},
                  {"missing", s.missing},
                  {"mean_c", s.mean},
                  {"std_c", s.std},
                  {"rms_c", s.rms},
                  {"exposure_spread_c", s.exposure_spread}});
  j["table4"] = t4;
  j["mlp"] = {{"final_train_rmse_c", o.mlp_report.final_train_rmse},
              {"final_test_rmse_c", o.mlp_report.final_test_rmse},
              {"locus_max_error_c", o.mlp_locus_max_error_c},
              {"locus_rms_error_c", o.mlp_locus_rms_error_c},
              {"polish_iterations", o.mlp_report.polish_iterations_done},
              {"noisy_copies", o.mlp_report.augmented_samples},
              {"noisy_copies_rmse_c", o.mlp_report.augmented_rmse},
              {"noisy_copies_median_abs_error_c", o.mlp_report.augmented_median_abs_error},
              {"seconds", o.mlp_report.seconds}};
  j["warnings"] = o.warnings;
  j["seconds"] = o.seconds;
  return j;
}

}  // namespace pyrocam
