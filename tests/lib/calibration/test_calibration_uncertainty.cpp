// The uncertainty stage: the emissivity tilt, the thermocouple Monte Carlo and the table.
#include <gtest/gtest.h>

#include <cmath>

#include "calibration/synthetic_calibration.h"
#include "pyrocam/calibration/calibration_uncertainty.h"
#include "pyrocam/runtime/estimators.h"

namespace pyrocam {
namespace {

const std::vector<double> kFurnaceC = {800, 900, 1000, 1100, 1200, 1300, 1400};

TEST(WithEmissivitySlope, tilts_q_linearly_about_the_pass_band_centre) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const Eigen::MatrixXd q = p.system_qe();
  EXPECT_EQ(with_emissivity_slope(p, q, 0), q);
  const double centre = 0.5 * (p.filter_pass_band_nm[0] + p.filter_pass_band_nm[1]);
  const Eigen::MatrixXd tilted = with_emissivity_slope(p, q, 0.1);
  for (Eigen::Index i = 0; i < p.grid.size(); i += 7)
    for (Eigen::Index b = 0; b < q.rows(); ++b)
      EXPECT_NEAR(tilted(b, i), q(b, i) * (1 + 0.1 * (p.grid.nm()[i] - centre) / 100), 1e-15);
}

// A model of the datasheet camera (fitted QE: refits allowed), its range 800-1400 degC, no MLP.
ThermalModel camera_only_model(const CameraProfile& p) {
  ThermalModel m;
  m.qe_solver = "regularised";
  m.min_temperature_c = 800;
  m.max_temperature_c = 1400;
  m.camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  return m;
}

UncertaintyModel table_at(std::vector<double> t_c, double tolerance_c, int refits) {
  UncertaintyModel u;
  u.temperature_c = std::move(t_c);
  u.thermocouple_tolerance_c = tolerance_c;
  u.monte_carlo_refits = refits;
  return u;
}

TEST(ThermocoupleUncertainty, grows_with_the_tolerance_and_is_zero_without_it) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const ThermalModel m = camera_only_model(p);
  const Eigen::MatrixXd rates = test::furnace_rates(m.camera, kFurnaceC);
  const std::vector<double> grid = {900, 1300};
  std::size_t reports = 0;
  const auto exact =
      thermocouple_uncertainty(m, table_at(grid, 0, 3), kFurnaceC, rates, 1,
                               [&](const std::string& stage, std::size_t, std::size_t) {
                                 EXPECT_EQ(stage, "Monte-Carlo refits");
                                 ++reports;
                               });
  EXPECT_EQ(reports, 4u);  // one per refit and the last
  const auto loose = thermocouple_uncertainty(m, table_at(grid, 5, 3), kFurnaceC, rates, 1);
  const auto looser = thermocouple_uncertainty(m, table_at(grid, 20, 3), kFurnaceC, rates, 1);
  ASSERT_EQ(exact.size(), 2u);
  ASSERT_EQ(loose.size(), 2u);
  ASSERT_EQ(looser.size(), 2u);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    SCOPED_TRACE(grid[i]);
    EXPECT_NEAR(exact[i], 0, 1e-6);  // every refit sees the same temperatures
    EXPECT_GT(loose[i], 0.01);
    EXPECT_GT(looser[i], loose[i]);
  }
}

// The term is the thermocouple's, not the fit's: on a hostile colour unit (the fit of its
// furnace rates, where the readings above the furnace depend most on the data) a tolerance a
// hundred times smaller gives a term about a hundred times smaller at 1800-2600 degC. While
// the fit stopped at its iteration limit, where it then was, a tolerance of 0.01 degC already
// gave a term of degrees there.
TEST(ThermocoupleUncertainty, follows_the_tolerance_above_the_furnace) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const CalibrationRates data = test::hostile_campaign(p, 1).data;
  const QeFitResult fit = fit_qe(p, data);
  ThermalModel m;
  m.qe_solver = "regularised";
  m.min_temperature_c = 500;
  m.max_temperature_c = 3000;
  m.camera = CameraModel{p, fit.system_qe, fit.gains};
  const std::vector<double> grid = {1800, 2200, 2600};
  const Eigen::MatrixXd rates = data.rates.transpose();
  const auto u1 = thermocouple_uncertainty(m, table_at(grid, 1, 4), data.temperatures_c, rates, 1);
  const auto u001 =
      thermocouple_uncertainty(m, table_at(grid, 0.01, 4), data.temperatures_c, rates, 1);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    SCOPED_TRACE(grid[i]);
    EXPECT_GT(u1[i], 0.1);  // a degree's deviation does reach the high range
    // Linear for small deviations: the same draws scaled, so the ratio is near 100; the bounds
    // leave a factor two for the fit's own tolerance and the curvature at 1 degC.
    EXPECT_GT(u1[i] / u001[i], 50);
    EXPECT_LT(u1[i] / u001[i], 200);
  }
}

TEST(ThermocoupleUncertainty, without_refits_is_the_tolerances_standard_uncertainty) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const ThermalModel m = camera_only_model(p);
  const Eigen::MatrixXd rates = test::furnace_rates(m.camera, kFurnaceC);
  const auto u =
      thermocouple_uncertainty(m, table_at({900, 1000, 1100}, 6, 0), kFurnaceC, rates, 1);
  EXPECT_EQ(u, std::vector<double>(3, 6 / std::sqrt(3.0)));
}

