// pyrocam-calib as users run it: bad input gives exit code 1 and one message on stderr that
// names the file and the problem, and writes no output.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <sstream>
#include <utility>

#include "cli_support.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::png_header;
using test::read_text;
using test::ScratchDir;
using test::test_model;
using test::write_text;

struct ToolRun {
  int exit_code = -1;
  std::string err;
};

// Runs pyrocam-calib with `args` (already shell-quoted where needed), stdin closed; stderr is
// kept. A timeout ends a run that hangs (a FIFO opened for reading blocks forever).
ToolRun run_tool(const std::string& args, const ScratchDir& dir) {
  const auto err = dir / "stderr.txt";
  const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' " + args +
                              " < /dev/null > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_text(err);
  return r;
}

std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// A small simulated colour campaign that calibrates: 5 temperatures, 3 exposures, 1 frame each.
class CliDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 5});
    CampaignSettings s;
    s.temperatures_c = {1000, 1025, 1050, 1075, 1100};  // 5: the QE cross-validation's groups
    s.exposure_count = 3;
    s.frames_per_setting = 1;
    s.width = 32;
    s.height = 32;
    s.roi_area_px = 200;
    write_furnace_campaign(data, camera, s);
  }
  void replace_in_manifest(const std::string& from, const std::string& to) {
    std::string text = read_text(data / "manifest.csv");
    const auto pos = text.find(from);
    ASSERT_NE(pos, std::string::npos) << from;
    text.replace(pos, from.size(), to);
    write_text(data / "manifest.csv", text);
  }
  // The manifest line (1-based) that lists `file`.
  int line_of(const std::string& file) {
    std::ifstream in(data / "manifest.csv");
    int n = 0;
    for (std::string line; std::getline(in, line);) {
      ++n;
      if (line.rfind(file + ",", 0) == 0) return n;
    }
    return -1;
  }
  ToolRun calibrate(const std::string& extra = "") {
    return run_tool("-q calibrate --dataset " + quoted(data) + " --out " + quoted(model) +
                        " --epochs 1 --polish-iterations 0 --mc-refits 0 " + extra,
                    dir);
  }
  void expect_failed(const ToolRun& r, const std::vector<std::string>& needles) {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    for (const auto& n : needles) EXPECT_NE(r.err.find(n), std::string::npos) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_FALSE(std::filesystem::exists(model)) << "a model was written";
  }

  ScratchDir dir{"cli"};
  std::filesystem::path data = dir / "furnace", model = dir / "model.json";
  const std::string first_frame = "frames/T1000_e00_f0.pgm";
};

TEST_F(CliDataset, calibrate_writes_a_model_from_the_intact_dataset) {
  // What the rejections below are measured against: the same dataset, unchanged, calibrates.
  // Without its prebuilt table, a table left beside the model by an earlier one goes.
  write_text(dir / "model.json.lut", "an earlier model's table");
  const ToolRun r = run_tool("-q calibrate --dataset " + quoted(data) + " --out " + quoted(model) +
                                 " --epochs 1 --polish-iterations 0 --mc-refits 0 "
                                 "--no-prebuilt-table",
                             dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(model));
  EXPECT_FALSE(std::filesystem::exists(dir / "model.json.lut"));
}

