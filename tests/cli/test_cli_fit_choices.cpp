// pyrocam-calib calibrate's choices of what the fit models, decided by a test on the data by
// default or as asked: --leak-terms (the regularised QE fit's leaks outside the filter's pass
// band), --prior-widths (how wide its priors on the QE's shape are) and --rate-offsets (where
// the furnace lines of net signal against exposure meet zero exposure); the report names what
// was done.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli_support.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::calib;
using test::q;
using test::read_text;
using test::ScratchDir;

class FitChoices : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("cli");
    ASSERT_EQ(calib("simulate campaign --profile rgb-reference --temperatures 1000 1025 1050 "
                    "1075 1100 --exposures 12 --frames 1 --size 32x32 --roi-area 200 --out " +
                    q(*dir_ / "furnace")),
              0);
  }
  static void TearDownTestSuite() { delete dir_; }
  // Calibrates with `options`; the report's JSON, and its HTML in `html`.
  static nlohmann::json calibrate(const std::string& name, const std::string& options,
                                  std::string* html = nullptr) {
    const std::filesystem::path model = *dir_ / (name + ".json");
    EXPECT_EQ(calib("calibrate --dataset " + q(*dir_ / "furnace") + " " + options +
                    " --epochs 1 --polish-iterations 0 --mc-refits 0 --no-prebuilt-table --out " +
                    q(model)),
              0)
        << options;
    if (html) *html = read_text(*dir_ / (name + "-report.html"));
    return nlohmann::json::parse(read_text(*dir_ / (name + "-report.json")));
  }
  static ScratchDir* dir_;
};
ScratchDir* FitChoices::dir_ = nullptr;

// The regularised solver's row of the report's solver table.
std::string leak_terms_in(const nlohmann::json& report) {
  for (const auto& s : report["solvers"])
    if (s["solver"] == "regularised") return s["leak_terms"].get<std::string>();
  return "(no regularised solver in the report)";
}

TEST_F(FitChoices, calibrate_selects_keeps_or_drops_the_leak_terms) {
  const auto leak_terms = [](const std::string& how) {
    return leak_terms_in(calibrate("leak-" + how, "--solver regularised --leak-terms " + how));
  };
  // Kept or dropped as told, without a test to report.
  EXPECT_EQ(leak_terms("keep"), "kept (bumps every 10 nm)");
  EXPECT_EQ(leak_terms("drop"), "dropped");
  // Selected: the decision with the test's figures.
  const std::string selected = leak_terms("select");
  EXPECT_NE(selected.find("chi2 gain"), std::string::npos) << selected;
  EXPECT_TRUE(selected.rfind("kept", 0) == 0 || selected.rfind("dropped", 0) == 0) << selected;
}

TEST_F(FitChoices, calibrate_selects_or_takes_the_prior_widths) {
  // The regularised solver's row of the report.
  const auto row = [](const std::string& name, const std::string& how, std::string* html) {
    const nlohmann::json report =
        calibrate("widths-" + name, "--solver regularised --prior-widths " + how, html);
    for (const auto& s : report["solvers"])
      if (s["solver"] == "regularised") return s;
    ADD_FAILURE() << "no regularised solver in the report";
    return nlohmann::json{{"prior_widths", ""}, {"prior_sensitivity", ""}};
  };
  std::string html;
  EXPECT_EQ(row("nominal", "nominal", nullptr)["prior_widths"], "1 x nominal");
  const nlohmann::json factor = row("factor", "3", &html);
  EXPECT_EQ(factor["prior_widths"], "3 x nominal");
  // The uncertainty's prior-sensitivity fits around the widths kept: twice and half as wide,
  // each counted or left out by its evidence, in the JSON and the HTML.
  const std::string sensitivity = factor["prior_sensitivity"];
  EXPECT_EQ(sensitivity.rfind("6 x nominal ", 0), 0u) << sensitivity;
  EXPECT_NE(sensitivity.find("; 1.5 x nominal "), std::string::npos) << sensitivity;
  EXPECT_NE(html.find(sensitivity), std::string::npos) << sensitivity;
  // Selected: the factor kept, with the evidence of each factor tried, in the HTML too.
  const std::string selected = row("select", "select", &html)["prior_widths"];
  EXPECT_NE(selected.find(" x nominal (log evidence "), std::string::npos) << selected;
  EXPECT_NE(selected.find(" at 0.5 x, "), std::string::npos) << selected;
  EXPECT_NE(selected.find(" at 2 x)"), std::string::npos) << selected;
  EXPECT_NE(html.find(selected), std::string::npos) << selected;
}

