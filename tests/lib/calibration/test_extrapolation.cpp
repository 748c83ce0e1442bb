// Above the furnace: the hostile unit family, reference rows in the QE fit, and the posterior
// spread that tells the model where it extrapolates. Rate level (no images), a few seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <string>

#include "calibration/synthetic_calibration.h"
#include "pyrocam/calibration/calibration_uncertainty.h"
#include "pyrocam/calibration/extrapolation_study.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

double rms_between(const std::vector<double>& t, const std::vector<double>& e, double lo,
                   double hi) {
  double ss = 0;
  int n = 0;
  for (std::size_t i = 0; i < t.size(); ++i)
    if (t[i] >= lo && t[i] <= hi) ss += e[i] * e[i], ++n;
  return std::sqrt(ss / n);
}

std::vector<double> grid_c() {
  std::vector<double> t;
  for (double x = 700; x <= 2600; x += 100) t.push_back(x);
  return t;
}

TEST(HostileUnits, differ_from_typical_and_are_seeded) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const Eigen::MatrixXd typical = true_system_qe(p, UnitPerturbation::parse("typical", 4));
  const Eigen::MatrixXd hostile = true_system_qe(p, UnitPerturbation::parse("hostile", 4));
  EXPECT_EQ(hostile, true_system_qe(p, UnitPerturbation::parse("hostile", 4)));
  EXPECT_NE(hostile, true_system_qe(p, UnitPerturbation::parse("hostile", 5)));
  EXPECT_GE(hostile.minCoeff(), 0.0);
  EXPECT_LE(hostile.maxCoeff(), 1.0);
  // Edges, leaks, a slope and shapes: several percent of the band's QE, not a rounding.
  const double change =
      ((hostile - typical).rowwise().norm().array() / typical.rowwise().norm().array()).maxCoeff();
  std::cout << "largest relative change of a band against the typical unit: " << change << "\n";
  EXPECT_GT(change, 0.03);
  EXPECT_THROW(UnitPerturbation::parse("friendly", 1), InputError);
}

// The foreign family: seeded, within [0, 1], and off the typical unit by deviations of its own
// (on every band, and outside the pass band where the typical unit's filter blocks).
TEST(ForeignUnits, differ_from_typical_and_hostile_and_are_seeded) {
  for (const char* name : {"rgb-reference", "nir5x5-reference"}) {
    const CameraProfile p = load_profile_by_name(name);
    const Eigen::MatrixXd typical = true_system_qe(p, UnitPerturbation::parse("typical", 4));
    const Eigen::MatrixXd hostile = true_system_qe(p, UnitPerturbation::parse("hostile", 4));
    const Eigen::MatrixXd foreign = true_system_qe(p, UnitPerturbation::parse("foreign", 4));
    EXPECT_EQ(foreign, true_system_qe(p, UnitPerturbation::parse("foreign", 4)));
    EXPECT_NE(foreign, true_system_qe(p, UnitPerturbation::parse("foreign", 5)));
    EXPECT_NE(foreign, hostile);
    EXPECT_GE(foreign.minCoeff(), 0.0);
    EXPECT_LE(foreign.maxCoeff(), 1.0);
    const Eigen::ArrayXd change =
        (foreign - typical).rowwise().norm().array() / typical.rowwise().norm().array();
    std::cout << name << ": smallest and largest relative change of a band against the typical "
              << "unit: " << change.minCoeff() << ", " << change.maxCoeff() << "\n";
    EXPECT_GT(change.minCoeff(), 0.01);
    // The weak blocking: light outside the pass band that the typical unit's filter stops (the
    // colour camera's below it, the 5x5 camera's below 650 nm).
    const double cut = std::string(name) == "rgb-reference" ? p.filter_pass_band_nm[0] - 45 : 650.0;
    double outside_typical = 0, outside_foreign = 0;
    for (Eigen::Index i = 0; i < p.grid.size(); ++i)
      if (p.grid.nm()[i] < cut)
        outside_typical += typical.col(i).sum(), outside_foreign += foreign.col(i).sum();
    EXPECT_GT(outside_foreign, 2 * outside_typical);
  }
}

// What the hostile family does to the fit without and with three reference rows.
struct Study {
  std::vector<double> without, with;
  QeFitResult fit_with;
};

Study study(const std::string& profile_name, std::uint64_t unit) {
  const CameraProfile p = load_profile_by_name(profile_name);
  const Eigen::MatrixXd truth = true_system_qe(p, UnitPerturbation::parse("hostile", unit));
  RateCampaign campaign;
  campaign.seed = 100 + unit;
  Study s;
  const QeFitResult plain = fit_qe(p, simulate_calibration_rates(p, truth, campaign));
  s.without =
      extrapolation_errors(p, truth, CameraModel{p, plain.system_qe, plain.gains}, grid_c());
  campaign.reference_temperatures_c = {1324, 1738, 2474};
  s.fit_with = fit_qe(p, simulate_calibration_rates(p, truth, campaign));
  s.with = extrapolation_errors(p, truth, CameraModel{p, s.fit_with.system_qe, s.fit_with.gains},
                                grid_c());
  return s;
}

