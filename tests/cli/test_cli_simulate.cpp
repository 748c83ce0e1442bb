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

}  // namespace
}  // namespace pyrocam
