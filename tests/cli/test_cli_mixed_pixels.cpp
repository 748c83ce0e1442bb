// pyrocam-calib measure --mixed-pixels: demosaic25's mixed-pixel check on a simulated plate. The
// pixels whose footprint crosses the plate's edge lose their readings, the others keep theirs
// unchanged; off by default; out-of-range values are refused.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

#include "cli_support.h"
#include "pyrocam/core/image_io.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;

TEST(CliMixedPixels, measure_drops_the_plates_edge_and_keeps_its_inside) {
  const fs::path model = test_model("test-model-rgb.json");
  ASSERT_TRUE(fs::exists(model)) << model << ": " << kNoTestModels;
  ScratchDir dir{"cli-mixed"};
  write_plate(dir / "plate", "rgb-reference", 6, 1200, 100);
  const std::string base =
      "measure --model " + q(model) + " --dataset " + q(dir / "plate") +
      " --method likelihood --demosaic bilinear";  // the check is for bilinear's footprints
  ASSERT_EQ(calib(base + " --out " + q(dir / "plain")), 0);
  ASSERT_EQ(calib(base + " --mixed-pixels 0.5 --out " + q(dir / "checked")), 0);
  ASSERT_EQ(calib(base + " --mixed-pixels 0 --out " + q(dir / "off")), 0);
  const cv::Mat plain = read_raw_image(dir / "plain" / "0000_temperature.png"),
                checked = read_raw_image(dir / "checked" / "0000_temperature.png"),
                off = read_raw_image(dir / "off" / "0000_temperature.png");
  const int read_plain = cv::countNonZero(plain), read_checked = cv::countNonZero(checked);
  // The edge's pixels (about 4 of the plate's 60 or so per row and column) go, the rest stays.
  EXPECT_LT(read_checked, read_plain);
  EXPECT_GT(read_checked, read_plain / 2);
  cv::Mat kept = checked != 0, same;
  cv::compare(plain, checked, same, cv::CMP_EQ);
  EXPECT_EQ(cv::countNonZero(same & kept), read_checked);
  // Off by default: 0 reads as without the option.
  EXPECT_EQ(cv::countNonZero(plain != off), 0);
  for (const std::string bad : {"-0.1", "11"})
    EXPECT_NE(calib(base + " --mixed-pixels " + bad + " --out " + q(dir / "bad")), 0) << bad;
}

}  // namespace
}  // namespace pyrocam::test
