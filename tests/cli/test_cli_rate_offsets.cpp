// pyrocam-calib calibrate --rate-offsets: the furnace lines' offsets tested, or one per band or
// per temperature as asked, and the report naming which.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "cli_support.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::calib;
using test::q;
using test::read_text;
using test::ScratchDir;

TEST(CliRateOffsets, calibrate_tests_or_takes_the_offsets_asked_for) {
  ScratchDir dir("cli");
  ASSERT_EQ(calib("simulate campaign --profile rgb-reference --temperatures 1000 1025 1050 1075 "
                  "1100 --exposures 12 --frames 1 --size 32x32 --roi-area 200 --out " +
                  q(dir / "furnace")),
            0);
  const auto calibrate = [&](const std::string& how) {
    const std::filesystem::path model = dir / (how + ".json");
    EXPECT_EQ(calib("calibrate --dataset " + q(dir / "furnace") + " --solver datasheet " +
                    "--epochs 1 --polish-iterations 0 --mc-refits 0 --no-prebuilt-table " +
                    "--rate-offsets " + how + " --out " + q(model)),
              0)
        << how;
    const std::string words =
        nlohmann::json::parse(read_text(dir / (how + "-report.json")))["rate_offsets"];
    // The HTML report says it too (with < and > escaped).
    std::string html_words;
    for (char c : words) html_words += c == '<' ? "&lt;" : c == '>' ? "&gt;" : std::string(1, c);
    EXPECT_NE(read_text(dir / (how + "-report.html")).find(html_words), std::string::npos)
        << html_words;
    return words;
  };
  EXPECT_EQ(calibrate("common"), "one per band (as asked)");
  EXPECT_EQ(calibrate("per-step"), "one per temperature (as asked)");
  const std::string tested = calibrate("select");
  EXPECT_NE(tested.find("degrees of freedom)"), std::string::npos) << tested;
  EXPECT_TRUE(tested.rfind("one per band (chi2 ", 0) == 0 ||
              tested.rfind("one per temperature (chi2 ", 0) == 0)
      << tested;
}

TEST(CliRateOffsets, calibrate_rejects_another_rate_offsets_value_n) {
  ScratchDir dir("cli");
  EXPECT_EQ(calib("calibrate --dataset " + q(dir.path()) + " --rate-offsets zero --out " +
                  q(dir / "m.json")),
            2);
  EXPECT_FALSE(std::filesystem::exists(dir / "m.json"));
}

}  // namespace
}  // namespace pyrocam
