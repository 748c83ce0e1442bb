// pyrocam-calib calibrate --leak-terms: the regularised QE fit's leaks chosen by the data, or
// always kept or dropped, and the report naming what the fit did.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "cli_support.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::calib;
using test::q;
using test::read_text;
using test::ScratchDir;

// The regularised solver's row of the report's solver table.
std::string leak_terms_in_report(const std::filesystem::path& report_json) {
  const nlohmann::json j = nlohmann::json::parse(read_text(report_json));
  for (const auto& s : j["solvers"])
    if (s["solver"] == "regularised") return s["leak_terms"].get<std::string>();
  return "(no regularised solver in the report)";
}

TEST(CliLeakTerms, calibrate_selects_keeps_or_drops_the_leak_terms) {
  ScratchDir dir("cli");
  ASSERT_EQ(calib("simulate campaign --profile rgb-reference --temperatures 1000 1025 1050 1075 "
                  "1100 --exposures 3 --frames 1 --size 32x32 --roi-area 200 --out " +
                  q(dir / "furnace")),
            0);
  const auto calibrate = [&](const std::string& how) {
    const std::filesystem::path model = dir / (how + ".json");
    EXPECT_EQ(calib("calibrate --dataset " + q(dir / "furnace") + " --solver regularised " +
                    "--epochs 1 --polish-iterations 0 --mc-refits 0 --no-prebuilt-table " +
                    "--leak-terms " + how + " --out " + q(model)),
              0)
        << how;
    return leak_terms_in_report(dir / (how + "-report.json"));
  };
  // Kept or dropped as told, without a test to report.
  EXPECT_EQ(calibrate("keep"), "kept");
  EXPECT_EQ(calibrate("drop"), "dropped");
  // Selected: the decision with the test's figures.
  const std::string selected = calibrate("select");
  EXPECT_NE(selected.find("chi2 gain"), std::string::npos) << selected;
  EXPECT_TRUE(selected.rfind("kept", 0) == 0 || selected.rfind("dropped", 0) == 0) << selected;
}

TEST(CliLeakTerms, calibrate_rejects_another_leak_terms_value_n) {
  ScratchDir dir("cli");
  EXPECT_EQ(calib("calibrate --dataset " + q(dir.path()) + " --leak-terms sometimes --out " +
                  q(dir / "m.json")),
            2);
  EXPECT_FALSE(std::filesystem::exists(dir / "m.json"));
}

}  // namespace
}  // namespace pyrocam