// The <svg> element with this id in a report page ("" if none).
std::string svg_with_id(const std::string& html, const std::string& id) {
  const auto at = html.find("<svg xmlns='http://www.w3.org/2000/svg' id='" + id + "'");
  if (at == std::string::npos) return "";
  const auto end = html.find("</svg>", at);
  return end == std::string::npos ? "" : html.substr(at, end - at);
}
std::size_t count_of(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

// The locus plot: a line with many points, the furnace measurements (one marker per
// temperature), temperature labels; the error plot: one marker per estimator and setting.
void expect_report_plots(const std::string& html, int furnace_temperatures) {
  const std::string locus = svg_with_id(html, "locus-plot");
  ASSERT_FALSE(locus.empty()) << "no locus plot";
  EXPECT_NE(locus.find("Planckian locus"), std::string::npos);
  EXPECT_GT(count_of(locus, " L"), 100u) << "the locus line has too few points";
  // Markers: the locus every 500 degC (at least 2) and the furnace temperatures.
  EXPECT_GE(count_of(locus, "<circle"), static_cast<std::size_t>(furnace_temperatures + 2));
  EXPECT_NE(locus.find("1000 °C"), std::string::npos) << "no temperature labels on the locus";
  const std::string errors = svg_with_id(html, "setting-error-plot");
  ASSERT_FALSE(errors.empty()) << "no per-setting error plot";
  EXPECT_NE(errors.find("reading − furnace"), std::string::npos);
  EXPECT_GE(count_of(errors, "<circle"), static_cast<std::size_t>(furnace_temperatures))
      << "no per-setting points";
  EXPECT_NE(errors.find("MLP"), std::string::npos);
}

TEST_F(CliDataset, calibrate_report_plots_the_locus_and_the_error_per_setting) {
  const ToolRun r = calibrate();
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::filesystem::path report = model;
  report.replace_extension();
  expect_report_plots(read_text(report.string() + "-report.html"), 5);
}

TEST(CliReport, the_5x5_test_models_report_plots_the_locus_and_the_error_per_setting) {
  // tests/data/make-test-model.sh keeps each test model's report beside it.
  const std::filesystem::path report =
      test_model("test-model-nir5x5.json").string() + ".d/report.html";
  ASSERT_TRUE(std::filesystem::exists(report)) << report;
  const std::string html = read_text(report);
  expect_report_plots(html, 31);  // the test models' campaigns: 800..1100 degC every 10 degC
  // Where the data end (said, and shaded on the uncertainty plot); every band's residual,
  // though the plots show 5 of the 25.
  for (const char* part :
       {"Furnace data 800–1100 °C", ">furnace data</text>", "(5 of 25 bands)", "<td>b25</td>"})
    EXPECT_NE(html.find(part), std::string::npos) << part;
}

TEST_F(CliDataset, calibrate_rejects_a_manifest_path_leaving_the_dataset_n) {
  const int line = line_of(first_frame);
  replace_in_manifest(first_frame, "../../../../etc/passwd");
  expect_failed(calibrate(), {"manifest.csv:" + std::to_string(line) +
                              ": file '../../../../etc/passwd' leaves the dataset folder"});
}

TEST_F(CliDataset, calibrate_rejects_an_absolute_path_to_a_valid_image_n) {
  // A readable image of the right size elsewhere was read and a model written (exit 0).
  std::filesystem::copy_file(data / first_frame, dir / "elsewhere.pgm");
  const int line = line_of(first_frame);
  replace_in_manifest(first_frame, (dir / "elsewhere.pgm").string());
  expect_failed(calibrate(), {"manifest.csv:" + std::to_string(line) + ": file '" +
                              (dir / "elsewhere.pgm").string() + "' is an absolute path"});
}

TEST_F(CliDataset, calibrate_rejects_a_relative_path_to_another_folder_n) {
  std::filesystem::create_directories(dir / "other");
  std::filesystem::copy_file(data / first_frame, dir / "other/frame.pgm");
  replace_in_manifest(first_frame, "frames/../../other/frame.pgm");
  expect_failed(calibrate(), {"file 'frames/../../other/frame.pgm' leaves the dataset folder"});
}

TEST_F(CliDataset, calibrate_rejects_a_symbolic_link_out_of_the_dataset_n) {
  std::filesystem::create_directories(dir / "other");
  std::filesystem::rename(data / first_frame, dir / "other/frame.pgm");
  std::filesystem::create_symlink(dir / "other/frame.pgm", data / first_frame);
  expect_failed(calibrate(), {first_frame + " (manifest.csv line " +
                                  std::to_string(line_of(first_frame)) + "): resolves to",
                              "outside the dataset folder"});
}

TEST_F(CliDataset, calibrate_rejects_a_nul_inside_a_file_name_n) {
  // The name was cut at the NUL without a message.
  const int line = line_of(first_frame);
  replace_in_manifest(first_frame, first_frame + std::string(1, '\0') + "x");
  expect_failed(calibrate(), {"manifest.csv:" + std::to_string(line) +
                              ": file name holds a control character (byte 0x00)"});
}

TEST_F(CliDataset, calibrate_rejects_a_directory_listed_as_a_frame_n) {
  std::filesystem::remove(data / first_frame);
  std::filesystem::create_directory(data / first_frame);
  expect_failed(calibrate(),
                {first_frame + " (manifest.csv line " + std::to_string(line_of(first_frame)) +
                 "): is a directory, not an image"});
}

TEST_F(CliDataset, calibrate_rejects_a_fifo_listed_as_a_frame_without_blocking_n) {
  std::filesystem::remove(data / first_frame);
  ASSERT_EQ(mkfifo((data / first_frame).c_str(), 0600), 0);
  expect_failed(calibrate(),
                {first_frame + " (manifest.csv line " + std::to_string(line_of(first_frame)) +
                 "): is not a regular file (a FIFO, socket or device)"});
}

TEST_F(CliDataset, calibrate_rejects_a_dataset_at_one_temperature_n) {
  // It named band R ("no temperature with 2 usable points") instead.
  std::string kept;
  std::ifstream in(data / "manifest.csv");
  for (std::string line; std::getline(in, line);)
    if (line.find(",frame,") == std::string::npos || line.find(",frame,1000,") != std::string::npos)
      kept += line + "\n";
  in.close();
  write_text(data / "manifest.csv", kept);
  expect_failed(calibrate(), {"furnace: every frame in manifest.csv is at one temperature (1000 "
                              "degC); calibration needs frames at 2 or more temperatures"});
}

TEST_F(CliDataset, calibrate_rejects_a_dataset_of_another_mosaic_than_the_profile_n) {
  write_text(data / "mosaic.txt", "5x5\n");
  const char* error = "mosaic.txt: the images are 5x5, the profile rgb-reference describes a";
  expect_failed(calibrate("--profile rgb-reference"), {error});  // without, the 5x5 profile
}

TEST_F(CliDataset, calibrate_rejects_a_huge_png_dark_frame_before_decoding_n) {
  // A 30000x30000 PNG was decoded in full (4.4 GB resident) before its size was checked. Its
  // header is enough to show that: a decoder allocates from it before reading any pixel.
  write_text(data / "darks/huge.png", png_header(30000, 30000, 8));
  replace_in_manifest("darks/e00_f0.pgm", "darks/huge.png");
  expect_failed(calibrate(), {"huge.png: image is 30000x30000, the dataset's (ROI) size is 32x32"});
}

// The same kind of campaign, written by `simulate campaign --reference`: Pt-C and Re-C cells
// beyond the furnace, each with its own 16-exposure sweep and darks.
class CliReferenceDataset : public CliDataset {
 protected:
  void SetUp() override {
    const ToolRun r = run_tool(
        "-q simulate campaign --profile rgb-reference --unit typical --unit-seed 5 "
        "--temperatures 1000 1025 1050 1075 1100 --exposures 16 --frames 1 --size 32x32 "
        "--roi-area 200 --reference 1738,2474 --out " +
            quoted(data),
        dir);
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  ToolRun calibrate_with(const std::string& extra) {
    return run_tool("-q calibrate --dataset " + quoted(data) + " --out " + quoted(model) +
                        " --epochs 1 --polish-iterations 0 --mc-refits 0 " + extra,
                    dir);
  }
  // Keeps the manifest lines for which `keep` is true.
  template <typename Keep>
  void filter_manifest(const Keep& keep) {
    std::string kept;
    std::ifstream in(data / "manifest.csv");
    for (std::string line; std::getline(in, line);)
      if (keep(line)) kept += line + "\n";
    in.close();
    write_text(data / "manifest.csv", kept);
  }
  const std::string first_reference = "references/R1738_e00_f0.pgm";
};

TEST_F(CliReferenceDataset, simulate_writes_reference_rows_with_their_uncertainty) {
  const std::string manifest = read_text(data / "manifest.csv");
  EXPECT_EQ(manifest.rfind(std::string(kManifestHeaderWithUncertainty) + "\n", 0), 0u);
  const Dataset d = Dataset::open(data);
  ASSERT_EQ(d.references().size(), 32u);  // 2 references x 16 exposures
  for (const FrameGroup& g : d.references()) {
    EXPECT_TRUE(g.temperature_c == 1738 || g.temperature_c == 2474) << g.temperature_c;
    EXPECT_DOUBLE_EQ(g.temperature_uncertainty_c, 0.5);
  }
  EXPECT_EQ(d.temperatures_c(), (std::vector<double>{1000, 1025, 1050, 1075, 1100}));
  EXPECT_GT(line_of(first_reference), 1);
  // The furnace steps, then the references' true temperatures.
  const std::string truth = read_text(data / "furnace-truth.csv");
  EXPECT_EQ(std::count(truth.begin(), truth.end(), '\n'), 8);
}

TEST_F(CliReferenceDataset, calibrate_writes_a_model_from_a_dataset_with_references) {
  const ToolRun r = calibrate_with("");
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(std::filesystem::exists(model));
  // The report reads each reference with the datasheet and the fitted QE.
  std::filesystem::path report = model;
  report.replace_extension();
  const auto summary =
      nlohmann::json::parse(read_text(report.string() + "-report.json")).at("references");
  ASSERT_EQ(summary.size(), 2u);
  for (const auto& ref : summary) {
    EXPECT_TRUE(ref.at("error_datasheet_c").is_number()) << ref;
    // The fit saw these rows: its residual stays near their 0.5 degC (with the furnace's pull).
    EXPECT_LT(std::abs(ref.at("error_fitted_c").get<double>()), 10.0) << ref;
  }
  std::filesystem::path html = model;
  html.replace_extension();
  EXPECT_NE(read_text(html.string() + "-report.html").find("Reference sources"), std::string::npos);
}

TEST_F(CliReferenceDataset, calibrate_rejects_a_reference_outside_the_models_range_n) {
  const int line = line_of("references/R2474_e00_f0.pgm");
  expect_failed(calibrate_with("--max-temperature 2000"),
                {"manifest.csv line " + std::to_string(line) +
                 ": reference at 2474 degC is outside the model's range 500-2000 degC"});
}

TEST_F(CliReferenceDataset, calibrate_rejects_a_negative_reference_uncertainty_n) {
  const int line = line_of(first_reference);
  std::string text = read_text(data / "manifest.csv");
  const auto row = text.find(first_reference + ",");
  const auto end = text.find('\n', row);
  ASSERT_EQ(text.substr(end - 4, 4), ",0.5");
  text.replace(end - 4, 4, ",-0.5");
  write_text(data / "manifest.csv", text);
  expect_failed(calibrate(), {"manifest.csv:" + std::to_string(line) +
                              ": temperature_uncertainty_c must be > 0"});
}

TEST_F(CliReferenceDataset, calibrate_rejects_a_reference_exposure_without_its_dark_n) {
  const std::string dark = "darks/R1738_e03_f0.pgm";
  ASSERT_GT(line_of(dark), 0);
  filter_manifest([&](const std::string& l) { return l.rfind(dark + ",", 0) != 0; });
  const int line = line_of("references/R1738_e03_f0.pgm");
  expect_failed(calibrate(), {"R1738_e03_f0.pgm (manifest.csv line " + std::to_string(line) +
                                  "): reference at 1738 degC, exposure",
                              "has no dark row of that exposure"});
}

TEST_F(CliReferenceDataset, calibrate_rejects_a_reference_dim_at_every_exposure_n) {
  // Only the sweep's first two exposures are left: the brightest band is below the dim level.
  filter_manifest([](const std::string& l) {
    return l.rfind("references/R1738_e", 0) != 0 || l.rfind("references/R1738_e00", 0) == 0 ||
           l.rfind("references/R1738_e01", 0) == 0;
  });
  const int line = line_of(first_reference);
  expect_failed(calibrate(), {"reference 1738 degC (manifest line " + std::to_string(line) +
                              "): every band is dim or saturated at every one of its 2"});
}

TEST_F(CliReferenceDataset, calibrate_rejects_an_empty_reference_roi_n) {
  write_raw_image(data / kReferenceRoiFile, cv::Mat::zeros(32, 32, CV_8U));
  expect_failed(calibrate(), {"reference-roi.png: the reference ROI is empty"});
}

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
  const ToolRun r =
      run_tool("measure --model " + quoted(test_model("test-model-rgb.json")) + " --dataset " +
                   quoted(data) + " --pattern bggr --out " + quoted(out),
               dir);
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

TEST(CliVersion, prints_the_tool_and_version_and_exits_0) {
  ScratchDir dir("version");
  const auto out = dir / "out.txt";
  const std::string command = "timeout 60 '" + std::string(PYROCAM_CALIB_TOOL) +
                              "' --version < /dev/null > '" + out.string() + "' 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_EQ(read_text(out).rfind("pyrocam-calib ", 0), 0u) << read_text(out);
}

}  // namespace
}  // namespace pyrocam
