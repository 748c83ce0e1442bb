// Partial readings of the likelihood fit: pixels that some bands do not read (saturated, dim,
// invalid), read from the rest as the exhaustive scan reads them, only where that is safe, and
// without a bias on a uniform surface. Models: the small calibrated models the build makes
// (tests/data).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <memory>
#include <numeric>
#include <opencv2/core.hpp>
#include <vector>

#include "../true_model.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "runtime/estimator_kinds.h"
#include "runtime/estimator_test_support.h"
#include "runtime/likelihood_direct.h"
#include "runtime/likelihood_kernels.h"

namespace pyrocam::test {
namespace {

// The fast likelihood fit of a model, reading pixels with bands dropped by `rule`.
std::unique_ptr<TemperatureEstimator> partial_fit(const std::shared_ptr<const ThermalModel>& model,
                                                  TemperatureEstimator::PartialBands rule) {
  auto fit = make_estimator(model, Method::kLikelihood);
  fit->set_partial_bands(rule);
  return fit;
}

// A pixel of the 5x5 test model at a random temperature (or a mixture of two), with noise of a
// few per cent, scaled so that its `kept` dimmest bands read (the brightest of them between the
// dim threshold and 0.9 of saturation) and the others saturate; *dimmest: its dimmest band.
Eigen::VectorXd few_bands_read(const ThermalModel& m, Uniform& uniform, int kept, bool mixture,
                               int& dimmest) {
  const int bands = m.profile().band_count();
  const double dim = m.profile().thresholds.inference_dim_dn;
  const double saturated = saturation_signal_dn(m);
  const double t1 = 550 + 2900 * uniform(), t2 = 550 + 2900 * uniform();
  Eigen::VectorXd s = m.camera.rates(t1);
  if (mixture)
    s += (0.2 + uniform()) * s.maxCoeff() / m.camera.rates(t2).maxCoeff() * m.camera.rates(t2);
  for (int k = 0; k < bands; ++k) s[k] *= 1 + 0.03 * (2 * uniform() - 1);
  std::vector<int> order(static_cast<std::size_t>(bands));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) { return s[a] < s[b]; });
  s *= (dim + (0.9 * saturated - dim) * uniform()) / s[order[static_cast<std::size_t>(kept - 1)]];
  for (std::size_t k = static_cast<std::size_t>(kept); k < order.size(); ++k)
    s[order[k]] = std::numeric_limits<double>::infinity();
  dimmest = order[0];
  return s;
}

// 5x5 pixels that 2 to 16 bands read, the others saturated (the brightest, as on an
// over-exposed plate), dim or invalid: the pixels with few bands are scanned from those bands
// alone (likelihood_direct.h), the others through the factors, and each reads as the exhaustive
// scan, bit for bit; on the locus with noise and off it (a mixture of two temperatures), so
// that chi2 has one minimum, two, or none inside the range.
TEST(LikelihoodEstimator, pixels_that_few_bands_read_read_as_the_exhaustive_fit) {
  const auto model = test_model("test-model-nir5x5.json");
  const ThermalModel& m = *model;
  const int bands = m.profile().band_count();
  const BothFits fits = both_fits(model, true);
  Uniform uniform{977};
  const double dim = m.profile().thresholds.inference_dim_dn;
  std::vector<std::size_t> read_with(static_cast<std::size_t>(bands) + 1, 0);
  std::size_t pixels = 0, read = 0, disagree = 0;
  for (int i = 0; i < 6000; ++i) {
    const int kept = 2 + i % 15;
    int dimmest = 0;
    Eigen::VectorXd s = few_bands_read(m, uniform, kept, i % 4 == 3, dimmest);
    if (i % 5 == 1) s[dimmest] = std::numeric_limits<double>::quiet_NaN();
    if (i % 5 == 2) s[dimmest] = 0.3 * dim;
    ++pixels;
    const double x = fits.fast->temperature_c(s.data());
    const double e = fits.exhaustive->temperature_c(s.data());
    if (!std::isnan(e)) ++read, ++read_with[static_cast<std::size_t>(kept)];
    if (!(x == e || (std::isnan(x) && std::isnan(e))) && ++disagree < 10)
      ADD_FAILURE() << "pixel " << i << " (" << kept << " bands kept): fast " << x
                    << ", exhaustive " << e;
  }
  EXPECT_EQ(disagree, 0u);
  // Both decisions, and readings from few bands and from many.
  EXPECT_GT(read, pixels / 4);
  EXPECT_LT(read, pixels);
  for (const int kept : {3, 7, 12, 16}) EXPECT_GT(read_with[static_cast<std::size_t>(kept)], 20u);
}

