// pyrocam-calib measure on datasets and single frames: what it refuses (a model of another
// mosaic, a pattern that contradicts the dataset, an ROI or dark that does not fit the frames, a
// folder that holds a measurement) and what its options do to the readings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <sstream>
#include <string>
#include <utility>

#include "cli_support.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::read_text;
using test::run_tool;
using test::ScratchDir;
using test::test_model;
using test::ToolRun;
using test::write_text;

std::string quoted(const std::filesystem::path& p) { return test::q(p); }

TEST(Cli, measure_rejects_a_model_path_that_is_a_directory_n) {
  ScratchDir dir("cli");
  std::filesystem::create_directory(dir / "model.json");
  write_raw_image(dir / "f.pgm", cv::Mat::zeros(8, 8, CV_8U));
  const ToolRun r = run_tool("measure --model " + quoted(dir / "model.json") + " --frame " +
                                 quoted(dir / "f.pgm") + " --dark " + quoted(dir / "f.pgm") +
                                 " --pattern rggb --out " + quoted(dir / "out"),
                             dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("model.json: model file is a directory"), std::string::npos) << r.err;
}

TEST(Cli, measure_rejects_a_frame_without_pattern_n) {
  ScratchDir dir("cli");
  const ToolRun r = run_tool("measure --model m.json --frame f.pgm --dark d.pgm --out o", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--frame needs --pattern"), std::string::npos) << r.err;
}

TEST(Cli, measure_rejects_an_unknown_pattern_n) {
  ScratchDir dir("cli");
  const ToolRun r =
      run_tool("measure --model m.json --frame f.pgm --dark d.pgm --pattern rgbg --out o", dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("mosaic layout 'rgbg' is not rggb, bggr, grbg, gbrg"), std::string::npos)
      << r.err;
}

// A 5x5 model on a Bayer frame read a 1200 degC plate as 652 degC.
class CliMeasure : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(std::filesystem::exists(test_model("test-model-nir5x5.json")))
        << test::kNoTestModels;
    Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 6});
    SceneSequenceSettings s;
    s.kind = SceneKind::kPlate;
    s.temperatures_c = {1200};
    s.width = 100;
    s.height = 100;
    write_scene_sequence(data, camera, s);
  }
  // measure with the colour test model on the plate into `out`, with `options` added.
  ToolRun measure_plate(const std::string& options) {
    return run_tool("measure --model " + quoted(test_model("test-model-rgb.json")) + " --dataset " +
                        quoted(data) + " " + options + " --out " + quoted(out),
                    dir);
  }
  ScratchDir dir{"cli"};
  std::filesystem::path data = dir / "plate", out = dir / "out";
};

TEST_F(CliMeasure, measure_rejects_a_5x5_model_on_a_bayer_dataset_n) {
  ASSERT_EQ(read_text(data / "mosaic.txt"), "rggb\n");
  const ToolRun r = run_tool("measure --model " + quoted(test_model("test-model-nir5x5.json")) +
                                 " --dataset " + quoted(data) + " --out " + quoted(out),
                             dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("test-model-nir5x5.json: the model was calibrated for a 5x5 mosaic "
                       "(profile nir5x5-reference), the frames are rggb (" +
                       (data / "mosaic.txt").string() + ")"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(out / "stats.csv"));
}

TEST_F(CliMeasure, measure_rejects_a_5x5_model_on_a_frame_named_bayer_n) {
  const ToolRun r =
      run_tool("measure --model " + quoted(test_model("test-model-nir5x5.json")) + " --frame " +
                   quoted(data / "frames/0000.pgm") + " --dark " + quoted(data / "darks/0000.pgm") +
                   " --pattern RGGB --out " + quoted(out),
               dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("calibrated for a 5x5 mosaic (profile nir5x5-reference), the frames are "
                       "rggb (--pattern)"),
            std::string::npos)
      << r.err;
}

TEST_F(CliMeasure, measure_rejects_a_pattern_contradicting_the_dataset_n) {
  const ToolRun r = measure_plate("--pattern bggr");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("--pattern bggr contradicts " + (data / "mosaic.txt").string() + " (rggb)"),
            std::string::npos)
      << r.err;
}

