// Region statistics of a temperature image: median, extremes, mean and valid fraction in a mask.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "pyrocam/runtime/region_stats.h"

namespace pyrocam {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(RegionStats, median_min_max_mean_and_valid_fraction_inside_a_mask) {
  const cv::Mat t = (cv::Mat_<float>(2, 4) << 1000, 1010, kNaN, 990, 2000, 5, 1020, kNaN);
  const cv::Mat mask = (cv::Mat_<std::uint8_t>(2, 4) << 1, 1, 1, 1, 0, 0, 1, 1);
  const RegionStats s = region_stats(t, mask);
  EXPECT_EQ(s.pixels, 6u);
  EXPECT_EQ(s.valid, 4u);
  EXPECT_DOUBLE_EQ(s.valid_fraction, 4.0 / 6.0);
  EXPECT_DOUBLE_EQ(s.min_c, 990);
  EXPECT_DOUBLE_EQ(s.max_c, 1020);
  EXPECT_DOUBLE_EQ(s.mean_c, 1005);
  EXPECT_DOUBLE_EQ(s.median_c, 1005);  // even count: mean of the middle two
  const RegionStats all = region_stats(t);
  EXPECT_EQ(all.pixels, 8u);
  EXPECT_DOUBLE_EQ(all.median_c, 1005);  // 5, 990, 1000, 1010, 1020, 2000
  EXPECT_DOUBLE_EQ(all.max_c, 2000);
  const RegionStats none = region_stats(cv::Mat(2, 2, CV_32F, cv::Scalar(kNaN)));
  EXPECT_EQ(none.valid, 0u);
  EXPECT_TRUE(std::isnan(none.median_c));
}

}  // namespace
}  // namespace pyrocam
