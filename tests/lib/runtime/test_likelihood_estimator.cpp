// The fast likelihood fit against the exhaustive scan on noisy simulated pixels, with saturated,
// dim and NaN bands. Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/runtime/estimators.h"
#include "runtime/estimator_test_support.h"

namespace pyrocam::test {
namespace {

// With saturated, NaN and dim bands among them: the fit drops bands (partial readings allowed),
// and with two left the locus may pass the same ratios twice (an ambiguous reading). Without
// partial readings the pixels with such bands have none, and the others read as with them.
void expect_fast_fit_is_exhaustive_fit(const std::shared_ptr<const ThermalModel>& model,
                                       std::uint64_t seed) {
  const ThermalModel& m = *model;
  const NoisyPixels px = noisy_pixels(m, kSweepC, 400, 8, 400, saturation_signal_dn(m), 0.1, seed);
  const auto fast = make_estimator(model, Method::kLikelihood);
  const auto exhaustive = make_exhaustive_likelihood_estimator(model);
  const auto strict = make_estimator(model, Method::kLikelihood);
  fast->set_allow_partial(true);
  exhaustive->set_allow_partial(true);
  cv::Mat f(1, static_cast<int>(px.size()), CV_32F), e(f.size(), CV_32F);
  std::size_t complete = 0;
  for (std::size_t i = 0; i < px.size(); ++i) {
    const double reading = fast->temperature_c(px.pixel(i));
    f.at<float>(0, static_cast<int>(i)) = static_cast<float>(reading);
    e.at<float>(0, static_cast<int>(i)) =
        static_cast<float>(exhaustive->temperature_c(px.pixel(i)));
    const double* s = px.pixel(i);
    const bool all_read = std::all_of(s, s + px.bands, [&](double v) {
      return std::isfinite(v) && v >= m.profile().thresholds.inference_dim_dn;
    });
    const double strict_reading = strict->temperature_c(s);
    if (!all_read) {
      EXPECT_TRUE(std::isnan(strict_reading)) << "pixel " << i;
    } else {
      ++complete;
      EXPECT_TRUE(strict_reading == reading || (std::isnan(strict_reading) && std::isnan(reading)))
          << "pixel " << i;
    }
  }
  EXPECT_GT(complete, px.size() / 10);  // both cases exercised
  EXPECT_LT(complete, px.size());
  const Agreement a = compare(e, f, 0.01);
  EXPECT_EQ(a.only_reference, 0u);
  EXPECT_EQ(a.only_fast, 0u);
  EXPECT_EQ(a.over_tolerance, 0u) << "largest difference " << a.max_difference_c;
  // Both decisions are exercised.
  EXPECT_GT(a.both, px.size() / 4);
  EXPECT_GT(a.neither, px.size() / 50);
}

TEST(LikelihoodEstimator, fast_fit_gives_the_exhaustive_fits_answer_colour) {
  expect_fast_fit_is_exhaustive_fit(test_model("test-model-rgb.json"), 5);
}

TEST(LikelihoodEstimator, fast_fit_gives_the_exhaustive_fits_answer_5x5) {
  expect_fast_fit_is_exhaustive_fit(test_model("test-model-nir5x5.json"), 6);
}

TEST(LikelihoodEstimator, one_valid_band_is_no_reading_n) {
  const auto fast = make_estimator(test_model("test-model-nir5x5.json"), Method::kLikelihood);
  fast->set_allow_partial(true);
  std::vector<double> s(25, INFINITY);
  s[3] = 100;
  EXPECT_TRUE(std::isnan(fast->temperature_c(s.data())));
  std::fill(s.begin(), s.end(), NAN);
  EXPECT_TRUE(std::isnan(fast->temperature_c(s.data())));
}

// Safe partial readings: a pixel with unusable bands reads from the rest only when two of them
// have a ratio monotonic over the model's range. The shipped colour camera has no such pair
// (each of its ratios turns over), the 5x5 one has many: its dim-band pixels read, and as
// the fit with any bands reads them (the rule only decides whether).
TEST(LikelihoodEstimator, safe_partial_readings_need_a_monotonic_pair) {
  for (const char* name : {"test-model-rgb.json", "test-model-nir5x5.json"}) {
    SCOPED_TRACE(name);
    const auto model = test_model(name);
    const ThermalModel& m = *model;
    const NoisyPixels px = noisy_pixels(m, kSweepC, 100, 30, 200, saturation_signal_dn(m), 0.3, 17);
    const auto safe = make_estimator(model, Method::kLikelihood);
    const auto any = make_estimator(model, Method::kLikelihood);
    safe->set_partial_bands(TemperatureEstimator::PartialBands::kSafe);
    any->set_partial_bands(TemperatureEstimator::PartialBands::kAny);
    const bool colour = m.profile().band_count() == 3;
    EXPECT_EQ(safe->can_read_partial(), !colour);
    std::size_t partial = 0, safe_read = 0;
    for (std::size_t i = 0; i < px.size(); ++i) {
      const double* s = px.pixel(i);
      const bool all_read = std::all_of(s, s + px.bands, [&](double v) {
        return std::isfinite(v) && v >= m.profile().thresholds.inference_dim_dn;
      });
      const double a = any->temperature_c(s), b = safe->temperature_c(s);
      if (all_read || std::isnan(b)) {
        if (all_read) {
          EXPECT_EQ(std::isnan(a), std::isnan(b)) << i;
        }
        continue;
      }
      ++safe_read;
      EXPECT_EQ(a, b) << i;  // the same fit: the rule only decides whether it reads
    }
    for (std::size_t i = 0; i < px.size(); ++i) {
      const double* s = px.pixel(i);
      partial += !std::all_of(s, s + px.bands, [&](double v) {
        return std::isfinite(v) && v >= m.profile().thresholds.inference_dim_dn;
      });
    }
    ASSERT_GT(partial, 50u);
    if (colour)
      EXPECT_EQ(safe_read, 0u);
    else
      EXPECT_GT(safe_read, partial / 2);
  }
}

}  // namespace
}  // namespace pyrocam::test