TEST_F(CliMeasure, measure_rejects_a_dataset_that_does_not_name_its_mosaic_n) {
  std::filesystem::remove(data / "mosaic.txt");
  const ToolRun r = run_tool("measure --model " + quoted(test_model("test-model-rgb.json")) +
                                 " --dataset " + quoted(data) + " --out " + quoted(out),
                             dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("the dataset does not say its frames' mosaic layout (no mosaic.txt); give "
                       "--pattern"),
            std::string::npos)
      << r.err;
}

TEST_F(CliMeasure, measure_method_auto_reads_with_the_method_the_library_chooses) {
  const auto model = test_model("test-model-rgb.json");
  const std::string chosen = method_name(choose_method(
      std::make_shared<const ThermalModel>(load_model(model.string())), MethodRequest::kAuto));
  const std::filesystem::path by_name = dir / "by-name";
  for (const auto& [method, folder] :
       {std::pair{std::string("auto"), out}, std::pair{chosen, by_name}}) {
    const ToolRun r =
        run_tool("-q measure --model " + quoted(model) + " --dataset " + quoted(data) +
                     " --method " + method + " --out " + quoted(folder),
                 dir);
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
  }
  EXPECT_EQ(read_text(out / "stats.csv"), read_text(by_name / "stats.csv"));
}

