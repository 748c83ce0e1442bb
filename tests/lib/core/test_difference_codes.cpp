// GRAY16 codes of temperature differences (uncertainty images): rounding, the reserved 0,
// clamping, and the way back.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pyrocam/core/difference_codes.h"

namespace pyrocam {
namespace {

TEST(DifferenceCodes, rounds_to_tenths_of_a_kelvin_and_keeps_0_for_no_reading) {
  const float inf = std::numeric_limits<float>::infinity();
  const cv::Mat u =
      (cv::Mat_<float>(1, 9) << 12.34f, 12.36f, 0.01f, 0.f, 7000.f, NAN, inf, -0.5f, 3.06f);
  const cv::Mat codes = encode_decikelvin_difference(u);
  ASSERT_EQ(codes.type(), CV_16U);
  EXPECT_EQ(codes.at<std::uint16_t>(0), 123);
  EXPECT_EQ(codes.at<std::uint16_t>(1), 124);
  EXPECT_EQ(codes.at<std::uint16_t>(2), 1);  // a reading is never 0
  EXPECT_EQ(codes.at<std::uint16_t>(3), 1);
  EXPECT_EQ(codes.at<std::uint16_t>(4), 65535);  // clamped to 6553.5 K
  EXPECT_EQ(codes.at<std::uint16_t>(5), 0);
  EXPECT_EQ(codes.at<std::uint16_t>(6), 0);
  EXPECT_EQ(codes.at<std::uint16_t>(7), 0);  // a negative difference is no uncertainty
  EXPECT_EQ(codes.at<std::uint16_t>(8), 31);
  const cv::Mat back = decode_decikelvin_difference(codes);
  EXPECT_FLOAT_EQ(back.at<float>(0), 12.3f);
  EXPECT_FLOAT_EQ(back.at<float>(1), 12.4f);
  EXPECT_TRUE(std::isnan(back.at<float>(5)));
}

TEST(DifferenceCodes, works_on_views_with_row_padding) {
  cv::Mat big(4, 6, CV_32F, cv::Scalar(2.5f));
  const cv::Mat view = big(cv::Rect(1, 1, 3, 2));
  const cv::Mat codes = encode_decikelvin_difference(view);
  EXPECT_EQ(codes.size(), cv::Size(3, 2));
  EXPECT_EQ(cv::countNonZero(codes == 25), 6);
}

}  // namespace
}  // namespace pyrocam
