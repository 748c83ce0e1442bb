// Targets above the furnace (rate level, no images): for seeded hostile units of each camera
// (twenty colour, six 5x5: a colour unit's fit takes a second, a 5x5 one's five), the QE fit's
// reading error from 700 to 2600 degC without and with three reference rows
// (1324 / 1738 / 2474 degC), and how often a k=2 interval covers it at 1500-2600 degC: that of
// the QE-model uncertainty (the posterior's spread and the prior-sensitivity fits, as
// pyrocam-calib computes it), and that of the QE-model and the default emissivity terms together
// (the part of the interval ratiotemp output=uncertainty and measure --uncertainty report that
// this level of study holds; the reading's noise and the thermocouple's term only widen it).
// Prints every figure; asserts the targets that hold with loose bounds and, for those not yet
// met, that they do not get worse than measured when this test was written. Last, six units of
// the foreign family (out of family, no targets): the interval still covers their errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pyrocam/calibration/calibration_uncertainty.h"
#include "pyrocam/calibration/extrapolation_study.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

struct Figures {
  double in_range = 0, range_800_2600 = 0, range_1800_2600 = 0, range_700_2600 = 0;
  int covered = 0, counted = 0;
  int covered_with_emissivity = 0;
};

Figures evaluate(const std::string& profile_name, bool references, int units,
                 const std::string& family = "hostile") {
  const CameraProfile p = load_profile_by_name(profile_name);
  std::vector<double> temps;
  for (double t = 700; t <= 2600; t += 100) temps.push_back(t);
  double ss[4] = {0, 0, 0, 0};
  int n[4] = {0, 0, 0, 0};
  Figures f;
  std::printf("%s, %d %s units%s\n", profile_name.c_str(), units, family.c_str(),
              references ? ", three reference rows" : "");
  for (std::uint64_t unit = 1; unit <= static_cast<std::uint64_t>(units); ++unit) {
    const Eigen::MatrixXd truth = true_system_qe(p, UnitPerturbation::parse(family, unit));
    RateCampaign campaign;
    campaign.seed = 100 + unit;
    if (references) campaign.reference_temperatures_c = {1324, 1738, 2474};
    QeFitOptions options;
    options.regularised.posterior_samples = 48;
    const CalibrationRates data = simulate_calibration_rates(p, truth, campaign);
    const QeFitResult fit = fit_qe(p, data, options);
    const CameraModel model{p, fit.system_qe, fit.gains};
    const double top = hottest_calibrated_c(data);  // as pyrocam-calib stores it in the model
    const std::vector<double> e = extrapolation_errors(p, truth, model, temps, top);
    // Coverage is counted without reference rows only: no prior refits for the others.
    const std::vector<double> u = qe_model_uncertainty(
        model, fit.posterior, temps,
        references ? std::vector<QeSample>{} : prior_sensitivity_fits(p, data, options, fit),
        *std::max_element(data.temperatures_c.begin(), data.temperatures_c.end()), top);
    // The default emissivity term: the reading of a grey-assuming model for rates with the
    // model's default slope uncertainty.
    const Eigen::MatrixXd tilted =
        with_emissivity_slope(p, fit.system_qe, UncertaintyModel{}.emissivity_slope_u)
            .array()
            .colwise() *
        fit.gains.array();
    const std::vector<double> u_e = extrapolation_errors(p, tilted, model, temps, top);
    std::printf("  unit %d:", static_cast<int>(unit));
    for (std::size_t i = 0; i < temps.size(); ++i) {
      std::printf(" %.0f", e[i]);
      const double t = temps[i];
      const bool in[4] = {t >= 700 && t <= 1100, t >= 800, t >= 1800, true};
      for (int k = 0; k < 4; ++k)
        if (in[k]) ss[k] += e[i] * e[i], ++n[k];
      if (t < 1500) continue;
      f.covered += std::abs(e[i]) <= 2 * u[i], ++f.counted;
      f.covered_with_emissivity += std::abs(e[i]) <= 2 * std::hypot(u[i], u_e[i]);
    }
    std::printf("\n");
  }
  f.in_range = std::sqrt(ss[0] / n[0]);
  f.range_800_2600 = std::sqrt(ss[1] / n[1]);
  f.range_1800_2600 = std::sqrt(ss[2] / n[2]);
  f.range_700_2600 = std::sqrt(ss[3] / n[3]);
  std::printf(
      "  rms in range %.2f, 800-2600 %.2f, 1800-2600 %.2f, 700-2600 %.2f degC; k=2 "
      "coverage at 1500-2600: %d of %d (with the emissivity term %d)\n",
      f.in_range, f.range_800_2600, f.range_1800_2600, f.range_700_2600, f.covered, f.counted,
      f.covered_with_emissivity);
  return f;
}

