// pyrocam-calib simulate as a study uses it: campaigns meant as independent furnace runs.
#include <gtest/gtest.h>

#include <algorithm>

#include "cli_support.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::calib;
using test::q;
using test::read_text;
using test::ScratchDir;

// The plate's errors come from --furnace-seed: another seed draws other errors, the same seed
// the same ones.
TEST(CliSimulate, campaign_furnace_seed_draws_the_plate_errors) {
  ScratchDir dir("cli");
  const auto truth = [&](const std::string& name, int seed) {
    EXPECT_EQ(calib("simulate campaign --profile rgb-reference --temperatures 1000 1100 "
                    "--exposures 2 --frames 1 --size 16x16 --roi-area 50 --furnace-seed " +
                    std::to_string(seed) + " --out " + q(dir / name)),
              0);
    return read_text(dir / name / "furnace-truth.csv");
  };
  const std::string a = truth("a", 1), b = truth("b", 2), again = truth("again", 1);
  EXPECT_EQ(std::count(a.begin(), a.end(), '\n'), 3);  // header and two steps
  EXPECT_NE(a, b);
  EXPECT_EQ(a, again);
}

// An unsigned option would read -3 as 2^64 - 3 and write a campaign nobody asked for.
TEST(CliSimulate, campaign_rejects_a_negative_seed_n) {
  ScratchDir dir("cli");
  for (const char* option : {"--furnace-seed", "--noise-seed", "--unit-seed"}) {
    EXPECT_EQ(calib("simulate campaign --profile rgb-reference " + std::string(option) +
                    " -3 --out " + q(dir / "c")),
              2)
        << option;
    EXPECT_FALSE(std::filesystem::exists(dir / "c")) << option;
  }
}

// CLI::Range lets "nan" through and takes "inf" for a number: a campaign at an infinite
// temperature was written (its frames named T-9223372036854775808), a scene at an infinite
// exposure, and measure read with no sample marked saturated.
TEST(CliSimulate, numbers_that_are_not_finite_are_refused_n) {
  ScratchDir dir("cli");
  const std::string scene = "simulate scene --scene plate --size 16x16 --out " + q(dir / "s");
  for (const char* bad : {"--temperatures inf", "--temperatures 1000,nan", "--exposure nan",
                          "--exposure inf", "--emissivity nan"}) {
    EXPECT_EQ(calib(scene + " " + bad), 2) << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "s")) << bad;
  }
  const std::string campaign =
      "simulate campaign --profile rgb-reference --exposures 2 "
      "--frames 1 --size 16x16 --roi-area 50 --out " +
      q(dir / "c");
  for (const char* bad : {"--temperatures 1000 inf", "--first-exposure nan",
                          "--exposure-factor nan", "--exposure-factor 0.5", "--roi-area nan"}) {
    EXPECT_EQ(calib(campaign + " " + bad), 2) << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "c")) << bad;
  }
  // Trailing text after the size, and seeds past 64 bits (read as 2^64 - 1: two seeds, one unit).
  for (const char* bad :
       {"--size 16x16junk", "--size 16x16x5", "--unit-seed 99999999999999999999999",
        "--unit-seed 18446744073709551616"}) {
    EXPECT_EQ(calib(campaign + " " + bad), 2) << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "c")) << bad;
  }
  EXPECT_EQ(calib("simulate campaign --profile rgb-reference --exposures 2 --frames 1 --size 16x16 "
                  "--roi-area 50 --unit-seed 18446744073709551615 --out " +
                  q(dir / "c2")),
            0);
  // A longest exposure past the camera's 1e8 us (factor 10, 200 exposures: 1e201 us).
  EXPECT_EQ(calib("simulate campaign --profile rgb-reference --exposures 200 --exposure-factor 10 "
                  "--frames 1 --size 16x16 --roi-area 50 --out " +
                  q(dir / "c")),
            1);
  EXPECT_FALSE(std::filesystem::exists(dir / "c"));
  // A scene whose automatic exposure is past 1e8 us (a faint surface: all saturated frames once),
  // or whose exposure rounds to 0 at the manifest's 0.001 us.
  for (const char* bad : {"--emissivity 1e-9", "--exposure 1e-9"}) {
    EXPECT_EQ(calib("simulate scene --scene plate --size 16x16 --temperatures 1000 " +
                    std::string(bad) + " --out " + q(dir / "s")),
              1)
        << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "s")) << bad;
  }
  for (const char* bad : {"--saturation nan", "--saturation inf", "--mixed-pixels nan"}) {
    EXPECT_EQ(calib("measure --model " + q(test::test_model("test-model-rgb.json")) +
                    " --frame x.pgm --pattern rggb " + bad + " --out " + q(dir / "m")),
              2)
        << bad;
    EXPECT_FALSE(std::filesystem::exists(dir / "m")) << bad;
  }
}

// Temperatures as --reference takes them (comma separated) or space separated.
TEST(CliSimulate, temperatures_may_be_comma_separated) {
  ScratchDir dir("cli");
  ASSERT_EQ(calib("simulate scene --scene plate --size 16x16 --temperatures 1000,1200 --out " +
                  q(dir / "s")),
            0);
  EXPECT_TRUE(std::filesystem::exists(dir / "s" / "frames" / "0001.pgm"));
  EXPECT_FALSE(std::filesystem::exists(dir / "s" / "frames" / "0002.pgm"));
}

}  // namespace
}  // namespace pyrocam
