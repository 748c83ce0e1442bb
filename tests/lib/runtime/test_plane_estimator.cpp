// The plane estimator: temperature codes straight from the planes, the model it shares, and
// the analogue gain's noise.
// Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/core.hpp>
#include <thread>

#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
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

TEST(PlaneEstimator, an_analogue_gain_grows_the_uncertainty_not_the_reading) {
  // The same DN taken at 12 dB hold a quarter of the electrons: the shot-noise variance per DN
  // is 3.98 times as large. Readings by ratio stay; the likelihood fit's shot-noise weights scale
  // by the same factor in every band (the read-noise floor does not), so its readings move
  // little; the uncertainty's noise term grows, its calibration term stays.
  const auto model = test_model("test-model-rgb.json");
  const NoisyPixels px = noisy_pixels(*model, {1000, 1400}, 50, 100, 150, 1e9, 0, 5);
  const std::vector<cv::Mat> planes = as_planes(px);
  for (Method method : {Method::kMlp, Method::kLikelihood}) {
    SCOPED_TRACE(method_name(method));
    PlaneEstimator estimator(model, method, 1e-6);
    cv::Mat t0, u0, t12, u12;
    estimator.estimate(planes, t0, &u0);
    estimator.set_analogue_gain(std::pow(10.0, 12.0 / 20));
    EXPECT_DOUBLE_EQ(estimator.analogue_gain(), std::pow(10.0, 12.0 / 20));
    estimator.estimate(planes, t12, &u12);
    int compared = 0;
    for (int i = 0; i < t0.cols; ++i) {
      const float a = t0.at<float>(0, i), b = t12.at<float>(0, i);
      if (!std::isfinite(a) || !std::isfinite(b)) continue;
      ++compared;
      if (method == Method::kMlp) {
        EXPECT_EQ(a, b);
      }
      // The fit's weights change a little band against band (the floor stays): a move well
      // inside the reading's noise.
      EXPECT_NEAR(a, b, 0.1 * u0.at<float>(0, i));
      EXPECT_GT(u12.at<float>(0, i), u0.at<float>(0, i));
    }
    EXPECT_GT(compared, 50);
    // Back to 0 dB: the readings and uncertainties of the start again.
    estimator.set_analogue_gain(1.0);
    cv::Mat t1, u1;
    estimator.estimate(planes, t1, &u1);
    EXPECT_EQ(cv::countNonZero((t1 != t0) & (t0 == t0)), 0);
    EXPECT_EQ(cv::countNonZero((u1 != u0) & (u0 == u0)), 0);
    EXPECT_THROW(estimator.set_analogue_gain(0), InputError);
    EXPECT_THROW(estimator.set_analogue_gain(NAN), InputError);
  }
}

// Bit-for-bit equality of two CV_32F images, NaN at the same places.
int differing(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat marks;
  cv::compare(a != a, b != b, marks, cv::CMP_NE);
  cv::Mat x = a.clone(), y = b.clone();
  cv::patchNaNs(x, -1);
  cv::patchNaNs(y, -1);
  return cv::countNonZero(marks) + cv::countNonZero(x != y);
}