TEST(UncertaintyModel, tabulates_every_50_degc_and_the_emissivity_term_grows_with_the_slope) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  ThermalModel m = test::small_model(p, 800, 1400);
  m.qe_solver = "datasheet";  // no refits: the table's calibration term is the floor
  const Eigen::MatrixXd rates = test::furnace_rates(m.camera, kFurnaceC);
  CalibrationOptions opt;
  opt.min_temperature_c = 800;
  opt.max_temperature_c = 1400;
  opt.thermocouple_tolerance_c = 3;
  const UncertaintyModel u = uncertainty_model(m, kFurnaceC, rates, opt);
  ASSERT_EQ(u.temperature_c.size(), 13u);
  EXPECT_EQ(u.temperature_c.front(), 800);
  EXPECT_EQ(u.temperature_c.back(), 1400);
  EXPECT_EQ(u.monte_carlo_refits, 0);
  EXPECT_EQ(u.thermocouple_tolerance_c, 3);
  EXPECT_EQ(u.u_calibration_c, std::vector<double>(13, 3 / std::sqrt(3.0)));
  ASSERT_EQ(u.u_emissivity_c.size(), 13u);

  UncertaintyModel steeper = u;
  steeper.emissivity_slope_u = 0.1;
  const std::vector<double> shifted = emissivity_uncertainty(m, steeper);
  ASSERT_EQ(shifted.size(), 13u);
  for (std::size_t i = 0; i < shifted.size(); ++i) {
    SCOPED_TRACE(u.temperature_c[i]);
    EXPECT_GT(shifted[i], u.u_emissivity_c[i]);
  }
  // A grey body's reading is the reference: the network's own error on the locus is not an
  // emissivity effect (it made the term 0.5-0.8 degC too large).
  UncertaintyModel grey = u;
  grey.emissivity_slope_u = 0;
  EXPECT_EQ(emissivity_uncertainty(m, grey), std::vector<double>(13, 0.0));
}

// A 5x5 camera well exposed at 400 degC has a band too dim to read, so no posterior sample reads
// there: the model still gets a number (the nearest temperature's). A calibrated hostile unit
// wrote null there, and load_model refused its own model.
TEST(QeModelUncertainty, a_temperature_no_sample_reads_gets_the_nearest_value) {
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  const CameraModel camera{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  auto model = std::make_shared<ThermalModel>();
  model->camera = camera;
  model->datasheet_qe = p.system_qe();
  model->min_temperature_c = 200;
  model->max_temperature_c = 1300;
  Eigen::VectorXd s = camera.rates(400);
  s *= 150 / s.maxCoeff();
  ASSERT_TRUE(std::isnan(make_estimator(model, Method::kLikelihood)->temperature_c(s.data())))
      << "the test needs a temperature that does not read";
  std::vector<QeSample> posterior;
  for (int k = 0; k < 8; ++k) {
    Eigen::VectorXd gains = Eigen::VectorXd::Ones(p.band_count());
    for (Eigen::Index b = 0; b < gains.size(); ++b) gains[b] += 0.01 * std::sin(3.0 * k + b);
    posterior.push_back(QeSample{p.system_qe(), gains});
  }
  const std::vector<double> u =
      qe_model_uncertainty(camera, posterior, {400, 500, 600, 700, 800, 900});
  ASSERT_EQ(u.size(), 6u);
  for (double v : u) EXPECT_TRUE(std::isfinite(v));
  std::size_t first = 0;  // the first temperature that reads
  while (first < u.size() && u[first] == u[0]) ++first;
  EXPECT_GT(first, 0u);
  EXPECT_GT(u[0], 0.0);
}

// A prior fit that reads as the model does adds nothing; one that reads otherwise adds its
// difference in quadrature, so the term never shrinks.
TEST(QeModelUncertainty, prior_fits_add_the_reading_change_they_make) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const CameraModel camera{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  std::vector<QeSample> posterior;
  for (int k = 0; k < 8; ++k) {
    Eigen::VectorXd gains = Eigen::VectorXd::Ones(p.band_count());
    for (Eigen::Index b = 0; b < gains.size(); ++b) gains[b] += 0.002 * std::sin(3.0 * k + b);
    posterior.push_back(QeSample{p.system_qe(), gains});
  }
  const std::vector<double> t{900, 1500, 2500};
  const std::vector<double> alone = qe_model_uncertainty(camera, posterior, t);
  const std::vector<double> same =
      qe_model_uncertainty(camera, posterior, t, {QeSample{p.system_qe(), camera.band_scale}});
  EXPECT_EQ(same, alone);
  const QeSample tilted{with_emissivity_slope(p, p.system_qe(), 0.05), camera.band_scale};
  const std::vector<double> wider = qe_model_uncertainty(camera, posterior, t, {tilted});
  ASSERT_EQ(wider.size(), t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    SCOPED_TRACE(t[i]);
    EXPECT_GT(wider[i], alone[i] + 1.0);  // a 5 %/100 nm slope moves readings by degrees
  }
  EXPECT_GT(wider[2], wider[0]);  // and more the hotter the body
}

}  // namespace
}  // namespace pyrocam