TEST(ExtrapolationTargets, colour) {
  const Figures plain = evaluate("rgb-reference", false, 20);
  const Figures refs = evaluate("rgb-reference", true, 20);
  EXPECT_LT(plain.in_range, 0.8);       // target: no worse than before (0.8)
  EXPECT_LT(refs.range_700_2600, 5.0);  // target 5 degC rms with three reference rows
  // Target 15, NOT MET: 22.0 measured over these 20 units since above the calibration the
  // colour camera reads from the ratio of the two bands the furnace constrains best (30.4 from
  // every band, 37.6 while the furnace offsets' trend was held at zero, 35.8 before the fit
  // converged); a regression bound. The figures are deterministic (portable maths), so the
  // margins guard against regressions, not noise. The rates' noise here (3e-4) is above what
  // image campaigns give: end to end, each unit calibrated from its own campaign of ten frames a
  // setting and `measure` reading its filaments, the 20 units read 15.2 degC rms
  // (docs/extrapolation.md).
  EXPECT_LT(plain.range_1800_2600, 26);
  // Coverage target 95 +- 3 %: the QE-model term's k=2 interval covers 229 of 240 measured
  // (95.4 %; 226 when every band read). With the default emissivity term too it covers all 240:
  // that term is the reading's change for a surface 1 %/100 nm off grey, and the simulated
  // surfaces are grey, so it can only widen the interval here (one ratio of nearer bands moves
  // more with a slope than two: 229 of 240 when every band read). Over six units alone the
  // coverage is too poorly sampled to tell (a unit's twelve temperatures are covered or missed
  // together).
  EXPECT_GE(plain.covered, 0.92 * plain.counted);
  EXPECT_LE(plain.covered, 0.98 * plain.counted);
  EXPECT_GE(plain.covered_with_emissivity, plain.covered);
}

TEST(ExtrapolationTargets, multispectral) {
  const Figures plain = evaluate("nir5x5-reference", false, 6);
  const Figures refs = evaluate("nir5x5-reference", true, 6);
  EXPECT_LT(plain.in_range, 1.2);       // target: no worse than before (1.2)
  EXPECT_LT(refs.range_700_2600, 5.0);  // target 5 degC rms with three reference rows
  // Target 10: 3.1 measured over these six units and 4.5 over the first twenty
  // (bench_extrapolation --units 20; 4.0 and 4.5 before the prior widths were chosen by the
  // evidence), with the leak terms kept only where the data call for them (three of the twenty);
  // always kept 7.7 and 12.0 (7.9 with the offsets' trend held at zero, 6.9 before the fit
  // converged, 12.3 before the joint fit).
  EXPECT_LT(plain.range_800_2600, 10);
  // Coverage target 95 +- 3 %: 72 of 72 measured (62 before the joint fit), above the target's
  // band on these six units; over the first twenty 230 of 240 (95.8 %, bench_extrapolation
  // --coverage; 240 while every prior-sensitivity fit counted, whatever its evidence: the
  // window leaves out those the data reject). Six units are too few to tell (a unit's twelve
  // temperatures are covered or missed together): asserted as a lower bound only.
  EXPECT_GE(plain.covered, 65);
}

// Out of family: units whose deviations the QE model was not built around (the simulator's
// foreign family; docs/extrapolation.md), which no setting was chosen by. No target there: the
// readings go further wrong above the furnace (they lean low at 2600 degC, from leaks the furnace
// cannot see), and what must hold is that the interval a reading carries says so, and that the
// furnace range reads as on any unit.
TEST(ExtrapolationOutOfFamily, foreign_units_read_within_their_interval) {
  for (const char* camera : {"rgb-reference", "nir5x5-reference"}) {
    const Figures f = evaluate(camera, false, 6, "foreign");
    EXPECT_LT(f.in_range, 0.8);
    EXPECT_GE(f.covered_with_emissivity, 0.95 * f.counted);
  }
}

}  // namespace
}  // namespace pyrocam
