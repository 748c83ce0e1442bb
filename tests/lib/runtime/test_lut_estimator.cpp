// The lookup table against the network it tabulates, on noisy simulated pixels and far from the
// locus. Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "runtime/estimator_test_support.h"

namespace pyrocam::test {
namespace {

TEST(LutEstimator, gives_the_networks_answer_on_noisy_pixels) {
  const auto model = test_model("test-model-rgb.json");
  const ThermalModel& m = *model;
  const NoisyPixels px = noisy_pixels(m, kSweepC, 1500, 15, 200, saturation_signal_dn(m), 0.02, 11);
  const std::vector<cv::Mat> planes = as_planes(px);
  // Rows of band planes go to two threads: the table is filled from both at once.
  cv::Mat mlp, lut;
  PlaneEstimator(model, Method::kMlp).estimate(planes, mlp);
  const PlaneEstimator lut_estimator(model, Method::kLut);
  lut_estimator.estimate(planes, lut);
  const Agreement a = compare(mlp, lut, 0.5);
  EXPECT_EQ(a.only_reference, 0u);
  EXPECT_EQ(a.only_fast, 0u);
  // Both decisions are exercised: readings and no readings (saturated, dim, out of range).
  EXPECT_GT(a.both, px.size() / 2);
  EXPECT_GT(a.neither, px.size() / 20);
  // The stated tolerance: 0.5 degC for 99.9 % of the readings; nowhere beyond the range guard.
  EXPECT_LE(a.over_tolerance, a.both / 1000) << "largest difference " << a.max_difference_c;
  EXPECT_LT(a.max_difference_c, 2.0);
  // The same table again (now filled): the same image, and the single-pixel path agrees.
  cv::Mat again;
  lut_estimator.estimate(planes, again);
  int differ = 0;
  for (int i = 0; i < lut.cols; ++i) {
    const float x = lut.at<float>(0, i), y = again.at<float>(0, i);
    differ += !(x == y || (std::isnan(x) && std::isnan(y)));
  }
  EXPECT_EQ(differ, 0);
  for (std::size_t i = 0; i < px.size(); i += 97) {
    const double single = lut_estimator.estimator().temperature_c(px.pixel(i));
    const float image = lut.at<float>(0, static_cast<int>(i));
    if (std::isnan(image)) {
      EXPECT_TRUE(std::isnan(single)) << i;
    } else {
      EXPECT_NEAR(single, image, 1e-3) << i;
    }
  }
}

TEST(LutEstimator, answers_with_the_network_far_from_the_locus) {
  const auto model = test_model("test-model-rgb.json");
  const auto mlp = make_estimator(model, Method::kMlp);
  const auto lut = make_estimator(model, Method::kLut);
  // Ratios no graybody gives (edges of hot objects, mixed pixels): outside the table.
  const double far[][3] = {{150, 20, 150}, {20, 150, 20}, {160, 25, 21}, {21, 30, 160}};
  for (const auto& s : far) {
    const double a = mlp->temperature_c(s), b = lut->temperature_c(s);
    EXPECT_EQ(std::isnan(a), std::isnan(b));
    if (!std::isnan(a)) {
      EXPECT_NEAR(a, b, 1e-3);
    }
  }
}

TEST(LutEstimator, rejects_saturated_dim_and_invalid_bands_n) {
  const auto model = test_model("test-model-rgb.json");
  const auto lut = make_estimator(model, Method::kLut);
  const double ok[3] = {100, 120, 60}, saturated[3] = {INFINITY, 120, 60}, dim[3] = {100, 12, 60},
               nan[3] = {100, NAN, 60}, negative[3] = {100, -5, 60};
  EXPECT_TRUE(std::isfinite(lut->temperature_c(ok)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(saturated)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(dim)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(nan)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(negative)));
}

}  // namespace
}  // namespace pyrocam::test
