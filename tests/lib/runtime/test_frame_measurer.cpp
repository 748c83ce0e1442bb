// Offline measurement of raw frames: frames a model must refuse.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

// A model of the profile with the datasheet QE and an empty network (it predicts NaN): never
// asked, the frames are refused first.
std::shared_ptr<const ThermalModel> model_of(const std::string& profile_name) {
  auto m = std::make_shared<ThermalModel>();
  const CameraProfile p = load_profile_by_name(profile_name);
  m->camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
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
  const auto nir = model_of("nir5x5-reference");
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

  const auto rgb = model_of("rgb-reference");
  FrameMeasurer rgb_measurer(rgb, MeasureOptions{Method::kMlp});
  const cv::Mat odd(255, 256, CV_8U, cv::Scalar(60));
  expect_refusal(rgb_measurer, odd, odd, "RGGB mosaic periods");
  const cv::Mat colour_image(256, 256, CV_8UC3, cv::Scalar(60, 60, 60));
  expect_refusal(rgb_measurer, colour_image, colour_image, "3-channel");
}

TEST(FrameMeasurer, refuses_no_model_n) {
  EXPECT_THROW(FrameMeasurer(nullptr, MeasureOptions{}), InputError);
}

}  // namespace
}  // namespace pyrocam
