// The GRAY16 temperature codes (0.1 K, 0 = no reading) and the codes of temperature differences
// (uncertainty images): rounding, the reserved 0, the ends of the range, and the way back.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "pyrocam/core/error.h"
#include "pyrocam/core/temperature_codes.h"

namespace pyrocam {
namespace {

TEST(TemperatureCodes, are_tenths_of_a_kelvin_with_0_for_no_reading) {
  EXPECT_EQ(temperature_code(1200.05), 14732);  // the example in the caps documentation
  EXPECT_EQ(temperature_code(0), 2732);         // 273.15 K rounds half away from zero
  EXPECT_EQ(temperature_code(-273.05), 1);      // 0.1 K: the lowest code
  EXPECT_EQ(temperature_code(-273.15), 0);      // 0 K cannot be told from no reading
  EXPECT_EQ(temperature_code(6280.35), 65535);  // 6553.5 K: the highest code
  EXPECT_EQ(temperature_code(6280.5), 0);       // beyond it: no reading, never a wrapped code
  EXPECT_EQ(temperature_code(NAN), 0);
  EXPECT_EQ(temperature_code(std::numeric_limits<double>::infinity()), 0);
  EXPECT_TRUE(std::isnan(code_to_celsius(0)));
  EXPECT_NEAR(code_to_celsius(14732), 1200.05, 1e-9);
}

TEST(TemperatureCodes, images_round_trip_to_the_nearest_tenth) {
  const cv::Mat t = (cv::Mat_<float>(1, 5) << 726.96f, 1500.f, NAN, 7000.f, -300.f);
  const cv::Mat codes = encode_decikelvin(t);
  ASSERT_EQ(codes.type(), CV_16U);
  EXPECT_EQ(codes.at<std::uint16_t>(0), 10001);
  EXPECT_EQ(codes.at<std::uint16_t>(1), 17732);
  EXPECT_EQ(codes.at<std::uint16_t>(2), 0);
  EXPECT_EQ(codes.at<std::uint16_t>(3), 0);
  EXPECT_EQ(codes.at<std::uint16_t>(4), 0);
  const cv::Mat back = decode_decikelvin(codes);
  EXPECT_NEAR(back.at<float>(0), 726.95f, 1e-3);
  EXPECT_NEAR(back.at<float>(1), 1500.05f, 1e-3);  // 1773.15 K rounds up
  EXPECT_TRUE(std::isnan(back.at<float>(2)));
  EXPECT_THROW(decode_decikelvin(t), InputError);
  EXPECT_THROW(encode_decikelvin(codes), InputError);
}

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

TEST(Decikelvin, encodes_tenths_of_kelvin_with_zero_for_no_reading) {
  const cv::Mat t =
      (cv::Mat_<float>(1, 6) << 1200.05f, -273.15f, std::numeric_limits<float>::quiet_NaN(),
       6281.0f, 25.0f, std::numeric_limits<float>::infinity());
  const cv::Mat code = encode_decikelvin(t);
  ASSERT_EQ(code.type(), CV_16U);
  EXPECT_EQ(code.at<std::uint16_t>(0, 0), 14732);  // 1473.2 K
  EXPECT_EQ(code.at<std::uint16_t>(0, 1), 0);      // 0 K is no temperature
  EXPECT_EQ(code.at<std::uint16_t>(0, 2), 0);      // NaN: no reading
  EXPECT_EQ(code.at<std::uint16_t>(0, 3), 0);      // above 6553.5 K: no reading, not clipped
  EXPECT_EQ(code.at<std::uint16_t>(0, 4), 2982);
  EXPECT_EQ(code.at<std::uint16_t>(0, 5), 0);
  const cv::Mat back = decode_decikelvin(code);
  EXPECT_NEAR(back.at<float>(0, 0), 1200.05f, 1e-3);
  EXPECT_TRUE(std::isnan(back.at<float>(0, 2)));
  EXPECT_NEAR(back.at<float>(0, 4), 25.05f, 1e-3);
}

}  // namespace
}  // namespace pyrocam
