// The summary stage: the verdict line, the JSON summary and the provenance.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "pyrocam/calibration/calibrate.h"
#include "pyrocam/calibration/calibration_summary.h"
#include "pyrocam/core/error.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

TEST(RmsFinite, skips_nan_and_is_nan_with_nothing_finite) {
  Eigen::MatrixXd m(2, 2);
  m << 3, NAN, -4, INFINITY;
  EXPECT_NEAR(rms_finite(m), std::sqrt(12.5), 1e-12);
  EXPECT_TRUE(std::isnan(rms_finite(Eigen::MatrixXd::Constant(2, 3, NAN))));
}

CalibrationOutcome small_outcome() {
  CalibrationOutcome o;
  o.rate_residual_optimised = Eigen::MatrixXd::Constant(2, 3, 0.01);
  o.rate_residual_datasheet = Eigen::MatrixXd::Constant(2, 3, -0.05);
  o.rate_residual_datasheet(1, 1) = NAN;
  EstimatorScore mlp;
  mlp.name = "MLP";
  mlp.true_c = {1000, 1100};
  mlp.estimate_c = {1001, 1099.5};
  mlp.rms = 0.79;
  o.table4 = {mlp};
  o.rates.status = {{PointStatus::kUsed, PointStatus::kSaturated, PointStatus::kDim},
                    {PointStatus::kSaturated, PointStatus::kSaturated, PointStatus::kUsed}};
  o.warnings = {"1100 degC band R: 1 usable point"};
  o.model.qe_solver = "regularised";
  return o;
}

TEST(CalibrationVerdict, says_residuals_the_mlps_rms_skipped_points_and_warnings) {
  EXPECT_EQ(calibration_verdict(small_outcome()),
            "rate residual 1.00 % rms (datasheet QE: 5.00 %); MLP 0.79 degC rms on 2 "
            "calibration settings; 3 band means of the sweeps skipped as saturated, 1 as dim; 1 "
            "warning");
  CalibrationOutcome no_readings = small_outcome();
  no_readings.table4[0].rms = NAN;
  no_readings.warnings.clear();
  EXPECT_EQ(calibration_verdict(no_readings),
            "rate residual 1.00 % rms (datasheet QE: 5.00 %); 3 band means of the sweeps skipped "
            "as saturated, 1 as dim");
}

// A sound outcome says nothing; furnace rates the QE does not explain (a dataset in kelvin) or
// settings the network misreads are said; no setting read back at all is refused.
TEST(CalibrationQuality, warns_on_data_the_model_does_not_explain_n) {
  EXPECT_TRUE(calibration_quality_warnings(small_outcome()).empty());
  CalibrationOutcome kelvin = small_outcome();
  kelvin.rate_residual_optimised(0, 1) = 0.3;  // rms 12.3 %
  kelvin.table4[0].rms = 291;
  const auto w = calibration_quality_warnings(kelvin);
  ASSERT_EQ(w.size(), 2u);
  EXPECT_NE(w[0].find("the fitted QE leaves 12.3 % rms of the furnace signal rates unexplained"),
            std::string::npos)
      << w[0];
  EXPECT_NE(w[1].find("reads its own furnace settings 291.0 degC rms off (MLP, 2 settings"),
            std::string::npos)
      << w[1];
  CalibrationOutcome unread = small_outcome();
  unread.table4[0].true_c.clear();
  unread.table4[0].rms = NAN;
  try {
    calibration_quality_warnings(unread);
    ADD_FAILURE() << "accepted a model that read no furnace setting back";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("reads none of the furnace settings back"),
              std::string::npos)
        << e.what();
  }
}

TEST(OutcomeSummary, holds_the_verdict_solver_residuals_and_table4) {
  CalibrationOutcome o = small_outcome();
  o.verdict = calibration_verdict(o);
  o.solvers.push_back({"regularised", 0.01, 0.02, 0.03, 1.5, "dropped", "2 x nominal",
                       "4 x nominal counted; 1 x nominal counted"});
  const nlohmann::json j = outcome_summary(o);
  EXPECT_EQ(j["verdict"], o.verdict);
  EXPECT_EQ(j["qe_solver"], "regularised");
  EXPECT_EQ(j["solvers"][0]["held_out_residual_rms"], 0.02);
  EXPECT_EQ(j["solvers"][0]["leak_terms"], "dropped");
  EXPECT_EQ(j["solvers"][0]["prior_widths"], "2 x nominal");
  EXPECT_EQ(j["solvers"][0]["prior_sensitivity"], "4 x nominal counted; 1 x nominal counted");
  EXPECT_NEAR(j["rate_residual_rms"]["datasheet"].get<double>(), 0.05, 1e-15);
  EXPECT_EQ(j["table4"][0]["estimator"], "MLP");
  EXPECT_EQ(j["table4"][0]["n"], 2);
  EXPECT_EQ(j["warnings"].size(), 1u);
}

TEST(AboveCalibrationSummary, names_the_pair_where_it_reads_and_nothing_without_a_top) {
  ThermalModel m;
  const CameraProfile p = load_profile_by_name("rgb-reference");
  m.camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(3)};
  EXPECT_EQ(above_calibration_summary(m), "");  // no calibrated top: every band everywhere
  m.calibrated_up_to_c = 1100;
  const std::string s = above_calibration_summary(m);
  EXPECT_NE(s.find("above 1100 degC"), std::string::npos) << s;
  EXPECT_NE(s.find("ratio of R and G"), std::string::npos) << s;
  EXPECT_NE(s.find("B's 0.3"), std::string::npos) << s;  // blue overlaps least
  // The blend ends 200 degC above the calibrated top (the pair as precise as the three bands
  // there) and starts 200 degC below the range's (500-3500 degC).
  EXPECT_NE(s.find("alone from 1300 to 3300 degC"), std::string::npos) << s;
}

TEST(ModelProvenance, names_the_tool_profile_dataset_and_seed) {
  test::ScratchDir dir("provenance");
  const CameraProfile p = load_profile_by_name("rgb-reference");
  Simulator camera(p, UnitPerturbation{"datasheet", 1});
  CampaignSettings s;
  s.temperatures_c = {900, 1000};
  s.exposure_count = 2;
  s.frames_per_setting = 1;
  s.width = s.height = 16;
  s.roi_area_px = 60;
  write_furnace_campaign(dir.path(), camera, s);
  const Dataset d = Dataset::open(dir.path());
  const nlohmann::json j = model_provenance(d, p, 42);
  EXPECT_EQ(j["tool"], "pyrocam-calib");
  EXPECT_EQ(j["profile_name"], "rgb-reference");
  EXPECT_EQ(j["seed"], 42);
  EXPECT_EQ(j["dataset_path"], std::filesystem::absolute(dir.path()).string());
  // The manifest's text and the frame size, hashed.
  std::ifstream in(dir / "manifest.csv");
  const std::string manifest(std::istreambuf_iterator<char>(in), {});
  EXPECT_EQ(j["dataset_manifest_fnv1a64"], fnv1a_hex(manifest + "16x16"));
  EXPECT_EQ(j["created_utc"].get<std::string>().size(), 20u);  // e.g. 2024-01-31T12:00:00Z
}

}  // namespace
}  // namespace pyrocam
