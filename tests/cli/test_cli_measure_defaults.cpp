// pyrocam-calib measure reads as ratiotemp does by default: method auto, and pixels with dim or
// saturated bands read from the rest where that is safe (partial-bands safe). A 5x5 plate
// exposed at 0.6 times the usual exposure has some band below the dim threshold in every pixel:
// with every band required nothing reads. A frame whose ROI reads little says why.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "cli_support.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/runtime/model.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;

// Runs pyrocam-calib (not quiet); returns its standard error, empty when it failed.
std::string calib_stderr(const std::string& args, const fs::path& log) {
  const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' " + args +
                              " < /dev/null > /dev/null 2> '" + log.string() + "'";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) && WEXITSTATUS(status) == 0 ? test::read_text(log) : std::string();
}

TEST(CliMeasureDefaults, a_dim_5x5_plate_reads_from_its_good_bands_by_default) {
  const fs::path model = test_model("test-model-nir5x5.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-partial"};
  write_plate(dir / "bright", "nir5x5-reference", 1, 900, 100);
  write_plate(dir / "plate", "nir5x5-reference", 1, 900, 100, 0.6);
  const std::string base = "measure --model " + q(model) + " --dataset " + q(dir / "plate");
  ASSERT_EQ(calib(base + " --out " + q(dir / "default")), 0);
  ASSERT_EQ(calib(base + " --partial-bands off --out " + q(dir / "off")), 0);
  ASSERT_EQ(calib(base + " --method likelihood --allow-partial --out " + q(dir / "any")), 0);
  ASSERT_EQ(calib("measure --model " + q(model) + " --dataset " + q(dir / "bright") +
                  " --partial-bands off --out " + q(dir / "bright-off")),
            0);
  const auto by_default = first_stats_row(dir / "default"), off = first_stats_row(dir / "off"),
             any = first_stats_row(dir / "any"), bright = first_stats_row(dir / "bright-off");
  EXPECT_EQ(std::stod(off.at("valid_fraction")), 0.0) << "some band is dim in every pixel";
  // As many as every band reads at the usual exposure (the ROI's outer ring of macro-pixels
  // has no reading either way: its kernel reaches the cold background).
  EXPECT_GT(std::stod(bright.at("valid_fraction")), 0.5);
  EXPECT_GE(std::stod(by_default.at("valid_fraction")),
            0.95 * std::stod(bright.at("valid_fraction")));
  // In range (the test model's furnace reaches 1100 degC): a degree or two from the truth.
  EXPECT_LT(std::abs(std::stod(by_default.at("truth_median_error_c"))), 3.0);
  // The plate's 5x5 bands include monotonic pairs: safe reads what any does.
  EXPECT_EQ(by_default.at("median_c"), any.at("median_c"));
  EXPECT_EQ(by_default.at("valid_fraction"), any.at("valid_fraction"));
  EXPECT_NE(calib(base + " --partial-bands some --out " + q(dir / "bad")), 0);
}

TEST(CliMeasureDefaults, the_default_method_is_ratiotemps_auto) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-auto"};
  write_plate(dir / "plate", "rgb-reference", 1, 1000, 64);
  const std::string base = "measure --model " + q(model) + " --dataset " + q(dir / "plate");
  ASSERT_EQ(calib(base + " --out " + q(dir / "default")), 0);
  ASSERT_EQ(calib(base + " --method auto --out " + q(dir / "auto")), 0);
  ASSERT_EQ(calib(base + " --method mlp --out " + q(dir / "mlp")), 0);
  EXPECT_EQ(test::read_text(dir / "default" / "0000_temperature.png"),
            test::read_text(dir / "auto" / "0000_temperature.png"));
  // The table reads the network to within its tolerance, not to the bit.
  EXPECT_NE(test::read_text(dir / "default" / "0000_temperature.png"),
            test::read_text(dir / "mlp" / "0000_temperature.png"));
}

