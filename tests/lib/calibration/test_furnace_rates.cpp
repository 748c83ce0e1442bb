// Rate extraction of a furnace campaign: the slopes against the true signal rates, how points
// are classified, the lines' offsets (RateOffsets: one per band shared by every temperature,
// unless the temperatures' own offsets differ beyond the noise, as when the black level moves
// between the steps of a campaign) and bad input. References: test_rate_extraction.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "pyrocam/calibration/calibrate.h"
#include "pyrocam/calibration/rate_extraction.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/spectrum.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;

class Campaign : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("calib");
    profile_ = new CameraProfile(load_profile_by_name("rgb-reference"));
    true_qe_ = new Eigen::MatrixXd(write_campaign(dir_->path(), 0));
  }
  // The fixture's campaign (a typical unit, 5 temperatures, 30 exposures, 2 frames, a 48x48
  // frame), its furnace frames' black level drifting by `drift_dn`; returns the unit's QE.
  static Eigen::MatrixXd write_campaign(const std::filesystem::path& folder, double drift_dn) {
    Simulator camera(*profile_, UnitPerturbation{"typical", 4});
    CampaignSettings s;
    s.temperatures_c = {700, 800, 900, 1000, 1100};
    s.exposure_count = 30;
    s.frames_per_setting = 2;
    s.width = 48;
    s.height = 48;
    s.roi_area_px = 900;
    s.furnace_error_sigma_c = 0;  // rates are compared with the nominal temperatures' below
    s.black_level_drift_dn = drift_dn;
    write_furnace_campaign(folder, camera, s);
    return camera.system_qe();
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete profile_;
    delete true_qe_;
  }
  static ScratchDir* dir_;
  static CameraProfile* profile_;
  static Eigen::MatrixXd* true_qe_;
};
ScratchDir* Campaign::dir_ = nullptr;
CameraProfile* Campaign::profile_ = nullptr;
Eigen::MatrixXd* Campaign::true_qe_ = nullptr;

TEST_F(Campaign, slopes_recover_the_true_signal_rates) {
  const RateTable rt = extract_rates(Dataset::open(dir_->path()), *profile_);
  ASSERT_EQ(rt.temperatures_c.size(), 5u);
  const Eigen::MatrixXd r = rt.rates();
  for (std::size_t t = 0; t < 5; ++t) {
    const Eigen::VectorXd truth =
        signal_rates(*profile_, *true_qe_, celsius_to_kelvin(rt.temperatures_c[t]));
    for (int b = 0; b < 3; ++b) {
      SCOPED_TRACE(std::to_string(rt.temperatures_c[t]) + " " + profile_->band_names[b]);
      EXPECT_NEAR(r(t, b) / truth[b], 1.0, 0.01);
      EXPECT_GT(rt.fits[t][b].r_squared, 0.999);
      EXPECT_GE(rt.fits[t][b].points, 3);
    }
  }
  // The sweep runs from dim to saturated at every temperature.
  int saturated = 0, dim = 0;
  for (const auto& st : rt.status)
    for (PointStatus s : st)
      saturated += s == PointStatus::kSaturated, dim += s == PointStatus::kDim;
  EXPECT_GT(saturated, 20);
  EXPECT_GT(dim, 20);
}

TEST_F(Campaign, saturation_is_judged_on_raw_values) {
  // 235 raw with a 50 DN dark is only 185 DN net, yet above the 240 DN raw limit it is not:
  // 245 raw is saturated even though net is 195.
  EXPECT_EQ(classify_point(*profile_, 245, 195, 0, 1e-3), PointStatus::kSaturated);
  EXPECT_EQ(classify_point(*profile_, 235, 185, 0, 1e-3), PointStatus::kUsed);
  EXPECT_EQ(classify_point(*profile_, 235, 185, 0.01, 1e-3), PointStatus::kSaturated);
  EXPECT_EQ(classify_point(*profile_, 58, 8, 0, 1e-3), PointStatus::kDim);
}

TEST_F(Campaign, rejects_a_profile_whose_mosaic_does_not_fit_the_images_n) {
  const CameraProfile nir = load_profile_by_name("nir5x5-reference");
  try {
    extract_rates(Dataset::open(dir_->path()), nir);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not whole 5x5 mosaic periods"), std::string::npos)
        << e.what();
  }
}

TEST_F(Campaign, rejects_a_profile_of_another_bit_depth_n) {
  CameraProfile p16 = *profile_;
  p16.bit_depth = 12;
  try {
    extract_rates(Dataset::open(dir_->path()), p16);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("describes a 12-bit camera"), std::string::npos)
        << e.what();
  }
}

