// Offline measurement: the 0.1 K encoding, region statistics, and frames a model must refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "pyrocam/runtime/measure.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(Decikelvin, encodes_tenths_of_kelvin_with_zero_for_no_reading) {
  const cv::Mat t = (cv::Mat_<float>(1, 6) << 1200.05f, -273.15f, kNaN, 6281.0f, 25.0f,
                     std::numeric_limits<float>::infinity());
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

// A model of the profile with the datasheet QE and an empty network (it predicts NaN): never
// asked, the frames are refused first.
ThermalModel model_of(const std::string& profile_name) {
  ThermalModel m;
  const CameraProfile p = load_profile_by_name(profile_name);
  m.camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  return m;
}

void expect_refusal(FrameMeasurer& measurer, const cv::Mat& raw, const cv::Mat& dark,
                    const std::string& fragment) {
  cv::Mat t;
  try {
    measurer.measure(raw, dark, t);
    ADD_FAILURE() << "no InputError for a frame that should mention '" << fragment << "'";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(FrameMeasurer, rejects_frames_the_models_camera_cannot_give_n) {
  const ThermalModel nir = model_of("nir5x5-reference");
  FrameMeasurer nir_measurer(nir, MeasureOptions{Method::kMlp});
  // A colour camera's 256x256 frame is no whole number of 5x5 macro-pixels.
  const cv::Mat colour_frame(256, 256, CV_8U, cv::Scalar(60));
  expect_refusal(nir_measurer, colour_frame, colour_frame, "5x5 mosaic periods");
  // 16-bit frames for an 8-bit camera.
  const cv::Mat deep(250, 250, CV_16U, cv::Scalar(60));
  expect_refusal(nir_measurer, deep, deep, "16-bit");
  // A float image is named as such, not as a 16-bit one.
  const cv::Mat floats(250, 250, CV_32F, cv::Scalar(60));
  expect_refusal(nir_measurer, floats, floats, "32F");

  const ThermalModel rgb = model_of("rgb-reference");
  FrameMeasurer rgb_measurer(rgb, MeasureOptions{Method::kMlp});
  const cv::Mat odd(255, 256, CV_8U, cv::Scalar(60));
  expect_refusal(rgb_measurer, odd, odd, "RGGB mosaic periods");
  const cv::Mat colour_image(256, 256, CV_8UC3, cv::Scalar(60, 60, 60));
  expect_refusal(rgb_measurer, colour_image, colour_image, "3-channel");
}

}  // namespace
}  // namespace pyrocam