// DirectChi2::coarse_span, which the scan of pixels that few bands read trusts to leave out
// most of the locus: on 5x5 pixels with 3 to 12 bands weighed (the others saturated; a quarter
// of them mixtures of two temperatures), chi2 at every sample outside the refinement windows of
// the span is at least 9 (the margin asked) above the least chi2 of the whole locus, and
// `upper` is not below that least; every pixel with a monotonic pair among its weighed bands
// gets a span, and the spans leave out most of the locus.
TEST(LikelihoodDirect, the_coarse_span_holds_every_sample_that_can_matter) {
  const auto model = test_model("test-model-nir5x5.json");
  const ThermalModel& m = *model;
  const int bands = m.profile().band_count(), width = padded_bands(bands);
  const Locus locus = make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0);
  const Eigen::Index n = locus.size();
  std::vector<double> rates(static_cast<std::size_t>(n * width), 0.0), squares(rates.size(), 0.0);
  for (Eigen::Index i = 0; i < n; ++i)
    for (int b = 0; b < bands; ++b) {
      rates[static_cast<std::size_t>(i * width + b)] = locus.rates(i, b);
      squares[static_cast<std::size_t>(i * width + b)] = locus.rates(i, b) * locus.rates(i, b);
    }
  // Monotonic pairs as the fit finds them (likelihood_fit.h).
  std::vector<std::uint8_t> monotonic(static_cast<std::size_t>(bands * bands), 0);
  for (int i = 0; i < bands; ++i)
    for (int j = 0; j < bands; ++j) {
      if (i == j) continue;
      const Eigen::ArrayXd r = locus.rates.col(i).array() / locus.rates.col(j).array();
      const Eigen::Index k = n - 1;
      const bool rising = (r.tail(k) >= r.head(k)).all(), falling = (r.tail(k) <= r.head(k)).all();
      monotonic[static_cast<std::size_t>(i * bands + j)] = (locus.rates.col(i).array() > 0).all() &&
                                                           (locus.rates.col(j).array() > 0).all() &&
                                                           (rising || falling);
    }
  constexpr Eigen::Index kCoarse = 20;
  constexpr double kMargin = 9;
  const DirectChi2 direct(rates.data(), squares.data(), width, bands, n, kCoarse, monotonic.data());
  alignas(32) double gain[kMaxBands] = {}, floor[kMaxBands] = {};
  for (int b = 0; b < bands; ++b) {
    const SignalNoise noise = signal_noise(m.profile(), b);
    gain[b] = noise.shot_gain, floor[b] = noise.floor_dn2;
  }
  const double dim = m.profile().thresholds.inference_dim_dn;
  Uniform uniform{331};
  long pixels = 0, unbounded = 0, refused = 0, outside = 0, beneath = 0;
  double span_share = 0;
  for (int p = 0; p < 1500; ++p) {
    int dimmest = 0;
    const Eigen::VectorXd s = few_bands_read(m, uniform, 3 + p % 10, p % 4 == 3, dimmest);
    alignas(32) double w[kMaxBands], ws[kMaxBands], sss = 0;
    int bright = 0;
    weigh_bands(s.data(), bands, dim, dim, gain, floor, w, ws, &sss, &bright);
    const LaneBands lanes = lane_bands(w, bands);
    if (lanes.start[4] < 2) continue;
    ++pixels;
    Eigen::Index first = -1, last = -1;
    double upper = NAN;
    if (!direct.coarse_span(lanes, ws, w, sss, kMargin, first, last, upper)) {
      ++unbounded;
      bool pair = false;
      for (int a = 0; a < lanes.start[4]; ++a)
        for (int b = 0; b < lanes.start[4]; ++b)
          pair = pair || monotonic[static_cast<std::size_t>(lanes.band[a] * bands + lanes.band[b])];
      refused += pair;
      continue;
    }
    std::vector<double> chi2(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i)
      chi2[static_cast<std::size_t>(i)] =
          profiled_chi2(&rates[static_cast<std::size_t>(i * width)],
                        &squares[static_cast<std::size_t>(i * width)], ws, w, width, sss);
    const double least = *std::min_element(chi2.begin(), chi2.end());
    beneath += upper < least;
    for (Eigen::Index i = 0; i < n; ++i)
      if ((i < kCoarse * (first - 1) || i > kCoarse * (last + 1)) &&
          chi2[static_cast<std::size_t>(i)] < least + kMargin)
        ++outside;
    span_share +=
        static_cast<double>(last - first + 1) / static_cast<double>(direct.coarse_count());
  }
  span_share /= static_cast<double>(std::max(pixels - unbounded, 1L));
  std::printf(
      "%ld pixels, %ld without a span (%ld of them with a monotonic pair); spans %.1f %% of the "
      "coarse samples on average\n",
      pixels, unbounded, refused, 100 * span_share);
  EXPECT_EQ(outside, 0);
  EXPECT_EQ(beneath, 0);
  EXPECT_GT(pixels, 1000);
  EXPECT_EQ(refused, 0);             // a span wherever a weighed pair is monotonic
  EXPECT_LT(unbounded, pixels / 4);  // measured 259 of 1488 (3 to 5 bands, none monotonic)
  EXPECT_LT(span_share, 0.4);        // measured 26.5 %
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
    const auto safe = partial_fit(model, TemperatureEstimator::PartialBands::kSafe);
    const auto any = partial_fit(model, TemperatureEstimator::PartialBands::kAny);
    const bool colour = m.profile().band_count() == 3;
    EXPECT_EQ(safe->can_read_partial(), !colour);
    std::size_t partial = 0, safe_read = 0;
    for (std::size_t i = 0; i < px.size(); ++i) {
      const double* s = px.pixel(i);
      const bool all_read = every_band_reads(m, s);
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
      partial += !every_band_reads(m, s);
    }
    ASSERT_GT(partial, 50u);
    if (colour)
      EXPECT_EQ(safe_read, 0u);
    else
      EXPECT_GT(safe_read, partial / 2);
  }
}