// The fused path (strips demosaicked and read while in cache, dark blocks skipped) gives what
// demosaicking the whole frame and reading its planes gives: temperatures, uncertainties and
// codes, for every method and the settings that change what a pixel reads. Simulated frames of
// an odd size with a saturated melt pool (and its dim rim) on a cold background and a plate
// with noise, exposure and analogue gain varied.
TEST(PlaneEstimator, the_fused_path_reads_what_the_planes_read) {
  const auto model = test_model("test-model-rgb.json");
  const CameraProfile& p = model->profile();
  Simulator camera(p, UnitPerturbation::parse("typical", 2), 5);
  std::vector<SignalNoise> noise;
  for (int b = 0; b < p.band_count(); ++b) noise.push_back(signal_noise(p, b));
  const float no_signal = static_cast<float>(no_signal_level_dn(noise));
  std::vector<cv::Mat> mosaics;
  for (int i : {2, 7}) {
    const cv::Mat raw =
        camera.render(melt_pool_scene(331, 131, i, 10), camera.exposure_for(1800, 150, 0.35), 0.35);
    mosaics.emplace_back();
    subtract_dark_level(raw, p.dark_offset_dn, p.thresholds.inference_saturation_dn,
                        mosaics.back());
  }
  const cv::Mat plate = camera.render(plate_scene(203, 97, 1300), camera.exposure_for(1300, 120));
  mosaics.emplace_back();
  subtract_dark_level(plate, p.dark_offset_dn, p.thresholds.inference_saturation_dn,
                      mosaics.back());
  struct Setting {
    Method method;
    TemperatureEstimator::PartialBands partial;
    double misfit, slope, gain;
  };
  using Partial = TemperatureEstimator::PartialBands;
  for (const Setting& s : {Setting{Method::kLut, Partial::kSafe, 0, 0, 1},
                           Setting{Method::kLut, Partial::kAny, 1e-3, 0, 2},
                           Setting{Method::kLikelihood, Partial::kAny, 0, 0.02, 1},
                           Setting{Method::kLikelihood, Partial::kOff, 1e-3, 0, 1},
                           Setting{Method::kMlp, Partial::kSafe, 0, -0.01, 1}}) {
    SCOPED_TRACE(method_name(s.method));
    PlaneEstimator estimator(model, s.method, s.misfit);
    estimator.set_partial_bands(s.partial);
    estimator.set_emissivity_slope(s.slope, s.slope != 0 ? 0.01 : -1);
    estimator.set_analogue_gain(s.gain);
    // The planes' noise as matched demosaicking leaves it (the fused path's own).
    estimator.set_demosaic_noise(demosaic_noise(p.mosaic, DemosaicMethod::kMatched));
    for (const cv::Mat& mosaic : mosaics) {
      const PlaneEstimator::MatchedMosaic fused{mosaic, p.mosaic, no_signal};
      std::vector<cv::Mat> planes;
      demosaic(mosaic, p.mosaic, DemosaicMethod::kMatched, planes, no_signal);
      cv::Mat t, u, codes, t_fused, u_fused, codes_fused;
      estimator.set_dim_edge_mosaic(&fused);  // the dim-edge check's ring from the mosaic
      estimator.estimate(planes, t, &u);
      estimator.estimate_codes(planes, codes);
      estimator.set_dim_edge_mosaic(nullptr);
      estimator.estimate(fused, t_fused, &u_fused);
      estimator.estimate_codes(fused, codes_fused);
      EXPECT_EQ(differing(t, t_fused), 0);
      EXPECT_EQ(differing(u, u_fused), 0);
      ASSERT_EQ(codes_fused.type(), CV_16U);
      EXPECT_EQ(cv::countNonZero(codes != codes_fused), 0);
      EXPECT_GT(cv::countNonZero(codes), 30);        // something read
      EXPECT_GT(cv::countNonZero(codes == 0), 100);  // and something did not
    }
  }
}

TEST(PlaneEstimator, the_fused_path_refuses_what_it_cannot_read) {
  const auto model = test_model("test-model-rgb.json");
  const PlaneEstimator estimator(model, Method::kLut);
  cv::Mat t, codes;
  std::vector<int> map(25);
  for (int i = 0; i < 25; ++i) map[static_cast<std::size_t>(i)] = i;
  const cv::Mat mosaic(20, 20, CV_32F, cv::Scalar(50));
  EXPECT_THROW(estimator.estimate_codes({mosaic, MosaicLayout::snapshot(5, 5, map), 5}, codes),
               InputError);
  EXPECT_THROW(estimator.estimate({cv::Mat(20, 20, CV_8U), MosaicLayout::bayer("RGGB"), 5}, t),
               InputError);
  const auto nir = test_model("test-model-nir5x5.json");
  EXPECT_THROW(PlaneEstimator(nir, Method::kLikelihood)
                   .estimate_codes({mosaic, MosaicLayout::bayer("RGGB"), 5}, codes),
               InputError);
}