TEST(ReferenceRows, pin_the_high_range_of_hostile_units) {
  for (const char* profile : {"rgb-reference", "nir5x5-reference"})
    for (std::uint64_t unit : {2, 3}) {
      SCOPED_TRACE(std::string(profile) + " unit " + std::to_string(unit));
      const Study s = study(profile, unit);
      const double without = rms_between(grid_c(), s.without, 700, 2600);
      const double with = rms_between(grid_c(), s.with, 700, 2600);
      std::cout << profile << " hostile unit " << unit << ": rms error 700-2600 degC without "
                << without << ", with three reference rows " << with << " degC\n";
      // The target is 5 degC rms with three reference rows (over many units; 2.5 degC rms for
      // colour, 1.4 for 5x5 over six hostile units in bench_extrapolation); one unit may miss it.
      EXPECT_LT(with, 8.0);
      EXPECT_LT(with, std::max(without, 3.0));  // never much worse than without
      // The report's residuals: each reference read by the fitted model within a few degC.
      ASSERT_EQ(s.fit_with.diagnostics.reference_error_after_c.size(), 3u);
      for (double e : s.fit_with.diagnostics.reference_error_after_c) EXPECT_LT(std::abs(e), 10.0);
    }
}

TEST(ReferenceRows, bad_rows_are_named) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  RateCampaign campaign;
  campaign.reference_temperatures_c = {1738};
  CalibrationRates data = simulate_calibration_rates(p, p.system_qe(), campaign);
  data.references[0].name = "Pt-C cell";
  data.references[0].temperature_uncertainty_c = NAN;
  try {
    fit_qe(p, data);
    ADD_FAILURE() << "a NaN uncertainty was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Pt-C cell"), std::string::npos) << e.what();
  }
  data.references[0].temperature_uncertainty_c = 0.5;
  data.references[0].rates[1] = data.references[0].rates[2] = NAN;
  EXPECT_THROW(fit_qe(p, data), InputError);  // one usable band: no ratio
}

// Hostile 5x5 unit 4 has narrow leaks at 670 and 682 nm, just below the filter's 705 nm edge:
// the furnace barely sees them, and the fit without the shape changes explained what it saw
// with its own parameters and read +68 degC at 2600 degC. Fitted jointly, the shape changes
// take up what the parameters cannot shape, and the extrapolation follows. Both with the broad
// leak bumps (with the narrow ones that kept leaks get, +18 and +13 degC: test_leak_terms).
TEST(JointShapeFit, takes_up_what_the_parameters_cannot_shape) {
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  const Eigen::MatrixXd truth = true_system_qe(p, UnitPerturbation::parse("hostile", 4));
  const CalibrationRates data = simulate_calibration_rates(p, truth, {});
  // With the leak terms both ways (whether the data call for them is test_leak_terms').
  QeFitOptions posterior_only, joint_fit;
  posterior_only.regularised.leak_terms = joint_fit.regularised.leak_terms = LeakTerms::kKeep;
  posterior_only.regularised.fit_discrepancy = false;
  posterior_only.regularised.fine_leak_spacing_nm = joint_fit.regularised.fine_leak_spacing_nm = 0;
  const QeFitResult before = fit_qe(p, data, posterior_only);
  const QeFitResult joint = fit_qe(p, data, joint_fit);
  EXPECT_GE(joint.system_qe.minCoeff(), 0.0);
  EXPECT_LE(joint.system_qe.maxCoeff(), 1.0);
  const std::vector<double> t{900, 1100, 2600};
  const auto e0 = extrapolation_errors(p, truth, CameraModel{p, before.system_qe, before.gains}, t);
  const auto e1 = extrapolation_errors(p, truth, CameraModel{p, joint.system_qe, joint.gains}, t);
  std::cout << "hostile 5x5 unit 4, error at 900 / 1100 / 2600 degC: posterior only " << e0[0]
            << " / " << e0[1] << " / " << e0[2] << ", joint " << e1[0] << " / " << e1[1] << " / "
            << e1[2] << "\n";
  // The data still fit: in range within 0.5 degC (0.3 measured both ways).
  EXPECT_LT(std::abs(e1[0]), 0.5);
  EXPECT_LT(std::abs(e1[1]), 0.5);
  // Deterministic figures (portable maths): measured +68 and +37 degC.
  EXPECT_GT(std::abs(e0[2]), 40.0);
  EXPECT_LT(std::abs(e1[2]), 0.6 * std::abs(e0[2]));
}