// The standard deviation the noise alone leaves a reading at t_c, from the Fisher information of
// the bands the fit weighs (above the no-signal level; the estimator's weights, the scale
// profiled out); infinite without any.
double fit_sigma_c(const ThermalModel& m, const double* s, double t_c) {
  const CameraProfile& p = m.profile();
  const Eigen::VectorXd rate = m.camera.rates(t_c);
  const Eigen::VectorXd slope = m.camera.rates(t_c + 0.5) - m.camera.rates(t_c - 0.5);  // per degC
  std::vector<SignalNoise> noise;
  for (int b = 0; b < p.band_count(); ++b) noise.push_back(signal_noise(p, b));
  const double weighed = std::min(p.thresholds.inference_dim_dn, no_signal_level_dn(noise));
  double wss = 0, wmm = 0, wmd = 0, wdd = 0;
  for (int b = 0; b < p.band_count(); ++b) {
    if (!(std::isfinite(s[b]) && s[b] >= weighed)) continue;
    const SignalNoise n = signal_noise(p, b);
    const double w = 1 / (n.shot_gain * s[b] + n.floor_dn2);
    wss += w * s[b] * rate[b], wmm += w * rate[b] * rate[b];
    wmd += w * rate[b] * slope[b], wdd += w * slope[b] * slope[b];
  }
  const double scale = wss / wmm;
  const double information = scale * scale * (wdd - wmd * wmd / wmm);
  return information > 0 ? 1 / std::sqrt(information) : INFINITY;
}