// A 10-bit camera's frames saved left-justified in 16 bits (a common export setting) would read
// as saturated or 64 times too bright: refused, naming the file.
TEST(CalibrationData, rejects_frames_above_the_cameras_full_scale_n) {
  ScratchDir dir("leftjustified");
  CameraProfile p10 = load_profile_by_name("rgb-reference");
  p10.bit_depth = 10;
  Simulator camera(p10, UnitPerturbation{"datasheet", 1});
  CampaignSettings s;
  s.temperatures_c = {900, 1000};
  s.exposure_count = 3;
  s.frames_per_setting = 1;
  s.width = s.height = 32;
  s.roi_area_px = 300;
  write_furnace_campaign(dir.path(), camera, s);
  const Dataset d = Dataset::open(dir.path());
  // The brightest frame, whose shifted samples leave the 10-bit range.
  std::filesystem::path frame;
  double brightest = 0;
  for (const auto& g : d.frames())
    for (const auto& f : g.files) {
      double hi = 0;
      cv::minMaxLoc(read_raw_image(f), nullptr, &hi);
      if (hi > brightest) brightest = hi, frame = f;
    }
  ASSERT_LE(brightest, 1023);
  ASSERT_GT(brightest * 64, 1023);
  write_raw_image(frame, read_raw_image(frame) * 64);
  try {
    extract_rates(Dataset::open(dir.path()), p10);
    ADD_FAILURE() << "read left-justified frames";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(frame.string()), std::string::npos) << what;
    EXPECT_NE(what.find("above the 1023 DN full scale of a 10-bit camera"), std::string::npos)
        << what;
  }
}

TEST_F(Campaign, calibrate_rejects_data_outside_the_models_temperature_range_n) {
  CalibrationOptions options;
  options.min_temperature_c = 800;  // the campaign starts at 700 degC
  options.mlp.epochs = 1;
  try {
    calibrate(Dataset::open(dir_->path()), *profile_, options);
    ADD_FAILURE() << "calibrated data outside the model's range";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("700"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("800-3500"), std::string::npos) << e.what();
  }
}

TEST(CalibrationData, rejects_a_band_without_usable_points_n) {
  ScratchDir dir("nousable");
  Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"datasheet", 1});
  CampaignSettings s;
  s.temperatures_c = {700, 710};
  s.exposure_count = 2;  // 100 and 126 us: everything is dim at 700 degC
  s.frames_per_setting = 1;
  s.width = s.height = 32;
  s.roi_area_px = 300;
  write_furnace_campaign(dir.path(), camera, s);
  try {
    extract_rates(Dataset::open(dir.path()), camera.profile());
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("band R has no temperature with 2 usable points"),
              std::string::npos)
        << e.what();
  }
}

TEST(FitLine, recovers_slope_intercept_and_r_squared) {
  const SlopeFit f = fit_line({100, 200, 400}, {12, 22, 42});
  EXPECT_NEAR(f.rate_dn_per_s, 0.1 * 1e6, 1e-6);
  EXPECT_NEAR(f.intercept_dn, 2, 1e-9);
  EXPECT_NEAR(f.r_squared, 1, 1e-12);
  EXPECT_TRUE(std::isnan(fit_line({100}, {12}).rate_dn_per_s));
}

// The largest |rate / true rate - 1| over a table of the fixture's campaign (or one like it).
double worst_rate_error(const RateTable& rt, const CameraProfile& profile,
                        const Eigen::MatrixXd& true_qe) {
  const Eigen::MatrixXd r = rt.rates();
  double worst = 0;
  for (std::size_t t = 0; t < rt.temperatures_c.size(); ++t) {
    const Eigen::VectorXd truth =
        signal_rates(profile, true_qe, celsius_to_kelvin(rt.temperatures_c[t]));
    for (int b = 0; b < profile.band_count(); ++b)
      worst = std::max(worst, std::abs(r(static_cast<Eigen::Index>(t), b) / truth[b] - 1));
  }
  return worst;
}

