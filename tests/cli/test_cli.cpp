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
using test::run_tool;
using test::ScratchDir;
using test::test_model;
using test::ToolRun;
using test::write_text;

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

// A folder as --out was found only when the model was renamed into place, minutes later, with
// the model left beside it as model.json.partial.
TEST_F(CliDataset, calibrate_rejects_a_folder_as_out_before_calibrating_n) {
  std::filesystem::create_directories(model);
  const ToolRun r = calibrate();
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find(model.string() + ": is a folder; --out names the model file to write"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(std::filesystem::exists(model.string() + ".partial"));
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

// Two temperatures: the QE's cross-validation left one temperature a fold ("band 'R' has 1
// usable calibration rates"), while the docs said two were enough.
TEST_F(CliDataset, calibrate_rejects_a_dataset_at_two_temperatures_for_a_fitted_qe_n) {
  std::string kept;
  std::ifstream in(data / "manifest.csv");
  for (std::string line; std::getline(in, line);)
    if (line.find(",frame,") == std::string::npos ||
        line.find(",frame,1000,") != std::string::npos ||
        line.find(",frame,1100,") != std::string::npos)
      kept += line + "\n";
  in.close();
  write_text(data / "manifest.csv", kept);
  expect_failed(calibrate(), {"furnace: frames at 2 temperatures; fitting the QE needs 3 or more",
                              "or --solver datasheet"});
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