// Safe partial readings must also be precise. At the dim end of a melt pool a few noisy bands
// read hundreds of degrees off, within their own uncertainty: a pixel that the noise alone
// leaves more uncertain than max_partial_sigma_c (one standard deviation) has no reading. The
// estimator takes it from the fit's chi2 curvature; here it is recomputed from the model's rates,
// so pixels near the limit (where the two differ a little) are not judged.
TEST(LikelihoodEstimator, safe_partial_readings_must_be_precise) {
  const auto model = test_model("test-model-nir5x5.json");
  const ThermalModel& m = *model;
  const NoisyPixels px = noisy_pixels(m, kSweepC, 200, 10, 60, saturation_signal_dn(m), 0.6, 29);
  const auto safe = partial_fit(model, TemperatureEstimator::PartialBands::kSafe);
  const auto any = partial_fit(model, TemperatureEstimator::PartialBands::kAny);
  std::size_t kept = 0, refused = 0;
  for (std::size_t i = 0; i < px.size(); ++i) {
    const double* s = px.pixel(i);
    const bool all_read = every_band_reads(m, s);
    const double a = any->temperature_c(s), b = safe->temperature_c(s);
    if (all_read || std::isnan(a)) continue;
    const double sigma = fit_sigma_c(m, s, a);
    const double limit = TemperatureEstimator::max_partial_sigma_c(a);
    if (sigma < 0.8 * limit) {
      EXPECT_TRUE(std::isnan(b) || b == a) << i;  // NaN: no monotonic pair among the bands
      kept += b == a;
    } else if (sigma > 1.25 * limit) {
      EXPECT_TRUE(std::isnan(b)) << i << ": " << b << " degC, sigma " << sigma;
      ++refused;
    }
  }
  std::printf("kept %zu, refused %zu\n", kept, refused);
  // Both sides exercised (measured 857 kept, 278 refused).
  EXPECT_GT(kept, 100u);
  EXPECT_GT(refused, 100u);
}

// Partial readings of a uniform surface are the surface's, not a chosen few: the 5x5 camera
// (its true QE, matched demosaicking, safe partial bands) on plates exposed so that the brightest
// band sits at a fraction of its range where bands fall below the dim threshold. Two ways to get
// this wrong, both measured before: dropping a band at the dim threshold keeps it only where its
// noise is positive (1600 and 2000 degC at 0.22: +3.3 and +3.6 degC), and a precision limit in
// degrees keeps only the pixels that the noise moved lower, where the spread grows with
// temperature (2000 degC at 0.22: 8 % read, 50 degC low; 2500 degC at 0.4: 16 % read, 41 degC
// low). Now every pixel reads and the mean is within 1 degC (measured +0.3, +0.8, +0.9). Bound
// 2 degC: the standard error of a mean of about 42000 readings spread by 20-28 degC is 0.3 degC
// when counted as a quarter as many (neighbours share samples through the demosaicking kernel),
// so four of them above the largest measured.
TEST(LikelihoodEstimator, partial_readings_of_a_plate_are_the_plates) {
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  const UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  const auto model = test::true_model(p, unit);
  MeasureOptions options;
  options.method = Method::kLikelihood;
  options.demosaic = DemosaicMethod::kMatched;
  options.safe_partial = true;
  FrameMeasurer measurer(model, options);
  constexpr int kW = 320, kH = 240;
  for (const auto& [t_c, fill] : {std::pair{1600.0, 0.22}, {2000.0, 0.22}, {2500.0, 0.4}}) {
    Simulator camera(p, unit, 7);
    const cv::Mat truth(kH, kW, CV_32F, cv::Scalar(t_c));
    const double exposure =
        camera.exposure_for(t_c, fill * (p.thresholds.inference_saturation_dn - p.dark_offset_dn));
    double sum = 0;
    long pixels = 0, read = 0;
    for (int frame = 0; frame < 4; ++frame) {
      cv::Mat t;
      measurer.measure(camera.render(truth, exposure), camera.render_dark(kW, kH, exposure), t);
      for (int y = 2; y < t.rows - 2; ++y)  // away from the frame's edge
        for (int x = 2; x < t.cols - 2; ++x) {
          ++pixels;
          const float r = t.at<float>(y, x);
          if (!std::isfinite(r)) continue;
          ++read;
          sum += r - t_c;
        }
    }
    const double mean = read ? sum / static_cast<double>(read) : NAN;
    std::printf("%.0f degC, brightest band at %.2f of its range: %.1f %% read, mean error %+.2f\n",
                t_c, fill, 100.0 * static_cast<double>(read) / static_cast<double>(pixels), mean);
    EXPECT_GE(read, pixels * 95 / 100) << t_c << " degC";
    EXPECT_LE(std::abs(mean), 2.0) << t_c << " degC";
  }
}
}  // namespace
}  // namespace pyrocam::test