TEST(QePosterior, spreads_where_the_furnace_does_not_reach) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const Eigen::MatrixXd truth = true_system_qe(p, UnitPerturbation::parse("typical", 3));
  QeFitOptions options;
  options.regularised.posterior_samples = 48;
  // The mechanism at the nominal widths (this unit's data favour half of them: a narrower
  // posterior, whose prior fits then spread less above the furnace).
  options.regularised.prior_scales = {1};
  const QeFitResult fit = fit_qe(p, simulate_calibration_rates(p, truth, {}), options);
  ASSERT_EQ(fit.posterior.size(), 48u);
  const std::vector<double> t{900, 1500, 2500};
  const std::vector<double> u =
      qe_model_uncertainty(CameraModel{p, fit.system_qe, fit.gains}, fit.posterior, t);
  std::cout << "u QE model at 900 / 1500 / 2500 degC: " << u[0] << " " << u[1] << " " << u[2]
            << "\n";
  EXPECT_LT(u[0], 3.0);       // the furnace range is pinned by the data
  EXPECT_GT(u[2], 3 * u[0]);  // far above it the QE is open and the model says so

  // The priors' own share: fits with them twice as wide and half as wide read the furnace
  // range alike and part above it, so the term grows there and hardly at all in range.
  const std::vector<QeSample> prior_fits = prior_sensitivity_fits(
      p, simulate_calibration_rates(p, truth, {}), options, fit, 2, INFINITY);
  ASSERT_EQ(prior_fits.size(), 2u);
  const std::vector<double> with_priors =
      qe_model_uncertainty(CameraModel{p, fit.system_qe, fit.gains}, fit.posterior, t, prior_fits);
  std::cout << "with the prior-sensitivity fits: " << with_priors[0] << " " << with_priors[1] << " "
            << with_priors[2] << "\n";
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_GE(with_priors[i], u[i]);
  EXPECT_LT(with_priors[0], u[0] + 0.5);
  EXPECT_GT(with_priors[2], u[2] + 0.5);
  // The paper's solver has no priors to vary.
  QeFitOptions paper = options;
  paper.solver = QeSolver::kPaper;
  EXPECT_TRUE(
      prior_sensitivity_fits(p, simulate_calibration_rates(p, truth, {}), paper, fit).empty());
}

// A prior fit's reading crosses the model's somewhere above the furnace (hostile colour unit 1:
// between 1600 and 1800 degC), where its change is near zero; that is no knowledge, and the
// term must not dip there (it did: 13.5, 12.2, 9.7 degC at 1500, 1600 and 1700 degC). Nor where
// the posterior samples' readings pivot (1.08 degC at 1100, 0.86 at 1200 degC), even where the
// whole term is least just above the furnace's top (2.06 degC at 1100, 1.52 at 1200 once kept
// leaks were fitted with narrow bumps).
TEST(QePosterior, the_prior_term_never_shrinks_away_from_the_furnace) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const Eigen::MatrixXd truth = true_system_qe(p, UnitPerturbation::parse("hostile", 1));
  RateCampaign campaign;
  campaign.seed = 101;  // as the extrapolation study's unit 1
  const CalibrationRates data = simulate_calibration_rates(p, truth, campaign);
  QeFitOptions options;
  options.regularised.posterior_samples = 48;
  const QeFitResult fit = fit_qe(p, data, options);
  const CameraModel model{p, fit.system_qe, fit.gains};
  std::vector<double> t;
  for (double c = 2600; c >= 700; c -= 100) t.push_back(c);  // any order
  const std::vector<double> u = qe_model_uncertainty(
      model, fit.posterior, t, prior_sensitivity_fits(p, data, options, fit),
      *std::max_element(data.temperatures_c.begin(), data.temperatures_c.end()));
  ASSERT_EQ(u.size(), t.size());
  // From the furnace's top (1100 degC) up.
  for (std::size_t i = 0; i + 1 < t.size() && t[i + 1] >= 1100; ++i) {
    SCOPED_TRACE(t[i]);
    EXPECT_GE(u[i], u[i + 1]);
  }
}

// The fit is a smooth function of its data: furnace temperatures moved by a hundredth of a
// degree (all together, or each its own way) move the readings above the furnace by about as
// little, not by what wherever an unfinished fit stopped would give. Hostile colour unit 1,
// where the fit that stopped at its iteration limit moved the reading at 2600 degC by up to
// 29 degC for such a change.
TEST(QeFit, a_hundredth_of_a_degree_in_the_furnace_moves_the_high_range_by_little) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const auto [truth, data] = test::hostile_campaign(p, 1);
  const QeFitResult fit = fit_qe(p, data);
  const CameraModel model{p, fit.system_qe, fit.gains};
  const std::vector<double> hot = {1800, 2200, 2600};
  const std::vector<double> base = extrapolation_errors(p, truth, model, hot);
  for (int way = 0; way < 3; ++way) {
    SCOPED_TRACE(way);
    CalibrationRates moved = data;
    for (std::size_t i = 0; i < moved.temperatures_c.size(); ++i)
      moved.temperatures_c[i] += way == 0 ? 0.01 : way == 1 ? -0.01 : (i % 2 ? 0.01 : -0.01);
    const QeFitResult refit = fit_qe(p, moved);
    const std::vector<double> e =
        extrapolation_errors(p, truth, CameraModel{p, refit.system_qe, refit.gains}, hot);
    // A degree's shift of the whole scale moves the reading at 2600 degC by about 4 degC here:
    // a hundredth by about 0.04; 1 degC leaves room for the fit's own tolerance.
    for (std::size_t i = 0; i < hot.size(); ++i) EXPECT_LT(std::abs(e[i] - base[i]), 1.0) << hot[i];
  }
}

}  // namespace
}  // namespace pyrocam