TEST(CliMeasureDefaults, a_frame_that_reads_little_says_why) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-why"};
  write_plate(dir / "good", "rgb-reference", 1, 1000, 64);
  write_plate(dir / "bright", "rgb-reference", 1, 1000, 64, 50);  // far beyond saturation
  write_plate(dir / "dark", "rgb-reference", 1, 1000, 64, 0.02);  // far below the dim threshold
  const auto run = [&](const std::string& data) {
    // Bilinear: matched's kernels at the saturated plate's edge mix saturated samples with
    // samples without light into bands of neither kind (NaN), which the counts leave out.
    return calib_stderr("measure --demosaic bilinear --model " + q(model) + " --dataset " +
                            q(dir / data) + " --out " + q(dir / (data + "-t")),
                        dir / (data + ".log"));
  };
  const std::string bright = run("bright"), dark = run("dark"), good = run("good");
  const auto pixels = first_stats_row(dir / "good-t").at("pixels");
  EXPECT_NE(bright.find("0 of " + pixels + " pixels of the ROI read; " + pixels +
                        " have a band saturated or at the saturation level (shorten the exposure), "
                        "0 a band below"),
            std::string::npos)
      << bright;
  EXPECT_NE(dark.find("0 of " + pixels +
                      " pixels of the ROI read; 0 have a band saturated or at the saturation "
                      "level (shorten the exposure), " +
                      pixels + " a band below or near the dim threshold"),
            std::string::npos)
      << dark;
  EXPECT_EQ(good.find("pixels of the ROI read"), std::string::npos) << good;
  EXPECT_EQ(bright.find("at once"), std::string::npos) << bright;

  // Red saturated and green 2 DN above dark in every cell: no exposure reads these, and neither
  // "shorten" nor "lengthen" would; said as such, and counted in neither.
  cv::Mat frame(64, 64, CV_8U, cv::Scalar(52)), dark_frame(64, 64, CV_8U, cv::Scalar(50));
  for (int y = 0; y < 64; y += 2)
    for (int x = 0; x < 64; x += 2)
      frame.at<std::uint8_t>(y, x) = 255, frame.at<std::uint8_t>(y + 1, x + 1) = 150;
  write_raw_image(dir / "both.pgm", frame);
  write_raw_image(dir / "dark.pgm", dark_frame);
  const std::string both =
      calib_stderr("measure --model " + q(model) + " --frame " + q(dir / "both.pgm") + " --dark " +
                       q(dir / "dark.pgm") + " --pattern rggb --out " + q(dir / "both-t"),
                   dir / "both.log");
  EXPECT_NE(both.find(" pixels of the ROI read; 0 have a band saturated"), std::string::npos)
      << both;
  EXPECT_NE(both.find(", 0 a band below"), std::string::npos) << both;
  EXPECT_NE(both.find("one band saturated and another dim at once (no one exposure reads them"),
            std::string::npos)
      << both;
}

