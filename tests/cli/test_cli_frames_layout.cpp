// pyrocam-calib measure and the frames' layout: a Bayer mosaic whose readout window starts one
// column further on is read with the pattern it has (the model's filters), and read as the
// model's pattern it is warned about; a 5x5 mosaic shifted by a column misfits the model's band
// spectra and is warned about; a 5x5 mosaic read as a Bayer mosaic is said to be none. A run
// that fails part-way leaves no results that look complete.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <utility>

#include "cli_support.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;

// Runs pyrocam-calib (not quiet): its exit code and standard error.
std::pair<int, std::string> run(const std::string& args, const fs::path& log) {
  const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' " + args +
                              " < /dev/null > /dev/null 2> '" + log.string() + "'";
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_text(log)};
}

double median_of_first_frame(const fs::path& out) {
  const std::string median = first_stats_row(out).at("median_c");
  return median.empty() ? NAN : std::stod(median);
}

// The plate's first frame and its dark, with `left` columns cut at the left and `right` at the
// right (a readout window that starts further on), as PGM files in `folder`.
std::pair<fs::path, fs::path> cropped_plate(const fs::path& plate, const fs::path& folder, int left,
                                            int right) {
  const Dataset d = Dataset::open(plate);
  const ManifestRow& row =
      d.rows().front().kind == FrameKind::kFrame ? d.rows().front() : d.rows().back();
  const fs::path frame = d.path_of(row), dark = d.dark_for(row.exposure_us).files.front();
  std::pair<fs::path, fs::path> out{folder / "frame.pgm", folder / "dark.pgm"};
  fs::create_directories(folder);
  for (const auto& [from, to] : {std::pair{frame, out.first}, {dark, out.second}}) {
    const cv::Mat image = read_raw_image(from);
    write_raw_image(to, image.colRange(left, image.cols - right).clone());
  }
  return out;
}

TEST(CliFramesLayout, a_bayer_window_one_column_on_reads_with_its_own_pattern) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-layout-bayer"};
  write_plate(dir / "plate", "rgb-reference", 1, 1000, 128);
  const auto [frame0, dark0] = cropped_plate(dir / "plate", dir / "whole", 0, 0);
  const auto [frame, dark] = cropped_plate(dir / "plate", dir / "shifted", 1, 1);
  const std::string base = "measure --model " + q(model) + " --frame ";
  const auto whole =
      run(base + q(frame0) + " --dark " + q(dark0) + " --pattern rggb --out " + q(dir / "m-whole"),
          dir / "whole.log");
  const auto as_model =
      run(base + q(frame) + " --dark " + q(dark) + " --pattern rggb --out " + q(dir / "m-rggb"),
          dir / "rggb.log");
  const auto as_is =
      run(base + q(frame) + " --dark " + q(dark) + " --pattern grbg --out " + q(dir / "m-grbg"),
          dir / "grbg.log");
  ASSERT_EQ(whole.first, 0) << whole.second;
  // Temperatures that look right and are wrong fail the run, what it wrote kept.
  ASSERT_EQ(as_model.first, 1) << as_model.second;
  ASSERT_EQ(as_is.first, 0) << as_is.second;
  // (Warnings on how much of the frame reads are not the point: the plate fills a third of it.)
  EXPECT_EQ(whole.second.find("green samples"), std::string::npos) << whole.second;
  // Read as the model's rggb, red and green trade places: far off, and said.
  EXPECT_NE(as_model.second.find("green samples sit on the other diagonal"), std::string::npos)
      << as_model.second;
  EXPECT_GT(std::abs(median_of_first_frame(dir / "m-rggb") - 1000), 50);
  // Read as grbg: the same pixels as the whole frame's, less a column.
  EXPECT_NE(as_is.second.find("note: the frames are grbg"), std::string::npos) << as_is.second;
  EXPECT_EQ(as_is.second.find("green samples"), std::string::npos) << as_is.second;
  const double m0 = median_of_first_frame(dir / "m-whole"),
               m1 = median_of_first_frame(dir / "m-grbg");
  EXPECT_LT(std::abs(m0 - 1000), 10);
  EXPECT_LT(std::abs(m1 - m0), 1.0) << m0 << " " << m1;
  // A snapshot layout for a Bayer model stays refused.
  EXPECT_EQ(run(base + q(frame) + " --dark " + q(dark) + " --pattern 5x5 --out " + q(dir / "m-5x5"),
                dir / "5x5.log")
                .first,
            1);
}

