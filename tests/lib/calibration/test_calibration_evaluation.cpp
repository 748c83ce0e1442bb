// The Table 4 stage: which settings are scored, the scores' arithmetic, and every estimator on
// noise-free rates of the model's own camera.
#include <gtest/gtest.h>

#include <cmath>

#include "calibration/synthetic_calibration.h"
#include "pyrocam/calibration/calibration_evaluation.h"

namespace pyrocam {
namespace {

SettingMeans setting(double t_c, double exposure_us, const Eigen::VectorXd& net) {
  SettingMeans s;
  s.temperature_c = t_c;
  s.exposure_us = exposure_us;
  s.frames = 1;
  s.net_mean_dn = net;
  s.raw_mean_dn = net;
  s.saturated_fraction = Eigen::VectorXd::Zero(net.size());
  return s;
}

TEST(EvaluableSettings, leave_out_saturated_dim_and_clipped_settings) {
  const CameraProfile p = load_profile_by_name("rgb-reference");  // inference window 20-220 DN
  RateTable rt;
  rt.settings.push_back(setting(1000, 100, Eigen::Vector3d(100, 120, 40)));
  rt.settings.push_back(setting(1000, 200, Eigen::Vector3d(100, 221, 40)));  // raw above 220
  rt.settings.push_back(setting(1000, 300, Eigen::Vector3d(100, 120, 19)));  // net below 20
  rt.settings.push_back(setting(1000, 400, Eigen::Vector3d(100, 120, 40)));
  rt.settings.back().saturated_fraction[1] = 1e-3;  // too many clipped ROI pixels
  rt.settings.push_back(setting(1100, 100, Eigen::Vector3d(20, 220, 20)));  // at the limits
  rt.settings[1].net_mean_dn[1] = 150;  // saturation is judged on raw values
  EXPECT_EQ(evaluable_settings(rt, p), (std::vector<std::size_t>{0, 4}));
}

TEST(ScoreEstimator, gives_the_mean_rms_std_missing_and_exposure_spread) {
  // The estimator reads band 0 as its temperature: errors +1 and +3 at 1000 degC, -3 at
  // 1100 degC, and no reading for one 1100 degC setting.
  RateTable rt;
  rt.temperatures_c = {1000, 1100};
  rt.settings = {
      setting(1000, 100, Eigen::Vector2d(1001, 0)), setting(1000, 200, Eigen::Vector2d(1003, 0)),
      setting(1100, 100, Eigen::Vector2d(1097, 0)), setting(1100, 200, Eigen::Vector2d(NAN, 0))};
  const EstimatorScore s =
      score_estimator("band 0", rt, {0, 1, 2, 3}, [](const Eigen::VectorXd& v) { return v[0]; });
  EXPECT_EQ(s.name, "band 0");
  EXPECT_EQ(s.missing, 1);
  EXPECT_EQ(s.true_c, (std::vector<double>{1000, 1000, 1100}));
  EXPECT_EQ(s.estimate_c, (std::vector<double>{1001, 1003, 1097}));
  EXPECT_NEAR(s.mean, 1.0 / 3, 1e-12);
  EXPECT_NEAR(s.rms, std::sqrt(19.0 / 3), 1e-12);
  EXPECT_NEAR(s.std, std::sqrt(19.0 / 3 - 1.0 / 9), 1e-12);
  // Only 1000 degC has two readings: their sample standard deviation.
  EXPECT_NEAR(s.exposure_spread, std::sqrt(2.0), 1e-12);

  const EstimatorScore none =
      score_estimator("none", rt, {3}, [](const Eigen::VectorXd& v) { return v[0]; });
  EXPECT_EQ(none.missing, 1);
  EXPECT_TRUE(std::isnan(none.rms));
}

TEST(EvaluateEstimators, scores_every_estimator_and_the_locus_based_ones_read_true) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const ThermalModel m = test::small_model(p, 700, 1700);
  const Locus locus = make_locus(m.camera, 700, 1700, 1);
  RateTable rt;
  rt.temperatures_c = {850, 1150.5, 1450};
  for (double t : rt.temperatures_c) {
    const Eigen::VectorXd r = m.camera.rates(t);
    for (double peak_dn : {120.0, 180.0}) {
      const double exposure_us = peak_dn / r.maxCoeff() * 1e6;
      rt.settings.push_back(setting(t, exposure_us, r * exposure_us * 1e-6));
    }
  }
  const std::vector<EstimatorScore> table = evaluate_estimators(m, rt, locus, m.camera, 1);
  std::vector<std::string> names;
  for (const auto& s : table) names.push_back(s.name);
  EXPECT_EQ(names, (std::vector<std::string>{"MLP", "likelihood fit", "Ohno, optimised QE",
                                             "Ohno, datasheet QE", "two-colour"}));
  for (const auto& s : table) {
    SCOPED_TRACE(s.name);
    EXPECT_EQ(s.true_c.size() + static_cast<std::size_t>(s.missing), 6u);
  }
  // Noise-free rates of the camera whose locus the estimators invert.
  for (int i : {1, 2, 3}) {
    SCOPED_TRACE(table[static_cast<std::size_t>(i)].name);
    EXPECT_EQ(table[static_cast<std::size_t>(i)].missing, 0);
    EXPECT_LT(table[static_cast<std::size_t>(i)].rms, 0.5);
  }
  EXPECT_LT(table[0].rms, 20);  // a small network: only roughly right
}

}  // namespace
}  // namespace pyrocam
