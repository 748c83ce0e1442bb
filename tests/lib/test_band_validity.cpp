// complete_band_mask: a pixel is complete only when every band is a finite reading at or above
// the dim threshold.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pyrocam/band_validity.h"
#include "pyrocam/spectrum.h"

namespace pyrocam {
namespace {

TEST(BandValidity, every_band_must_be_a_reading_at_or_above_the_dim_threshold) {
  const float inf = std::numeric_limits<float>::infinity();
  const cv::Mat r = (cv::Mat_<float>(1, 6) << 100, inf, 100, 100, 20, 100);
  const cv::Mat g = (cv::Mat_<float>(1, 6) << 100, 100, NAN, 100, 20, -inf);
  const cv::Mat b = (cv::Mat_<float>(1, 6) << 100, 100, 100, 19.99f, 20, 100);
  const cv::Mat m = complete_band_mask({r, g, b}, 20);
  ASSERT_EQ(m.type(), CV_8U);
  const std::vector<int> expected = {255, 0, 0, 0, 255, 0};
  for (int x = 0; x < 6; ++x) EXPECT_EQ(m.at<std::uint8_t>(x), expected[x]) << x;
}

TEST(BandValidity, rejects_planes_that_do_not_match_n) {
  EXPECT_THROW(complete_band_mask({}, 20), InputError);
  EXPECT_THROW(complete_band_mask({cv::Mat(2, 2, CV_32F), cv::Mat(2, 3, CV_32F)}, 20), InputError);
  EXPECT_THROW(complete_band_mask({cv::Mat(2, 2, CV_8U)}, 20), InputError);
}

}  // namespace
}  // namespace pyrocam