// The fit audit: a reading of every 16th row checked against the model's spectra. Noisy
// graybody pixels fit (at 1e-9 and 5 % model error a true graybody pixel fails about once in
// 10^9); the same pixels with their bands one place further on (a 5x5 mosaic cropped by a
// column) read too, and most of the checked ones misfit. (The colour camera's bands traded
// often land on its locus elsewhere, one degree of freedom: darksub's green check guards it.)
TEST(PlaneEstimator, the_fit_audit_tells_bands_in_the_wrong_places) {
  const auto model = test_model("test-model-nir5x5.json");
  const NoisyPixels px =
      noisy_pixels(*model, {900, 1500, 2400}, 400, 60, 200, saturation_signal_dn(*model), 0, 3);
  std::vector<cv::Mat> planes;
  for (const cv::Mat& p : as_planes(px)) planes.push_back(p.reshape(1, 60));
  const PlaneEstimator estimator(model, Method::kLikelihood);
  cv::Mat t;
  estimator.estimate(planes, t);
  // The first call starts making the check; until it is made nothing is counted.
  EXPECT_EQ(estimator.take_fit_audit().checked, 0u);
  for (int tries = 0; tries < 600 && estimator.take_fit_audit().checked == 0; ++tries) {
    estimator.estimate(planes, t);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  // The counts add up over frames until taken: four frames of 60 rows, 15 audited rows.
  for (int frame = 0; frame < 4; ++frame) estimator.estimate(planes, t);
  const PlaneEstimator::FitAudit fitting = estimator.take_fit_audit();
  EXPECT_GE(fitting.checked, 10u);  // a reading in each audited row, nearly
  EXPECT_EQ(fitting.misfit, 0u);
  EXPECT_EQ(estimator.take_fit_audit().checked, 0u);  // taken: counted afresh
  std::vector<cv::Mat> shifted = planes;
  std::rotate(shifted.begin(), shifted.begin() + 1, shifted.end());
  for (int frame = 0; frame < 4; ++frame) estimator.estimate(shifted, t);
  const PlaneEstimator::FitAudit misplaced = estimator.take_fit_audit();
  EXPECT_GE(misplaced.checked, 10u);
  EXPECT_GT(2 * misplaced.misfit, misplaced.checked);
  std::printf("fit audit: %zu of %zu checked misfit; bands shifted: %zu of %zu\n", fitting.misfit,
              fitting.checked, misplaced.misfit, misplaced.checked);
}

// The brightness count: a plate of emissivity 0.8 whose signals are what the model's rates give
// at the frames' exposure is never too bright; its red and blue traded (a bggr sensor read as
// rggb) read a colder temperature on the locus, about ten thousand times too bright for
// it. Without the exposure nothing is counted.
TEST(PlaneEstimator, the_fit_audit_counts_readings_brighter_than_a_black_body) {
  const auto model = test_model("test-model-rgb.json");
  const Locus locus = make_locus(model->camera, 1300, 1300, 1);
  const double exposure_s = 150 / (0.8 * locus.rates.row(0).maxCoeff());
  std::vector<cv::Mat> planes;
  for (int b = 0; b < 3; ++b)
    planes.emplace_back(64, 64, CV_32F, cv::Scalar(0.8 * locus.rates(0, b) * exposure_s));
  std::vector<cv::Mat> traded = {planes[2], planes[1], planes[0]};
  PlaneEstimator estimator(model, Method::kLikelihood);
  cv::Mat t;
  estimator.estimate(planes, t);
  estimator.take_fit_audit(true);  // made: counted from now on
  const auto audit = [&](const std::vector<cv::Mat>& p, double exposure_us) {
    estimator.set_exposure_us(exposure_us);
    estimator.estimate(p, t);
    return estimator.take_fit_audit();
  };
  const PlaneEstimator::FitAudit right = audit(planes, exposure_s * 1e6);
  EXPECT_NEAR(t.at<float>(32, 32), 1300, 1);
  EXPECT_GE(right.checked, 3u);
  EXPECT_EQ(right.too_bright, 0u);
  const PlaneEstimator::FitAudit wrong = audit(traded, exposure_s * 1e6);
  const float read = t.at<float>(32, 32);
  EXPECT_LT(read, 900);  // a reading, and far too cold
  EXPECT_GE(wrong.checked, 3u);
  EXPECT_EQ(wrong.too_bright, wrong.checked) << "read " << read;
  EXPECT_EQ(audit(traded, 0).too_bright, 0u);
  EXPECT_EQ(audit(traded, NAN).too_bright, 0u);
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
