// The plane estimator: temperature codes straight from the planes, and the model it shares.
// Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <memory>
#include <opencv2/core.hpp>

#include "pyrocam/core/error.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "runtime/estimator_test_support.h"

namespace pyrocam::test {
namespace {

TEST(PlaneEstimator, codes_straight_from_the_planes_are_the_encoded_temperatures) {
  const auto model = test_model("test-model-rgb.json");
  const ThermalModel& m = *model;
  // A few hundred rows of a realistic width, so that rows go to several threads.
  const NoisyPixels px =
      noisy_pixels(m, {900, 1500, 2400}, 600, 15, 200, saturation_signal_dn(m), 0.05, 3);
  std::vector<cv::Mat> planes;
  for (const cv::Mat& p : as_planes(px)) planes.push_back(p.reshape(1, 450));
  for (Method method : {Method::kLut, Method::kLikelihood}) {
    const PlaneEstimator estimator(model, method);
    cv::Mat t, codes;
    estimator.estimate(planes, t);
    estimator.estimate_codes(planes, codes);
    const cv::Mat expected = encode_decikelvin(t);
    ASSERT_EQ(codes.type(), CV_16U);
    ASSERT_EQ(codes.size(), expected.size());
    EXPECT_EQ(cv::countNonZero(codes != expected), 0) << method_name(method);
    EXPECT_GT(cv::countNonZero(codes), static_cast<int>(codes.total() / 4)) << method_name(method);
  }
}

TEST(PlaneEstimator, refuses_no_model_n) {
  EXPECT_THROW(PlaneEstimator(nullptr, Method::kMlp), InputError);
}

TEST(PlaneEstimator, keeps_the_model_it_shares_alive) {
  auto model = std::make_shared<const ThermalModel>(*test_model("test-model-rgb.json"));
  const PlaneEstimator estimator(model, Method::kLikelihood, 1e-6);
  std::weak_ptr<const ThermalModel> watch = model;
  model.reset();
  EXPECT_FALSE(watch.expired());  // the estimator, its fit and its check still hold it
  const NoisyPixels px =
      noisy_pixels(estimator.estimator().model(), {1500}, 20, 100, 150, 1e9, 0, 1);
  cv::Mat t;
  estimator.estimate(as_planes(px), t);
  EXPECT_GT(cv::countNonZero(t == t), 10);  // readings, from the model no caller holds
}

}  // namespace
}  // namespace pyrocam::test