// --uncertainty adds the ROI median's own expanded uncertainty to stats.csv: the systematic
// terms whole (the median has them too) with the noise of many readings, so more than the
// systematic terms alone and less than a single reading's.
// stats.csv has the frame's peak as ratiotemp's peak-c (the largest median of 5x5 windows at
// least half read) with the truth's by the same rule. On a 1000 degC plate the peak is the
// largest of some 1 300 window medians, which scatter by about 8 degC (measured on this plate),
// so it lies a few of those above the plate (17 degC here): 5 sd (40 degC) is passed by one of
// 1 300 independent normal medians with probability 1300 x 2.9e-7 = 4e-4, and correlated ones
// pass it less often; and it lies above the ROI's median reading. A plate whose every band
// saturates has no peak, and a saturated band says the peak would be a lower bound, as does a
// plate hotter than the model's range.
TEST(CliMeasureDefaults, stats_have_the_peak_and_the_truths) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-peak"};
  write_plate(dir / "good", "rgb-reference", 1, 1000, 64);
  write_plate(dir / "bright", "rgb-reference", 1, 1000, 64, 50);
  const std::string base = "measure --model " + q(model) + " --dataset ";
  ASSERT_EQ(calib(base + q(dir / "good") + " --out " + q(dir / "good-t")), 0);
  ASSERT_EQ(calib(base + q(dir / "bright") + " --out " + q(dir / "bright-t")), 0);
  const auto good = first_stats_row(dir / "good-t"), bright = first_stats_row(dir / "bright-t");
  ASSERT_FALSE(good.at("peak_c").empty());
  EXPECT_NEAR(std::stod(good.at("truth_peak_c")), 1000, 0.1);
  EXPECT_NEAR(std::stod(good.at("truth_max_c")), 1000, 0.1);
  EXPECT_GE(std::stod(good.at("peak_c")), std::stod(good.at("median_c")));
  EXPECT_LE(std::stod(good.at("peak_c")), 1040);
  EXPECT_NEAR(std::stod(good.at("peak_error_c")),
              std::stod(good.at("peak_c")) - std::stod(good.at("truth_peak_c")), 0.002);
  EXPECT_EQ(good.at("peak_lower_bound"), "false");
  // What the model says a reading at the peak may be off by (ratiotemp's peak-u-sys-c): the
  // error of this plate, near the datasheet, within it; none on a lower bound.
  const double u_sys = std::stod(good.at("peak_u_sys_c"));
  EXPECT_GT(u_sys, 0);
  EXPECT_LT(u_sys, 50);
  EXPECT_LT(std::abs(std::stod(good.at("median_c")) - 1000), u_sys);
  EXPECT_TRUE(bright.at("peak_u_sys_c").empty());
  const int x = std::stoi(good.at("peak_x")), y = std::stoi(good.at("peak_y"));
  EXPECT_TRUE(x >= 2 && x < 62 && y >= 2 && y < 62) << x << "," << y;
  EXPECT_TRUE(bright.at("peak_c").empty());
  EXPECT_TRUE(bright.at("peak_error_c").empty());
  EXPECT_EQ(bright.at("peak_lower_bound"), "true");
  EXPECT_EQ(calib(base + q(dir / "good") + " --peak-window 4 --out " + q(dir / "even")), 2);
  // A plate well above the model's range (3500 degC) reads nowhere: its pixels are counted as
  // above it (a 23 x 23 plate, less those at its edge), and the peak is a lower bound.
  EXPECT_EQ(good.at("above_range"), "0");
  write_plate(dir / "hot", "rgb-reference", 1, 4000, 64);
  ASSERT_EQ(calib(base + q(dir / "hot") + " --out " + q(dir / "hot-t")), 0);
  const auto hot = first_stats_row(dir / "hot-t");
  EXPECT_EQ(std::stod(hot.at("valid_fraction")), 0);
  EXPECT_GE(std::stoi(hot.at("above_range")), 400);
  EXPECT_LE(std::stoi(hot.at("above_range")), 64 * 64 * 36 / 100 + 100);
  EXPECT_EQ(hot.at("peak_lower_bound"), "true");
  EXPECT_TRUE(hot.at("peak_u_sys_c").empty());
}

TEST(CliMeasureDefaults, uncertainty_gives_the_rois_median_its_own) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-median-u"};
  write_plate(dir / "plate", "rgb-reference", 1, 1000, 64);
  const std::string base = "measure --model " + q(model) + " --dataset " + q(dir / "plate");
  ASSERT_EQ(calib(base + " --uncertainty --out " + q(dir / "u")), 0);
  ASSERT_EQ(calib(base + " --out " + q(dir / "plain")), 0);
  EXPECT_TRUE(first_stats_row(dir / "plain").at("median_u_c").empty());
  const auto row = first_stats_row(dir / "u");
  const double u = std::stod(row.at("median_u_c")), median = std::stod(row.at("median_c"));
  const ThermalModel m = load_model(model.string());
  EXPECT_GE(u, m.uncertainty.coverage_factor * m.uncertainty.systematic_u_c(median) - 0.01);
  // A single reading's: the per-pixel image (0.1 K units, 0 = no reading).
  const cv::Mat image = read_raw_image(dir / "u" / "0000_uncertainty.png");
  std::vector<double> each;
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x)
      if (image.at<std::uint16_t>(y, x) > 0) each.push_back(0.1 * image.at<std::uint16_t>(y, x));
  ASSERT_GT(each.size(), 100u);
  std::nth_element(each.begin(), each.begin() + static_cast<long>(each.size() / 2), each.end());
  std::printf("median_u_c %.1f degC; one reading's, median over the ROI, %.1f degC\n", u,
              each[each.size() / 2]);
  EXPECT_LT(u, each[each.size() / 2]);
  // In range the median reads well within it.
  EXPECT_LE(std::abs(std::stod(row.at("truth_median_error_c"))), u);
}

