// Benchmark: how the QE fit extrapolates beyond the furnace, per unit family and seeded unit, at
// the level of signal rates (furnace rates of the true QE with 0.3 % noise, the fit, and the
// likelihood reading of the fitted model at 700-2600 degC). Prints the error against temperature.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "pyrocam/calibration/calibration_uncertainty.h"
#include "pyrocam/calibration/extrapolation_study.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/simulation/simulator.h"

using namespace pyrocam;

int main(int argc, char** argv) {
  CLI::App app{"QE fit extrapolation per unit family"};
  std::vector<std::string> profiles{"rgb-reference", "nir5x5-reference"};
  std::vector<std::string> families{"typical", "hostile"};
  int units = 6;
  std::vector<double> references;
  RateCampaign base;
  app.add_option("--profile", profiles, "camera profiles");
  app.add_option("--family", families, "unit families: typical, hostile, foreign, datasheet");
  app.add_option("--units", units, "seeded units per family");
  app.add_option("--reference", references, "reference temperatures, degC")->delimiter(',');
  app.add_option("--noise", base.relative_noise, "relative rms noise of a furnace rate");
  app.add_option("--furnace-sigma", base.furnace_error_sigma_c, "furnace temperature error, degC");
  std::string model_file;
  std::uint64_t unit_seed = 1;
  app.add_option("--model", model_file,
                 "evaluate this calibrated model against unit --unit-seed of the first family");
  app.add_option("--unit-seed", unit_seed, "seed of the unit the model was calibrated on");
  std::vector<std::string> settings;
  app.add_option("--set", settings,
                 "regularised solver options, e.g. --set tilt_sigma=0.05 (see RegularisedOptions)");
  std::vector<std::string> variations;
  app.add_option("--vary", variations, "change the profile's unit variation (study), e.g. leak=0");
  bool coverage = false;
  app.add_flag("--coverage", coverage,
               "also the QE model uncertainty (posterior samples and the prior-sensitivity fits), "
               "and how often the k=2 interval covers the error at 1500-2600 degC");
  double occam_odds = 20;
  app.add_option("--occam-odds", occam_odds,
                 "with --coverage: the prior-sensitivity fits kept are those whose evidence is "
                 "within these odds of the best (inf: both)");
  CLI11_PARSE(app, argc, argv);
  QeFitOptions fit_options;
  RegularisedOptions& ro = fit_options.regularised;
  for (const std::string& setting : settings) {
    const auto eq = setting.find('=');
    const std::string key = setting.substr(0, eq);
    const double value = eq == std::string::npos ? NAN : std::atof(setting.c_str() + eq + 1);
    if (key == "tilt_sigma")
      ro.tilt_sigma = value;
    else if (key == "curvature_sigma")
      ro.curvature_sigma = value;
    else if (key == "shift_sigma_nm")
      ro.shift_sigma_nm = value;
    else if (key == "leak_sigma")
      ro.leak_sigma = value;
    else if (key == "leak_spacing_nm")
      ro.leak_spacing_nm = value;
    else if (key == "leak_curvature_sigma")
      ro.leak_curvature_sigma = value;
    else if (key == "common_tilt_sigma")
      ro.common_tilt_sigma = value;
    else if (key == "edge_shift_sigma_nm")
      ro.edge_shift_sigma_nm = value;
    else if (key == "furnace_temperature_sigma_c")
      ro.furnace_temperature_sigma_c = value;
    else if (key == "discrepancy_sigma")
      ro.discrepancy_sigma = value;
    else if (key == "discrepancy_spacing_nm")
      ro.discrepancy_spacing_nm = value;
    else if (key == "discrepancy_leak")
      ro.discrepancy_leak = value;
    else if (key == "fit_discrepancy")
      ro.fit_discrepancy = value != 0;
    else if (key == "discrepancy_leak_spacing_nm")
      ro.discrepancy_leak_spacing_nm = value;
    else if (key == "relative_noise")
      ro.relative_noise = value;
    else if (key == "noise_passes")
      ro.noise_passes = static_cast<int>(value);
    else if (key == "min_relative_noise")
      ro.min_relative_noise = value;
    else if (key == "leak_terms")  // 0 select, 1 keep, 2 drop
      ro.leak_terms = value == 1   ? LeakTerms::kKeep
                      : value == 2 ? LeakTerms::kDrop
                                   : LeakTerms::kSelect;
    else if (key == "leak_test_level")
      ro.leak_test_level = value;
    else if (key == "fine_leak_spacing_nm")
      ro.fine_leak_spacing_nm = value;
    else if (key == "prior_scale")  // one factor on the priors' widths: no choice
      ro.prior_scales = {value};
    else if (key == "leverage") {
      if (value == 0) ro.use_temperatures_c.clear();
    } else {
      std::fprintf(stderr, "unknown --set %s\n", key.c_str());
      return 2;
    }
  }
  std::vector<double> temps;
  for (double t = 700; t <= 2600; t += 100) temps.push_back(t);
  if (!model_file.empty()) {
    const ThermalModel m = load_model(model_file);
    const Eigen::MatrixXd truth =
        true_system_qe(m.profile(), UnitPerturbation::parse(families.front(), unit_seed));
    const std::vector<double> e =
        extrapolation_errors(m.profile(), truth, m.camera, temps, m.calibrated_up_to_c);
    for (std::size_t i = 0; i < temps.size(); ++i) std::printf("%6.0f %7.2f\n", temps[i], e[i]);
    return 0;
  }
  for (const auto& name : profiles) {
    CameraProfile profile = load_profile_by_name(name);
    for (const std::string& v : variations) {
      const auto eq = v.find('=');
      const std::string key = v.substr(0, eq);
      const double value = std::atof(v.c_str() + eq + 1);
      UnitVariation& u = profile.unit_variation;
      if (key == "leak")
        u.leak_system_qe = value;
      else if (key == "scale")
        u.scale_sigma = value;
      else if (key == "tilt")
        u.tilt_sigma = value;
      else if (key == "shift")
        u.shift_sigma_nm = value;
      else if (key == "filter_shift")
        u.filter_shift_sigma_nm = value;
      else if (key == "ripple")
        u.ripple_rms = value;
    }
    for (const auto& family : families) {
      std::printf("\n== %s, %s units%s\n   unit", name.c_str(), family.c_str(),
                  references.empty() ? "" : ", with reference rows");
      for (double t : temps) std::printf(" %6.0f", t);
      std::printf("   rms:in  1000-1400 1800-2600 800-2600\n");
      int covered = 0, counted = 0, covered_combined = 0, covered_posterior = 0;
      // Over the family's units per temperature: the mean error (a bias the units share, which
      // more units do not average away) and the rms.
      std::vector<double> sum(temps.size(), 0.0), sum2(temps.size(), 0.0);
      double all_sum2 = 0;  // 1800-2600 degC, every band read at every temperature
      for (int u = 1; u <= units; ++u) {
        const Eigen::MatrixXd truth =
            true_system_qe(profile, UnitPerturbation::parse(family, static_cast<std::uint64_t>(u)));
        RateCampaign campaign = base;
        campaign.reference_temperatures_c = references;
        campaign.seed = 100 + static_cast<std::uint64_t>(u);
        const CalibrationRates data = simulate_calibration_rates(profile, truth, campaign);
        QeFitOptions options = fit_options;
        options.regularised.posterior_samples = coverage ? 48 : 0;
        const QeFitResult fit = fit_qe(profile, data, options);
        const CameraModel model{profile, fit.system_qe, fit.gains};
        const double calibrated_up_to_c = hottest_calibrated_c(data);
        const std::vector<double> e =
            extrapolation_errors(profile, truth, model, temps, calibrated_up_to_c);
        // The same fit read with every band at every temperature, for comparison.
        const std::vector<double> e_all = extrapolation_errors(profile, truth, model, temps);
        const auto rms_of = [&](const std::vector<double>& v, double lo, double hi) {
          double ss = 0;
          int n = 0;
          for (std::size_t i = 0; i < temps.size(); ++i)
            if (temps[i] >= lo && temps[i] <= hi) ss += v[i] * v[i], ++n;
          return std::sqrt(ss / n);
        };
        const auto rms = [&](double lo, double hi) { return rms_of(e, lo, hi); };
        all_sum2 += std::pow(rms_of(e_all, 1800, 2600), 2);
        std::printf("   %4d", u);
        for (double v : e) std::printf(" %6.1f", v);
        for (std::size_t i = 0; i < temps.size(); ++i) sum[i] += e[i], sum2[i] += e[i] * e[i];
        if (coverage) {
          const double furnace_top =
              *std::max_element(data.temperatures_c.begin(), data.temperatures_c.end());
          const std::vector<double> u = qe_model_uncertainty(
              model, fit.posterior, temps,
              prior_sensitivity_fits(profile, data, options, fit, 2, occam_odds), furnace_top,
              calibrated_up_to_c);
          const std::vector<double> u_posterior = qe_model_uncertainty(
              model, fit.posterior, temps, {}, furnace_top, calibrated_up_to_c);
          // The emissivity term ratiotemp adds by default (e-slope-uncertainty 1 %/100 nm): the
          // reading of a grey-assuming model for rates with that slope.
          const Eigen::MatrixXd tilted =
              with_emissivity_slope(profile, fit.system_qe, UncertaintyModel{}.emissivity_slope_u)
                  .array()
                  .colwise() *
              fit.gains.array();
          const std::vector<double> u_e =
              extrapolation_errors(profile, tilted, model, temps, calibrated_up_to_c);
          std::printf("   u(k=1)");
          for (std::size_t i = 0; i < temps.size(); ++i) {
            std::printf(" %6.1f", u[i]);
            if (temps[i] < 1500) continue;
            covered += std::abs(e[i]) <= 2 * u[i], ++counted;
            covered_posterior += std::abs(e[i]) <= 2 * u_posterior[i];
            covered_combined += std::abs(e[i]) <= 2 * std::hypot(u[i], u_e[i]);
          }
          std::printf("\n       ");
        }
        std::printf("   %5.2f %8.2f %9.2f %8.2f   (fit %.1f s; leak terms %s; prior widths %s)\n",
                    rms(700, 1100), rms(1000, 1400), rms(1800, 2600), rms(800, 2600),
                    fit.diagnostics.wall_time_s, leak_terms_summary(fit).c_str(),
                    prior_widths_summary(fit).c_str());
      }
      std::printf("   mean");
      for (double v : sum) std::printf(" %6.1f", v / units);
      std::printf("\n    rms");
      for (double v : sum2) std::printf(" %6.1f", std::sqrt(v / units));
      double hot_sum2 = 0;
      int hot = 0;
      for (std::size_t i = 0; i < temps.size(); ++i)
        if (temps[i] >= 1800) hot_sum2 += sum2[i], ++hot;
      std::printf(
          "\n   1800-2600 degC: %.1f rms (read with every band at every temperature: %.1f)\n",
          std::sqrt(hot_sum2 / (units * hot)), std::sqrt(all_sum2 / units));
      if (coverage)
        std::printf(
            "   k=2 coverage at 1500-2600 degC: %d of %d (%.1f %%; the posterior's spread alone "
            "%d, %.1f %%); with the default emissivity term too: %d (%.1f %%)\n",
            covered, counted, 100.0 * covered / std::max(1, counted), covered_posterior,
            100.0 * covered_posterior / std::max(1, counted), covered_combined,
            100.0 * covered_combined / std::max(1, counted));
    }
  }
  return 0;
}