// An ROI of another size would be stretched onto the frames, a frame of another size read with
// its own: statistics of the wrong pixels. A dark of another depth is another camera's.
TEST_F(CliMeasure, measure_rejects_an_roi_or_dark_that_does_not_fit_the_frames_n) {
  const std::string command = "-q measure --model " + quoted(test_model("test-model-rgb.json")) +
                              " --dataset " + quoted(data) + " --out ";
  const auto roi = data / "roi.png";
  std::filesystem::copy_file(roi, dir / "roi.png");
  write_raw_image(roi, cv::Mat(8, 8, CV_8U, cv::Scalar(255)));
  ToolRun r = run_tool(command + quoted(dir / "o1"), dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(data.string() + "/roi.png: the ROI is 8x8, the frames 100x100"),
            std::string::npos)
      << r.err;
  // An empty --roi gave rows of empty statistics and exit 0.
  write_raw_image(dir / "empty.png", cv::Mat(100, 100, CV_8U, cv::Scalar(0)));
  r = run_tool(command + quoted(dir / "o0") + " --roi " + quoted(dir / "empty.png"), dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("empty.png: the ROI is empty"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o0" / "stats.csv"));
  std::filesystem::copy_file(dir / "roi.png", roi,
                             std::filesystem::copy_options::overwrite_existing);
  const auto dark = data / "darks/0000.pgm";
  write_raw_image(dark, cv::Mat(100, 100, CV_16U, cv::Scalar(50)));
  r = run_tool(command + quoted(dir / "o2"), dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(dark.string() + ": the dark has 16-bit samples, the frame " +
                       (data / "frames/0000.pgm").string() + " 8-bit ones"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "o2" / "stats.csv"));
}

// A dark 20 DN below the camera's (a dark frame of another camera or setting) is said, as darksub
// says it; the dataset's own is not.
TEST_F(CliMeasure, measure_warns_of_a_dark_that_is_not_the_cameras) {
  const std::string command = "measure --model " + quoted(test_model("test-model-rgb.json")) +
                              " --dataset " + quoted(data) + " --out ";
  ToolRun r = run_tool(command + quoted(dir / "right"), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("cold background"), std::string::npos) << r.err;
  const auto dark = data / "darks/0000.pgm";
  cv::Mat lower;
  read_raw_image(dark).convertTo(lower, CV_8U, 1, -20);
  write_raw_image(dark, lower);
  r = run_tool(command + quoted(dir / "low"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  // 20 DN and the dark's own rounding (its samples average 49.6 DN where the frames' clamp is 50).
  const std::string said =
      "warning: after the dark (" + dark.string() + ") the frames' darkest parts read +";
  const auto at = r.err.find(said);
  ASSERT_NE(at, std::string::npos) << r.err;
  EXPECT_NEAR(std::stod(r.err.substr(at + said.size())), 20, 1.5) << r.err;
  EXPECT_NE(r.err.find(" DN too low for this camera"), std::string::npos) << r.err;
}

// A dataset's darks are one per exposure: one wrong among them was missed (one check took every
// frame, and after its first verdict only every 8th), and a 1300 degC plate read 1235 degC.
TEST_F(CliMeasure, measure_checks_each_dark_of_a_dataset_on_its_own_frames) {
  Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 6});
  SceneSequenceSettings s;
  s.kind = SceneKind::kPlate;
  s.temperatures_c = {900, 1100, 1300, 1500};
  s.width = 100;
  s.height = 100;
  const auto plates = dir / "plates";
  write_scene_sequence(plates, camera, s);
  const auto dark = plates / "darks/0002.pgm";
  ASSERT_TRUE(std::filesystem::exists(dark));
  cv::Mat lower;
  read_raw_image(dark).convertTo(lower, CV_8U, 1, -20);
  write_raw_image(dark, lower);
  const ToolRun r = run_tool("-q measure --model " + quoted(test_model("test-model-rgb.json")) +
                                 " --dataset " + quoted(plates) + " --out " + quoted(out),
                             dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: after the dark (" + dark.string() + ")"), std::string::npos)
      << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;  // that dark alone
}

// A model calibrated only up to 1200 degC read a 1700 degC plate as 1000 degC with the network
// (its ratios fold into the range), exit 0 and no word; ratiotemp warned, measure did not. Now
// measure says so, and a frame that reads little counts the pixels hotter than the range.
TEST_F(CliMeasure, measure_warns_of_a_network_that_reads_hotter_surfaces_inside_its_range) {
  const auto campaign = dir / "campaign", narrow = dir / "narrow.json", hot = dir / "hot";
  ASSERT_EQ(run_tool("-q simulate campaign --out " + quoted(campaign) +
                         " --size 64x64 --temperatures 700,800,900,1000,1100 --exposures 12 "
                         "--exposure-factor 2 --frames 1 --roi-area 800",
                     dir)
                .exit_code,
            0);
  ASSERT_EQ(run_tool("-q calibrate --dataset " + quoted(campaign) + " --out " + quoted(narrow) +
                         " --max-temperature 1200 --epochs 1 --polish-iterations 20 "
                         "--mc-refits 0 --noisy-copies 0 --locus-step 5 --no-prebuilt-table",
                     dir)
                .exit_code,
            0);
  const std::string model = "measure --model " + quoted(narrow) + " --dataset " + quoted(data);
  ToolRun r = run_tool("-q " + model + " --out " + quoted(dir / "mlp"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("warning: with method "), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("reads graybodies hotter than its range inside it"), std::string::npos)
      << r.err;
  EXPECT_NE(r.err.find("use --method likelihood"), std::string::npos) << r.err;
  // The fit gives a 1700 degC plate no reading, and says why (it said: a band too dim).
  ASSERT_EQ(run_tool("-q simulate scene --scene plate --temperatures 1700 --size 64x64 --out " +
                         quoted(hot),
                     dir)
                .exit_code,
            0);
  r = run_tool("measure --model " + quoted(narrow) + " --dataset " + quoted(hot) +
                   " --method likelihood --out " + quoted(dir / "fit"),
               dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("reads graybodies hotter"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("of the frame hotter than the model's range (up to 1200 degC"),
            std::string::npos)
      << r.err;
}

// Two sources whose temperatures round to one whole degree were written to one file name, the
// second over the first, and the manifest listed it twice (its own calibrate then refused it).
TEST(Cli, simulate_campaign_refuses_temperatures_that_share_a_file_name_n) {
  ScratchDir dir("cli-campaign-names");
  for (const std::string& args :
       {std::string("--temperatures 700,700.4,800"), std::string("--reference 1324.2,1324.4")}) {
    const ToolRun r = run_tool(
        "simulate campaign --size 64x64 --roi-area 800 " + args + " --out " + quoted(dir / "c"),
        dir);
    EXPECT_EQ(r.exit_code, 1) << args << ": " << r.err;
    EXPECT_NE(r.err.find("round to " + std::string(args[2] == 't' ? "700" : "1324") +
                         " degC, the whole degrees its files are named by"),
              std::string::npos)
        << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir / "c" / "manifest.csv"));
  }
}

// A saturation level above the full scale marks no sample saturated, and saturated bands read
// hundreds of degrees too hot.
TEST_F(CliMeasure, measure_refuses_a_saturation_level_above_the_full_scale_n) {
  const ToolRun r = measure_plate("--saturation 1000");
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("the saturation level 1000"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("above the 8-bit camera's full scale, 255 DN"), std::string::npos) << r.err;
}

// A second run into the folder of a first would leave the first's images among its own.
TEST_F(CliMeasure, measure_refuses_a_folder_that_holds_a_measurement_n) {
  const std::string command = "-q measure --model " + quoted(test_model("test-model-rgb.json")) +
                              " --dataset " + quoted(data) + " --out " + quoted(out);
  ASSERT_EQ(run_tool(command, dir).exit_code, 0);
  const std::string first = read_text(out / "stats.csv");
  write_text(out / "9999_temperature.png", "an earlier run's frame");
  write_text(out / "notes.txt", "the user's");
  ToolRun r = run_tool(command, dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(out.string() +
                       " already holds a measurement (stats.csv): choose another --out, or "
                       "--overwrite to replace it"),
            std::string::npos)
      << r.err;
  EXPECT_TRUE(std::filesystem::exists(out / "9999_temperature.png"));
  r = run_tool(command + " --overwrite", dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_text(out / "stats.csv"), first);
  EXPECT_FALSE(std::filesystem::exists(out / "9999_temperature.png"));
  EXPECT_TRUE(std::filesystem::exists(out / "notes.txt"));
}

// measure reads the model's prebuilt lookup table as ratiotemp does: the same temperatures with
// it, without it and with a damaged one, which gets a warning naming it.
TEST_F(CliMeasure, measure_reads_the_prebuilt_table_with_the_same_temperatures) {
  const auto source = test_model("test-model-rgb.json");
  ASSERT_TRUE(std::filesystem::exists(source.string() + ".lut")) << test::kNoTestModels;
  const auto model = dir / "m.json", table = dir / "m.json.lut";
  std::filesystem::copy_file(source, model);
  const auto measure = [&](const std::string& name) {
    const ToolRun r = run_tool("measure --model " + quoted(model) + " --dataset " + quoted(data) +
                                   " --method lut --out " + quoted(dir / name),
                               dir);
    EXPECT_EQ(r.exit_code, 0) << name << ": " << r.err;
    return r.err;
  };
  const std::string without = measure("without");
  std::filesystem::copy_file(source.string() + ".lut", table);
  const std::string with = measure("with");
  EXPECT_EQ(with.find("prebuilt lookup table"), std::string::npos) << with;
  {
    std::fstream f(table, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-40, std::ios::end);
    f.put('x');  // inside the last block's values: the checksum no longer holds
  }
  const std::string damaged = measure("damaged");
  EXPECT_NE(damaged.find("warning: prebuilt lookup table " + table.string() + " not used"),
            std::string::npos)
      << damaged;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "without")) {
    const auto name = entry.path().filename();
    EXPECT_EQ(read_text(dir / "with" / name), read_text(entry.path())) << name;
    EXPECT_EQ(read_text(dir / "damaged" / name), read_text(entry.path())) << name;
  }
}

// The median_c column of the first frame's row of a measure stats.csv (NaN without one).
double first_median_c(const std::filesystem::path& stats_csv) {
  std::istringstream lines(read_text(stats_csv));
  std::string line;
  std::getline(lines, line);  // header
  if (!std::getline(lines, line)) return NAN;
  std::istringstream fields(line);
  std::string field;
  for (int i = 0; i <= 8 && std::getline(fields, field, ','); ++i) {
  }
  return field.empty() ? NAN : std::stod(field);
}

// The median code of a 16-bit image over its nonzero pixels.
double median_nonzero(const std::filesystem::path& image) {
  const cv::Mat m = read_raw_image(image);
  std::vector<int> v;
  for (int y = 0; y < m.rows; ++y)
    for (int x = 0; x < m.cols; ++x)
      if (m.at<std::uint16_t>(y, x) != 0) v.push_back(m.at<std::uint16_t>(y, x));
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

TEST_F(CliMeasure, measure_e_slope_moves_the_reading_and_its_uncertainty) {
  const std::string base = "-q measure --model " + quoted(test_model("test-model-rgb.json")) +
                           " --dataset " + quoted(data) + " --method likelihood --uncertainty";
  const std::filesystem::path grey = dir / "grey", sloped = dir / "sloped";
  ASSERT_EQ(run_tool(base + " --out " + quoted(grey), dir).exit_code, 0);
  const ToolRun r =
      run_tool(base + " --e-slope -20 --e-slope-uncertainty 5 --out " + quoted(sloped), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The simulated plate is grey: read as a surface whose emissivity falls 20 %/100 nm towards
  // the red (which would read hotter uncorrected), it reads cooler.
  const double t_grey = first_median_c(grey / "stats.csv"),
               t_sloped = first_median_c(sloped / "stats.csv");
  EXPECT_GT(t_grey - t_sloped, 20) << t_grey << " " << t_sloped;
  // u(alpha) 5 %/100 nm instead of the model's 1 %/100 nm: a larger emissivity term.
  const double u_grey = median_nonzero(grey / "0000_uncertainty.png"),
               u_sloped = median_nonzero(sloped / "0000_uncertainty.png");
  EXPECT_GT(u_sloped, 2 * u_grey) << u_grey << " " << u_sloped;
}

TEST_F(CliMeasure, measure_rejects_an_e_slope_out_of_range_n) {
  for (const std::string bad : {"60", "-50.5", "nan"}) {
    const ToolRun r =
        run_tool("-q measure --model " + quoted(test_model("test-model-rgb.json")) + " --dataset " +
                     quoted(data) + " --e-slope " + bad + " --out " + quoted(out),
                 dir);
    EXPECT_NE(r.exit_code, 0) << bad;
    EXPECT_NE(r.err.find("e-slope"), std::string::npos) << bad << ": " << r.err;
  }
}

TEST_F(CliMeasure, measure_gain_db_widens_the_uncertainty_not_the_reading) {
  const std::string base = "-q measure --model " + quoted(test_model("test-model-rgb.json")) +
                           " --dataset " + quoted(data) + " --method likelihood --uncertainty";
  const std::filesystem::path plain = dir / "plain", gained = dir / "gained";
  ASSERT_EQ(run_tool(base + " --out " + quoted(plain), dir).exit_code, 0);
  const ToolRun r = run_tool(base + " --gain-db 12 --out " + quoted(gained), dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The same frames read as taken at 12 dB: each DN holds a quarter of the electrons, so the
  // shot noise per DN is four times the variance. The ratios are the same, and the likelihood
  // weights change little on a plate whose bands are all well exposed.
  const double t_plain = first_median_c(plain / "stats.csv"),
               t_gained = first_median_c(gained / "stats.csv");
  EXPECT_NEAR(t_gained, t_plain, 1.0);
  const double u_plain = median_nonzero(plain / "0000_uncertainty.png"),
               u_gained = median_nonzero(gained / "0000_uncertainty.png");
  std::cout << "median expanded uncertainty, codes: 0 dB " << u_plain << ", 12 dB " << u_gained
            << "\n";
  EXPECT_GT(u_gained, u_plain);
  for (const std::string bad : {"-3", "60", "nan"}) {
    const ToolRun b = run_tool(base + " --gain-db " + bad + " --out " + quoted(out), dir);
    EXPECT_NE(b.exit_code, 0) << bad;
    EXPECT_NE(b.err.find("gain-db"), std::string::npos) << bad << ": " << b.err;
  }
}

}  // namespace
}  // namespace pyrocam