// calibrate without --profile: a dataset whose mosaic.txt says 5x5 is the shipped 5x5 camera's
// (it says so), not the colour default, which would refuse it; a --profile given still decides.
TEST(CliCalibrateDefaults, a_5x5_dataset_without_a_profile_is_the_shipped_5x5_cameras) {
  ScratchDir dir{"cli-5x5-profile"};
  ASSERT_EQ(
      calib("simulate campaign --profile nir5x5-reference --temperatures 900 950 1000 1050 1100 "
            "--exposures 12 --frames 1 --size 50x50 --roi-area 600 --out " +
            q(dir / "furnace")),
      0);
  const std::string fast = " --epochs 1 --polish-iterations 0 --mc-refits 0 --no-prebuilt-table";
  const std::string err = calib_stderr(
      "calibrate --dataset " + q(dir / "furnace") + " --out " + q(dir / "model.json") + fast,
      dir / "calibrate.log");
  EXPECT_NE(err.find("the dataset's mosaic is 5x5 and no --profile was given: using the shipped "
                     "nir5x5-reference"),
            std::string::npos)
      << test::read_text(dir / "calibrate.log");
  EXPECT_EQ(load_model((dir / "model.json").string()).profile().name, "nir5x5-reference");
  EXPECT_NE(calib("calibrate --dataset " + q(dir / "furnace") + " --profile rgb-reference --out " +
                  q(dir / "colour.json") + fast),
            0);
  EXPECT_FALSE(fs::exists(dir / "colour.json"));
}

// calibrate --thermocouple-tolerance: the furnace's thermocouple as the user knows it (a
// calibrated one is far better than class 1), kept in the model and, without refits, its
// rectangular standard uncertainty is the calibration term. A tolerance that is no number from
// 0 to 50 degC is bad usage, named, and no model is written.
TEST(CliCalibrateDefaults, the_thermocouple_tolerance_is_the_users) {
  ScratchDir dir{"cli-thermocouple"};
  ASSERT_EQ(calib("simulate campaign --temperatures 900 950 1000 1050 1100 --exposures 12 "
                  "--frames 1 --size 64x64 --roi-area 600 --out " +
                  q(dir / "furnace")),
            0);
  const std::string calibrate = "calibrate --dataset " + q(dir / "furnace") +
                                " --epochs 1 --polish-iterations 0 --mc-refits 0 "
                                "--no-prebuilt-table --thermocouple-tolerance ";
  ASSERT_EQ(calib(calibrate + "1.5 --out " + q(dir / "model.json")), 0);
  const ThermalModel m = load_model((dir / "model.json").string());
  EXPECT_EQ(m.uncertainty.thermocouple_tolerance_c, 1.5);
  ASSERT_FALSE(m.uncertainty.u_calibration_c.empty());
  for (double u : m.uncertainty.u_calibration_c) EXPECT_NEAR(u, 1.5 / std::sqrt(3.0), 1e-9);
  for (const std::string bad : {"-1", "51", "nan", "warm"}) {
    const fs::path log = dir / "bad.log", out = dir / "bad.json";
    const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' -q " +
                                calibrate + bad + " --out " + q(out) +
                                " < /dev/null > /dev/null 2> " + q(log);
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status)) << bad;
    EXPECT_EQ(WEXITSTATUS(status), 2) << bad;
    EXPECT_NE(test::read_text(log).find("--thermocouple-tolerance"), std::string::npos)
        << bad << ": " << test::read_text(log);
    EXPECT_FALSE(fs::exists(out)) << bad;
  }
}

}  // namespace
}  // namespace pyrocam::test
