// The fast per-pixel estimators against their references on noisy simulated pixels: the lookup
// table against the network it tabulates, the fast likelihood fit against the exhaustive scan.
// Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/measure.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {
namespace {

// $PYROCAM_TEST_MODEL_DIR (set by meson test), else the build tree's tests/data.
ThermalModel test_model(const std::string& name) {
  const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
  return load_model(std::filesystem::path(dir && *dir ? dir : PYROCAM_TEST_MODEL_DIR_DEFAULT) /
                    name);
}

// Noisy band signals of a graybody: the brightest band at a random level, EMVA 1288 noise, bands
// at or above `saturation_dn` saturated (+INF), and now and then a band made NaN or dim.
struct NoisyPixels {
  int bands = 0;
  std::vector<double> signals;  // pixel after pixel
  std::size_t size() const { return signals.size() / static_cast<std::size_t>(bands); }
  const double* pixel(std::size_t i) const { return &signals[i * static_cast<std::size_t>(bands)]; }
};

NoisyPixels noisy_pixels(const ThermalModel& m, const std::vector<double>& temperatures_c,
                         int per_temperature, double peak_lo_dn, double peak_hi_dn,
                         double saturation_dn, double damaged_fraction, std::uint64_t seed) {
  NoisyPixels px;
  px.bands = m.profile().band_count();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> peak(peak_lo_dn, peak_hi_dn), unit(0, 1);
  for (double t : temperatures_c) {
    const Eigen::VectorXd rates = m.camera.rates(t);
    for (int k = 0; k < per_temperature; ++k) {
      const double scale = peak(rng) / rates.maxCoeff();
      for (int b = 0; b < px.bands; ++b) {
        const double mean = rates[b] * scale;
        const double v = mean + std::sqrt(signal_variance_dn2(m.profile(), b, mean)) * gauss(rng);
        px.signals.push_back(mean >= saturation_dn ? INFINITY : v);
      }
      if (unit(rng) < damaged_fraction) {
        const auto b = static_cast<std::size_t>(unit(rng) * px.bands);
        px.signals[px.signals.size() - static_cast<std::size_t>(px.bands) + b] =
            unit(rng) < 0.5 ? NAN : 5.0;
      }
    }
  }
  return px;
}

// Band planes (one row) holding the pixels, as the elements pass them.
std::vector<cv::Mat> as_planes(const NoisyPixels& px) {
  std::vector<cv::Mat> planes;
  for (int b = 0; b < px.bands; ++b) {
    cv::Mat p(1, static_cast<int>(px.size()), CV_32F);
    for (std::size_t i = 0; i < px.size(); ++i)
      p.at<float>(0, static_cast<int>(i)) = static_cast<float>(px.pixel(i)[b]);
    planes.push_back(p);
  }
  return planes;
}

struct Agreement {
  std::size_t both = 0, neither = 0, only_reference = 0, only_fast = 0, over_tolerance = 0;
  double max_difference_c = 0;
};

Agreement compare(const cv::Mat& reference, const cv::Mat& fast, double tolerance_c) {
  Agreement a;
  for (int i = 0; i < reference.cols; ++i) {
    const float r = reference.at<float>(0, i), f = fast.at<float>(0, i);
    if (std::isfinite(r) && std::isfinite(f)) {
      ++a.both;
      const double d = std::abs(static_cast<double>(r) - f);
      a.max_difference_c = std::max(a.max_difference_c, d);
      if (d > tolerance_c) ++a.over_tolerance;
    } else if (std::isfinite(r)) {
      ++a.only_reference;
    } else if (std::isfinite(f)) {
      ++a.only_fast;
    } else {
      ++a.neither;
    }
  }
  return a;
}

const std::vector<double> kSweepC = {650, 900, 1200, 1500, 1800, 2200, 2700, 3200, 3450};

TEST(LutEstimator, gives_the_networks_answer_on_noisy_pixels) {
  const ThermalModel m = test_model("test-model-rgb.json");
  const double saturation =
      m.profile().thresholds.inference_saturation_dn - m.profile().dark_offset_dn;
  const NoisyPixels px = noisy_pixels(m, kSweepC, 1500, 15, 200, saturation, 0.02, 11);
  const std::vector<cv::Mat> planes = as_planes(px);
  // Rows of band planes go to two threads: the table is filled from both at once.
  cv::Mat mlp, lut;
  PlaneEstimator(m, Method::kMlp).estimate(planes, mlp);
  const PlaneEstimator lut_estimator(m, Method::kLut);
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
  const ThermalModel m = test_model("test-model-rgb.json");
  const auto mlp = make_estimator(m, Method::kMlp);
  const auto lut = make_estimator(m, Method::kLut);
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
  const ThermalModel m = test_model("test-model-rgb.json");
  const auto lut = make_estimator(m, Method::kLut);
  const double ok[3] = {100, 120, 60}, saturated[3] = {INFINITY, 120, 60}, dim[3] = {100, 12, 60},
               nan[3] = {100, NAN, 60}, negative[3] = {100, -5, 60};
  EXPECT_TRUE(std::isfinite(lut->temperature_c(ok)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(saturated)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(dim)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(nan)));
  EXPECT_TRUE(std::isnan(lut->temperature_c(negative)));
}

// With saturated, NaN and dim bands among them: the fit drops bands (partial readings allowed),
// and with two left the locus may pass the same ratios twice (an ambiguous reading). Without
// partial readings the pixels with such bands have none, and the others read as with them.
void expect_fast_fit_is_exhaustive_fit(const ThermalModel& m, std::uint64_t seed) {
  const double saturation =
      m.profile().thresholds.inference_saturation_dn - m.profile().dark_offset_dn;
  const NoisyPixels px = noisy_pixels(m, kSweepC, 400, 8, 400, saturation, 0.1, seed);
  const auto fast = make_estimator(m, Method::kLikelihood);
  const auto exhaustive = make_exhaustive_likelihood_estimator(m);
  const auto strict = make_estimator(m, Method::kLikelihood);
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
  const ThermalModel m = test_model("test-model-nir5x5.json");
  const auto fast = make_estimator(m, Method::kLikelihood);
  fast->set_allow_partial(true);
  std::vector<double> s(25, INFINITY);
  s[3] = 100;
  EXPECT_TRUE(std::isnan(fast->temperature_c(s.data())));
  std::fill(s.begin(), s.end(), NAN);
  EXPECT_TRUE(std::isnan(fast->temperature_c(s.data())));
}

TEST(PlaneEstimator, codes_straight_from_the_planes_are_the_encoded_temperatures) {
  const ThermalModel m = test_model("test-model-rgb.json");
  const double saturation =
      m.profile().thresholds.inference_saturation_dn - m.profile().dark_offset_dn;
  // A few hundred rows of a realistic width, so that rows go to several threads.
  const NoisyPixels px = noisy_pixels(m, {900, 1500, 2400}, 600, 15, 200, saturation, 0.05, 3);
  std::vector<cv::Mat> planes;
  for (const cv::Mat& p : as_planes(px)) planes.push_back(p.reshape(1, 450));
  for (Method method : {Method::kLut, Method::kLikelihood}) {
    const PlaneEstimator estimator(m, method);
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

}  // namespace
}  // namespace pyrocam