TEST_F(FitChoices, calibrate_tests_or_takes_the_rate_offsets_asked_for) {
  const auto offsets = [](const std::string& how) {
    std::string html;
    const std::string words = calibrate(
        "offsets-" + how, "--solver datasheet --rate-offsets " + how, &html)["rate_offsets"];
    // The HTML report says it too (with < and > escaped).
    std::string html_words;
    for (char c : words) html_words += c == '<' ? "&lt;" : c == '>' ? "&gt;" : std::string(1, c);
    EXPECT_NE(html.find(html_words), std::string::npos) << html_words;
    return words;
  };
  EXPECT_EQ(offsets("common"), "one per band (as asked)");
  EXPECT_EQ(offsets("per-step"), "one per temperature (as asked)");
  const std::string tested = offsets("select");
  EXPECT_NE(tested.find("degrees of freedom)"), std::string::npos) << tested;
  EXPECT_TRUE(tested.rfind("one per band (chi2 ", 0) == 0 ||
              tested.rfind("one per temperature (chi2 ", 0) == 0)
      << tested;
}

TEST_F(FitChoices, calibrate_keeps_one_offset_per_temperature_when_the_black_level_drifts) {
  // The same campaign with the furnace frames' black level drifting 3 DN from the darks'.
  ASSERT_EQ(calib("simulate campaign --profile rgb-reference --temperatures 1000 1025 1050 1075 "
                  "1100 --exposures 12 --frames 1 --size 32x32 --roi-area 200 "
                  "--black-level-drift 3 --out " +
                  q(*dir_ / "drifted")),
            0);
  const std::filesystem::path model = *dir_ / "drifted.json";
  ASSERT_EQ(calib("calibrate --dataset " + q(*dir_ / "drifted") +
                  " --solver datasheet --epochs 1 --polish-iterations 0 --mc-refits 0 "
                  "--no-prebuilt-table --out " +
                  q(model)),
            0);
  const std::string words =
      nlohmann::json::parse(read_text(*dir_ / "drifted-report.json"))["rate_offsets"];
  EXPECT_EQ(words.rfind("one per temperature (chi2 ", 0), 0u) << words;
}

TEST(CliFitChoices, calibrate_rejects_other_values_n) {
  ScratchDir dir("cli");
  for (const std::string option :
       {"--leak-terms sometimes", "--rate-offsets zero", "--prior-widths wide", "--prior-widths 0",
        "--prior-widths 11", "--prior-widths nan", "--prior-widths 2x"}) {
    EXPECT_EQ(calib("calibrate --dataset " + q(dir.path()) + " " + option + " --out " +
                    q(dir / "m.json")),
              2)
        << option;
    EXPECT_FALSE(std::filesystem::exists(dir / "m.json")) << option;
  }
}

// A model or report path in a folder that is not there is refused before the calibration's
// minutes, not after them.
TEST(CliFitChoices, calibrate_refuses_an_output_folder_that_is_not_there_first_n) {
  ScratchDir dir("cli");
  const std::vector<std::string> options = {"--out " + q(dir / "none" / "m.json"),
                                            "--report " + q(dir / "none" / "r")};
  for (const std::string& option : options) {
    const auto err = dir / "stderr.txt";
    const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) +
                                "' calibrate --dataset " + q(dir / "no-dataset") + " " + option +
                                " < /dev/null > /dev/null 2> " + q(err);
    const int status = std::system(command.c_str());
    EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1) << option;
    const std::string message = read_text(err);
    EXPECT_NE(message.find("the folder " + (dir / "none").string() + " does not exist"),
              std::string::npos)
        << message;
  }
}

// A report named as the model (--out cam.json --report cam) wrote its JSON over the model, and
// said the model was written: refused before the calibration, nothing written.
TEST(CliFitChoices, calibrate_refuses_a_report_named_as_the_model_n) {
  ScratchDir dir("cli");
  const auto err = dir / "stderr.txt";
  const std::string command = "cd " + q(dir.path()) + " && timeout 120 '" +
                              std::string(PYROCAM_CALIB_TOOL) +
                              "' calibrate --dataset no-dataset --out cam.json --report cam "
                              "< /dev/null > /dev/null 2> " +
                              q(err);
  const int status = std::system(command.c_str());
  EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 1);
  const std::string message = read_text(err);
  EXPECT_NE(message.find("--report cam would write cam.json over the model's cam.json"),
            std::string::npos)
      << message;
  EXPECT_FALSE(std::filesystem::exists(dir / "cam.json"));
}

}  // namespace
}  // namespace pyrocam