TEST_F(Campaign, darks_that_match_give_one_offset_per_band) {
  const RateTable rt = extract_rates(Dataset::open(dir_->path()), *profile_);
  // At the test's level of 0.99 a campaign whose darks match is split by the test once in 100
  // noise draws; this one is seeded.
  EXPECT_TRUE(rt.offsets.common) << rate_offsets_summary(rt.offsets);
  EXPECT_EQ(rt.offsets.degrees_of_freedom, 3 * (5 - 1));
  EXPECT_LE(rt.offsets.chi2, rt.offsets.threshold);
  EXPECT_NEAR(rt.offsets.threshold, 26.2, 0.3);  // chi2 with 12 degrees of freedom, 99 %
  for (int b = 0; b < 3; ++b) {
    EXPECT_LT(std::abs(rt.offsets.common_offset_dn[b]), 0.5) << profile_->band_names[b];
    for (const auto& row : rt.fits)
      EXPECT_DOUBLE_EQ(row[b].intercept_dn, rt.offsets.common_offset_dn[b]);
  }
  EXPECT_LT(worst_rate_error(rt, *profile_, *true_qe_), 0.01);
  const std::string words = rate_offsets_summary(rt.offsets);
  std::printf("darks that match: %s, worst rate error %.2g\n", words.c_str(),
              worst_rate_error(rt, *profile_, *true_qe_));
  EXPECT_EQ(words.rfind("one per band (chi2 ", 0), 0u) << words;
  EXPECT_NE(words.find("on 12 degrees of freedom"), std::string::npos) << words;
  // Asked for: no test in the words, the other fits.
  ExtractOptions own;
  own.offsets = RateOffsets::kPerStep;
  const RateTable per_step = extract_rates(Dataset::open(dir_->path()), *profile_, own);
  EXPECT_FALSE(per_step.offsets.common);
  EXPECT_EQ(rate_offsets_summary(per_step.offsets), "one per temperature (as asked)");
  EXPECT_NE(per_step.fits[0][0].intercept_dn, per_step.fits[1][0].intercept_dn);
  EXPECT_NE(per_step.rates()(2, 1), rt.rates()(2, 1));
}

TEST_F(Campaign, a_black_level_that_drifts_keeps_one_offset_per_step) {
  // The same campaign with the furnace frames' black level drifting from the darks' to 3 DN
  // above it over the five steps: far beyond the noise of an ROI mean (about 0.05 DN here).
  ScratchDir drifted("offsets-drift");
  write_campaign(drifted.path(), 3);
  const RateTable rt = extract_rates(Dataset::open(drifted.path()), *profile_);
  ExtractOptions common;
  common.offsets = RateOffsets::kCommon;
  const double forced = worst_rate_error(
      extract_rates(Dataset::open(drifted.path()), *profile_, common), *profile_, *true_qe_);
  std::printf("black level drifted: %s, worst rate error %.2g (%.2g with one offset per band)\n",
              rate_offsets_summary(rt.offsets).c_str(), worst_rate_error(rt, *profile_, *true_qe_),
              forced);
  EXPECT_FALSE(rt.offsets.common);
  EXPECT_GT(rt.offsets.chi2, 10 * rt.offsets.threshold);
  EXPECT_EQ(rate_offsets_summary(rt.offsets).rfind("one per temperature", 0), 0u);
  EXPECT_LT(worst_rate_error(rt, *profile_, *true_qe_), 0.01);  // each line takes its own offset
  // One offset per band forced: the drifted steps' slopes take up the drift.
  EXPECT_GT(forced, 2 * worst_rate_error(rt, *profile_, *true_qe_));
}

TEST(FitLinesCommonOffset, recovers_each_slope_and_the_shared_offset) {
  // Three sweeps of 0.1, 0.05 and 0.2 DN/us over a dark left 1.5 DN high; one with one point.
  const std::vector<std::vector<double>> x = {
      {100, 200, 400}, {300, 600, 900, 1200}, {50, 80}, {70}};
  std::vector<std::vector<double>> y(x.size());
  const double slope[] = {0.1, 0.05, 0.2, 0.3};
  for (std::size_t t = 0; t < x.size(); ++t)
    for (double e : x[t]) y[t].push_back(1.5 + slope[t] * e);
  const std::vector<SlopeFit> f = fit_lines_common_offset(x, y);
  ASSERT_EQ(f.size(), 4u);
  for (std::size_t t = 0; t < 3; ++t) {
    EXPECT_NEAR(f[t].rate_dn_per_s, slope[t] * 1e6, 1e-6);
    EXPECT_NEAR(f[t].intercept_dn, 1.5, 1e-9);
    EXPECT_NEAR(f[t].r_squared, 1, 1e-12);
    EXPECT_EQ(f[t].points, static_cast<int>(x[t].size()));
  }
  EXPECT_TRUE(std::isnan(f[3].rate_dn_per_s));
  EXPECT_EQ(f[3].points, 1);
}

}  // namespace
}  // namespace pyrocam