// A colour dataset whose mosaic.txt says bggr for rggb frames: red and blue traded, the greens in
// place (the green check cannot see it), the plate read far too cold on the model's locus (the
// band check passes it). At the rows' exposures it is thousands of times brighter than a black
// body at that reading: the run says so and fails. Labelled right, nothing is said.
TEST(CliFramesLayout, red_and_blue_traded_are_said_to_be_brighter_than_a_black_body) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-layout-traded"};
  write_plate(dir / "plate", "rgb-reference", 1, 1300, 128);
  const std::string base = "measure --model " + q(model) + " --dataset " + q(dir / "plate");
  const auto right = run(base + " --out " + q(dir / "m-right"), dir / "right.log");
  write_text(dir / "plate" / "mosaic.txt", "bggr\n");
  const auto traded = run(base + " --out " + q(dir / "m-traded"), dir / "traded.log");
  ASSERT_EQ(right.first, 0) << right.second;
  ASSERT_EQ(traded.first, 1) << traded.second;
  EXPECT_EQ(right.second.find("black body"), std::string::npos) << right.second;
  EXPECT_NE(traded.second.find("over a thousand times as bright as a black body"),
            std::string::npos)
      << traded.second;
  EXPECT_LT(median_of_first_frame(dir / "m-traded"), 900);  // what it read, kept to be seen
}

TEST(CliFramesLayout, a_5x5_mosaic_shifted_by_a_column_is_said_to_misfit) {
  const fs::path model = test_model("test-model-nir5x5.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-layout-5x5"};
  write_plate(dir / "plate", "nir5x5-reference", 1, 1000, 250);
  const auto [frame0, dark0] = cropped_plate(dir / "plate", dir / "whole", 0, 0);
  const auto [frame, dark] = cropped_plate(dir / "plate", dir / "shifted", 1, 4);
  const std::string base = "measure --model " + q(model) + " --pattern 5x5 --frame ";
  const auto whole = run(base + q(frame0) + " --dark " + q(dark0) + " --out " + q(dir / "m-whole"),
                         dir / "whole.log");
  const auto shifted =
      run(base + q(frame) + " --dark " + q(dark) + " --out " + q(dir / "m-shifted"),
          dir / "shifted.log");
  ASSERT_EQ(whole.first, 0) << whole.second;
  ASSERT_EQ(shifted.first, 1) << shifted.second;
  EXPECT_TRUE(fs::exists(dir / "m-shifted" / "stats.csv"));
  EXPECT_EQ(whole.second.find("do not fit"), std::string::npos) << whole.second;
  EXPECT_NE(shifted.second.find("readings checked do not fit the model's band spectra"),
            std::string::npos)
      << shifted.second;
}

// A 5x5 snapshot mosaic read with a colour model as a Bayer mosaic: every place of the 2x2 cell
// averages all 25 filters, so the greens are where rggb says on average; the greens of each
// cell are two different filters, and the run says so and fails.
TEST(CliFramesLayout, a_snapshot_mosaic_read_as_a_bayer_mosaic_fails) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-layout-snapshot-as-bayer"};
  write_plate(dir / "plate", "nir5x5-reference", 1, 1400, 250);
  const auto [frame, dark] = cropped_plate(dir / "plate", dir / "frames", 0, 0);
  const auto r = run("measure --model " + q(model) + " --frame " + q(frame) + " --dark " + q(dark) +
                         " --pattern rggb --out " + q(dir / "m"),
                     dir / "m.log");
  ASSERT_EQ(r.first, 1) << r.second;
  EXPECT_NE(r.second.find("the frames are not a Bayer mosaic"), std::string::npos) << r.second;
  EXPECT_TRUE(fs::exists(dir / "m" / "stats.csv"));
}

TEST(CliFramesLayout, a_run_that_fails_part_way_leaves_no_results_n) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-layout-partial"};
  Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 2});
  SceneSequenceSettings s;
  s.kind = SceneKind::kPlate;
  s.temperatures_c = {800, 1000, 1200};
  s.width = s.height = 64;
  write_scene_sequence(dir / "plates", camera, s);
  const std::string args =
      "measure --model " + q(model) + " --dataset " + q(dir / "plates") + " --out ";
  ASSERT_EQ(run(args + q(dir / "good"), dir / "good.log").first, 0);
  EXPECT_TRUE(fs::exists(dir / "good" / "stats.csv"));
  // The last frame truncated: the first two are measured, then the run fails.
  const fs::path last = dir / "plates" / "frames" / "0002.pgm";
  ASSERT_TRUE(fs::exists(last));
  const std::string text = read_text(last);
  write_text(last, text.substr(0, 100));
  const auto failed = run(args + q(dir / "bad"), dir / "bad.log");
  EXPECT_EQ(failed.first, 1);
  EXPECT_NE(failed.second.find("0002.pgm"), std::string::npos) << failed.second;
  EXPECT_FALSE(fs::exists(dir / "bad" / "stats.csv"));
  EXPECT_FALSE(fs::exists(dir / "bad" / "0000_temperature.png"));
  EXPECT_FALSE(fs::exists(dir / "bad" / "0001_temperature.png"));
}

}  // namespace
}  // namespace pyrocam::test
