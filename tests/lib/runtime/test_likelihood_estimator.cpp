// The fast likelihood fit against the exhaustive scan on noisy simulated pixels, with saturated,
// dim and NaN bands. Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

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
#include "runtime/likelihood_kernels.h"

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
    const bool all_read = every_band_reads(m, s);
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

// Pixels that put the fast fit's bounds on the spot, each read by both fits, bit for bit:
//  - noise-free pixels on the locus halfway between coarse samples (two coarse samples fit
//    almost equally well: their bounds overlap, the exact chi2 decides) and at every offset
//    from a coarse sample (the refinement's best sample anywhere in its window);
//  - near and at the locus ends (no reading at an end sample);
//  - with all but two bands dropped (partial readings: the locus may pass the same ratios
//    twice, two minima, an ambiguous reading) and very dim (flat chi2, many candidates).
void expect_same_on_edge_pixels(const std::shared_ptr<const ThermalModel>& model) {
  const ThermalModel& m = *model;
  const int bands = m.profile().band_count();
  const auto fast = make_estimator(model, Method::kLikelihood);
  const auto exhaustive = make_exhaustive_likelihood_estimator(model);
  fast->set_allow_partial(true);
  exhaustive->set_allow_partial(true);
  const double lo = m.min_temperature_c, hi = m.max_temperature_c;
  std::vector<double> temperatures;
  for (double t = lo; t <= lo + 45; t += 0.5) temperatures.push_back(t);
  for (double t = hi - 45; t <= hi; t += 0.5) temperatures.push_back(t);
  for (double t = lo + 200; t < hi - 200; t += 137.25) temperatures.push_back(t);
  for (int k = 1; k < 20; ++k) temperatures.push_back(lo + 1000 + k);  // each window offset
  const double saturation = saturation_signal_dn(m);
  std::size_t read = 0, no_reading = 0, disagree = 0;
  Uniform uniform{12345};
  for (double t : temperatures) {
    const Eigen::VectorXd rates = m.camera.rates(t);
    for (int variant = 0; variant < 6; ++variant) {
      // Brightest band at 0.6 of saturation, 0.01 of it (dim), or in between.
      const double peak = variant == 1 ? 0.01 * saturation : (0.05 + 0.55 * uniform()) * saturation;
      std::vector<double> s(static_cast<std::size_t>(bands));
      for (int b = 0; b < bands; ++b)
        s[static_cast<std::size_t>(b)] = peak * rates[b] / rates.maxCoeff();
      if (variant >= 3) {  // two bands left
        const int keep1 = static_cast<int>(uniform() * bands);
        const int keep2 = (keep1 + 1 + static_cast<int>(uniform() * (bands - 1))) % bands;
        for (int b = 0; b < bands; ++b)
          if (b != keep1 && b != keep2)
            s[static_cast<std::size_t>(b)] = variant == 3 ? NAN : INFINITY;
      }
      const double a = fast->temperature_c(s.data()), e = exhaustive->temperature_c(s.data());
      if (std::isnan(e))
        ++no_reading;
      else
        ++read;
      if (!(a == e || (std::isnan(a) && std::isnan(e)))) {
        ++disagree;
        ADD_FAILURE() << t << " degC, variant " << variant << ": fast " << a << ", exhaustive "
                      << e;
      }
    }
  }
  EXPECT_EQ(disagree, 0u);
  EXPECT_GT(read, temperatures.size());  // both decisions exercised
  EXPECT_GT(no_reading, temperatures.size() / 10);
}

TEST(LikelihoodEstimator, fast_fit_is_the_exhaustive_fit_on_edge_pixels_colour) {
  expect_same_on_edge_pixels(test_model("test-model-rgb.json"));
}

TEST(LikelihoodEstimator, fast_fit_is_the_exhaustive_fit_on_edge_pixels_5x5) {
  expect_same_on_edge_pixels(test_model("test-model-nir5x5.json"));
}

// Two minima whose chi2 differ by about the ambiguity margin: three bands read, two of them a
// pair whose ratio turns over (the same ratio at a temperature below the turn and at its twin
// above), the third swept from too dim to too bright for the first temperature, so that the twin
// fits first worse, then about as well (no reading), then better. Both fits read each pixel
// bit for bit alike, and the sweeps cross the no-reading decision.
void expect_same_near_twin_minima(const std::shared_ptr<const ThermalModel>& model) {
  const ThermalModel& m = *model;
  const int bands = m.profile().band_count();
  const Locus locus = make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0);
  const Eigen::Index n = locus.size();
  const auto fast = make_estimator(model, Method::kLikelihood);
  const auto exhaustive = make_exhaustive_likelihood_estimator(model);
  fast->set_allow_partial(true);
  exhaustive->set_allow_partial(true);
  const double saturation = saturation_signal_dn(m);
  std::size_t pairs = 0, disagree = 0, read = 0, flips = 0;
  for (int i = 0; i < bands && pairs < 4; ++i)
    for (int j = i + 1; j < bands && pairs < 4; ++j) {
      // The ratio's turn, a temperature well below it and its twin above it.
      const Eigen::ArrayXd ratio = locus.rates.col(i).array() / locus.rates.col(j).array();
      Eigen::Index turn;
      ratio.maxCoeff(&turn);
      if (turn < 200 || turn > n - 200) ratio.minCoeff(&turn);
      if (turn < 200 || turn > n - 200) continue;  // monotonic, or turning near an end
      const Eigen::Index below = turn - 150;
      Eigen::Index twin = turn + 1;
      for (Eigen::Index t = turn + 1; t < n; ++t)
        if (std::abs(ratio[t] - ratio[below]) < std::abs(ratio[twin] - ratio[below])) twin = t;
      if (twin + 5 >= n) continue;
      ++pairs;
      const int third = (j + 1) % bands == i ? (j + 2) % bands : (j + 1) % bands;
      const Eigen::RowVectorXd rates = locus.rates.row(below);
      for (double peak : {0.05, 0.2, 0.6}) {
        double previous = 0;
        for (int k = 0; k <= 400; ++k) {
          std::vector<double> s(static_cast<std::size_t>(bands), NAN);
          const double scale = peak * saturation / std::max(rates[i], rates[j]);
          s[static_cast<std::size_t>(i)] = scale * rates[i];
          s[static_cast<std::size_t>(j)] = scale * rates[j];
          s[static_cast<std::size_t>(third)] = scale * rates[third] * (0.25 + k * 0.01);
          const double a = fast->temperature_c(s.data()), e = exhaustive->temperature_c(s.data());
          if (!(a == e || (std::isnan(a) && std::isnan(e)))) {
            ++disagree;
            ADD_FAILURE() << "bands " << i << ", " << j << ", " << third << ", step " << k
                          << ": fast " << a << ", exhaustive " << e;
          }
          read += !std::isnan(e);
          if (k > 0 && std::isnan(previous) != std::isnan(e)) ++flips;
          previous = e;
        }
      }
    }
  ASSERT_GT(pairs, 0u);
  EXPECT_EQ(disagree, 0u);
  EXPECT_GT(read, 0u);
  EXPECT_GE(flips, pairs);  // into or out of the ambiguous readings
}

TEST(LikelihoodEstimator, fast_fit_is_the_exhaustive_fit_near_twin_minima_colour) {
  expect_same_near_twin_minima(test_model("test-model-rgb.json"));
}

TEST(LikelihoodEstimator, fast_fit_is_the_exhaustive_fit_near_twin_minima_5x5) {
  expect_same_near_twin_minima(test_model("test-model-nir5x5.json"));
}

// The 5x5 fit reads pixels whose bands all read, and with partial readings those with a few
// bands dropped, by a walk down chi2 from a guess (likelihood_descent.h), which proves no global
// minimum: on frames of cameras unlike the model (hostile units: moved edges, leaks, sloped ND
// glass), plates from dim to saturated and melt pools with their saturated cores and dim rims,
// it reads every pixel bit for bit as the exhaustive scan, with and without partial readings.
// The colour camera's ratios turn over: its fit scans.
TEST(LikelihoodEstimator, the_5x5_fits_descent_reads_frames_as_the_exhaustive_fit) {
  EXPECT_FALSE(likelihood_fit_descends(
      *make_estimator(test_model("test-model-rgb.json"), Method::kLikelihood)));
  const auto model = test_model("test-model-nir5x5.json");
  const CameraProfile& p = model->profile();
  const auto fast = make_estimator(model, Method::kLikelihood);
  const auto exhaustive = make_exhaustive_likelihood_estimator(model);
  ASSERT_TRUE(likelihood_fit_descends(*fast));
  ASSERT_TRUE(likelihood_fit_descends(*fast, true));
  std::size_t read = 0, no_reading = 0, partial_read = 0;
  for (int unit = 1; unit <= 2; ++unit) {
    Simulator camera(p, UnitPerturbation::parse("hostile", unit), 11 + unit);
    std::vector<cv::Mat> frames;
    // The brightest band's signal, DN: the dimmest bands below the dim threshold at 40, the
    // brightest saturated (at 170) at 220, most of them at 400 (where the walk starts from a
    // pair of bands, and where that lands off, from samples spread over the locus).
    for (double t : {700.0, 1300.0, 2000.0, 2800.0})
      for (double level : {40.0, 100.0, 160.0, 220.0, 400.0})
        frames.push_back(camera.render(plate_scene(255, 135, t), camera.exposure_for(t, level)));
    for (int i : {1, 4})
      frames.push_back(
          camera.render(melt_pool_scene(255, 135, i, 5), camera.exposure_for(1900, 150)));
    for (const cv::Mat& raw : frames) {
      cv::Mat signal;
      subtract_dark_level(raw, p.dark_offset_dn, p.thresholds.inference_saturation_dn, signal);
      std::vector<cv::Mat> planes;
      demosaic(signal, p.mosaic, DemosaicMethod::kBinCells, planes);
      std::vector<const float*> rows;
      for (const cv::Mat& plane : planes) rows.push_back(plane.ptr<float>());
      const std::size_t n = planes[0].total();
      std::vector<float> a(n), e(n);
      for (const auto partial :
           {TemperatureEstimator::PartialBands::kOff, TemperatureEstimator::PartialBands::kAny}) {
        fast->set_partial_bands(partial);
        exhaustive->set_partial_bands(partial);
        fast->estimate(rows.data(), n, a.data());
        exhaustive->estimate(rows.data(), n, e.data());
        for (std::size_t k = 0; k < n; ++k) {
          ASSERT_TRUE(a[k] == e[k] || (std::isnan(a[k]) && std::isnan(e[k])))
              << "unit " << unit << ", pixel " << k << ": fast " << a[k] << ", exhaustive " << e[k];
          ++(std::isnan(e[k]) ? no_reading : read);
          if (partial == TemperatureEstimator::PartialBands::kAny && !std::isnan(e[k])) {
            bool every_band = true;
            for (const cv::Mat& plane : planes) {
              const float v = plane.ptr<float>()[k];
              every_band = every_band && std::isfinite(v) && v >= p.thresholds.inference_dim_dn;
            }
            partial_read += !every_band;
          }
        }
      }
    }
  }
  EXPECT_GT(read, 4000u);  // both decisions exercised
  EXPECT_GT(no_reading, 500u);
  EXPECT_GT(partial_read, 5000u);  // pixels with bands dropped (10 689 measured)
}

// Pixels far off the locus, where chi2 could have two minima and the walk stop at the wrong
// one: mixtures of two temperatures (edge pixels), every band off by up to +-100 % with spikes
// (a camera unlike the model), and spectra spliced from two temperatures band by band, each
// also with 1 to 10 bands dropped and read partially. The 5x5 fit reads each as the exhaustive
// scan, bit for bit, with the same no-reading decisions.
TEST(LikelihoodEstimator, the_5x5_fits_descent_reads_off_locus_pixels_as_the_exhaustive_fit) {
  const auto model = test_model("test-model-nir5x5.json");
  const ThermalModel& m = *model;
  const int bands = m.profile().band_count();
  const BothFits whole = both_fits(model, false), partial = both_fits(model, true);
  Uniform uniform{4242};
  const double dim = m.profile().thresholds.inference_dim_dn;
  const double saturated = saturation_signal_dn(m);
  std::size_t pixels = 0, read = 0, partial_read = 0, disagree = 0;
  for (int i = 0; i < 30000; ++i) {
    const double t1 = 550 + 2900 * uniform(), t2 = 550 + 2900 * uniform();
    const Eigen::VectorXd a = m.camera.rates(t1) / m.camera.rates(t1).maxCoeff();
    const Eigen::VectorXd b = m.camera.rates(t2) / m.camera.rates(t2).maxCoeff();
    Eigen::VectorXd s(bands);
    const double f = uniform(), spread = i % 3 == 1 ? uniform() : 0;
    for (int k = 0; k < bands; ++k) {
      if (i % 3 == 0) s[k] = (1 - f) * a[k] + f * b[k];                      // mixture
      if (i % 3 == 1) s[k] = a[k] * (1 + spread * (2 * uniform() - 1));      // distorted
      if (i % 3 == 2) s[k] = uniform() < 0.5 ? a[k] : (0.1 + 3 * f) * b[k];  // spliced
    }
    if (i % 7 == 0) s[i % bands] *= 3;  // a spike
    s *= (0.25 + 0.7 * uniform()) * saturated / s.maxCoeff();
    if (!(s.minCoeff() >= dim)) continue;  // every band reads: the walk's pixels
    ++pixels;
    const double x = whole.fast->temperature_c(s.data());
    const double e = whole.exhaustive->temperature_c(s.data());
    read += !std::isnan(e);
    if (!(x == e || (std::isnan(x) && std::isnan(e))) && ++disagree < 10)
      ADD_FAILURE() << "pixel " << i << ": fast " << x << ", exhaustive " << e;
    // The same pixel with 1 to 10 bands dropped (dim, saturated or invalid), read partially.
    const int drop = 1 + i % 10;
    for (int k = 0; k < drop; ++k) {
      const int band = static_cast<int>(uniform() * bands) % bands;
      s[band] = k % 3 == 0   ? 0.5 * dim
                : k % 3 == 1 ? std::numeric_limits<double>::infinity()
                             : std::numeric_limits<double>::quiet_NaN();
    }
    const double xp = partial.fast->temperature_c(s.data());
    const double ep = partial.exhaustive->temperature_c(s.data());
    partial_read += !std::isnan(ep);
    if (!(xp == ep || (std::isnan(xp) && std::isnan(ep))) && ++disagree < 10)
      ADD_FAILURE() << "pixel " << i << " with " << drop << " bands dropped: fast " << xp
                    << ", exhaustive " << ep;
  }
  EXPECT_EQ(disagree, 0u);
  EXPECT_GT(pixels, 5000u);
  EXPECT_GT(read, pixels / 2);
  EXPECT_LT(read, pixels);  // some are no reading (an end of the range)
  EXPECT_GT(partial_read, pixels / 2);
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

// A row of pixels through estimate (which skips the pixels with too few bands that read before
// weighing them) gives each pixel's temperature_c, whatever the partial-band rule, with bands at
// the dim threshold's float and just under it, NaN and saturated among them.
TEST(LikelihoodEstimator, a_rows_readings_are_its_pixels_readings) {
  for (const char* name : {"test-model-rgb.json", "test-model-nir5x5.json"}) {
    SCOPED_TRACE(name);
    const auto model = test_model(name);
    const ThermalModel& m = *model;
    const int bands = m.profile().band_count();
    NoisyPixels px = noisy_pixels(m, kSweepC, 60, 1, 400, saturation_signal_dn(m), 0.1, 17);
    const double dim = m.profile().thresholds.inference_dim_dn;
    auto at_dim = static_cast<float>(dim);
    if (static_cast<double>(at_dim) < dim) at_dim = std::nextafter(at_dim, INFINITY);
    const float under_dim = std::nextafter(at_dim, 0.f);
    // Pixels of a hot plate with k of their bands set to the threshold or just under it, and
    // the plate dimmed until its dimmest band sits there (a reading only if that band counts).
    const std::size_t hot = px.size() - 1;
    for (float edge : {at_dim, under_dim}) {
      for (int k = 0; k <= bands; ++k) {
        std::vector<double> s(px.pixel(hot), px.pixel(hot) + bands);
        for (int b = 0; b < k; ++b) s[static_cast<std::size_t>(b)] = edge;
        px.signals.insert(px.signals.end(), s.begin(), s.end());
      }
      std::vector<double> s(px.pixel(hot), px.pixel(hot) + bands);
      const auto dimmest = std::min_element(s.begin(), s.end());
      const double scale = edge / *dimmest;
      for (double& v : s) v = static_cast<float>(v * scale);
      *dimmest = edge;
      px.signals.insert(px.signals.end(), s.begin(), s.end());
    }
    std::vector<int> reading_counts(static_cast<std::size_t>(bands) + 1, 0);
    for (std::size_t i = 0; i < px.size(); ++i) {
      const double* s = px.pixel(i);
      ++reading_counts[static_cast<std::size_t>(
          std::count_if(s, s + bands, [&](double v) { return v >= dim && v < INFINITY; }))];
    }
    for (int k : {0, 1, 2, bands}) EXPECT_GT(reading_counts[static_cast<std::size_t>(k)], 0) << k;
    // Each fit reads the row as it is and rearranged in chunks of 256 pixels (estimate's) where
    // the pixels 24-39 of every 64 read: estimate weighs such a chunk's pixels without counting
    // their bands (it probes eight pixels in the middle of each quarter), and the rest of the
    // chunk holds pixels that read, some that do not, and those with too few bands.
    for (auto partial :
         {TemperatureEstimator::PartialBands::kOff, TemperatureEstimator::PartialBands::kSafe,
          TemperatureEstimator::PartialBands::kAny}) {
      for (const auto& fit : {make_estimator(model, Method::kLikelihood),
                              make_exhaustive_likelihood_estimator(model)}) {
        fit->set_partial_bands(partial);
        std::vector<std::size_t> reads;
        for (std::size_t i = 0; i < px.size(); ++i)
          if (std::isfinite(fit->temperature_c(px.pixel(i)))) reads.push_back(i);
        ASSERT_FALSE(reads.empty());
        NoisyPixels chunked = px;
        chunked.signals.clear();
        for (std::size_t next = 0, next_read = 0; next < px.size();)
          for (std::size_t at = 0; at < 256; ++at) {
            const std::size_t i = at % 64 >= 24 && at % 64 < 40 ? reads[next_read++ % reads.size()]
                                                                : next++ % px.size();
            chunked.signals.insert(chunked.signals.end(), px.pixel(i), px.pixel(i) + bands);
          }
        for (const NoisyPixels* row_of : {&px, &chunked}) {
          const std::vector<cv::Mat> planes = as_planes(*row_of);
          std::vector<const float*> rows;
          for (const cv::Mat& p : planes) rows.push_back(p.ptr<float>(0));
          const std::size_t n = row_of->size();
          std::vector<float> row(n);
          fit->estimate(rows.data(), n, row.data());
          std::size_t differ = 0, read = 0;
          for (std::size_t i = 0; i < n; ++i) {
            std::vector<double> s(static_cast<std::size_t>(bands));
            for (int b = 0; b < bands; ++b)
              s[static_cast<std::size_t>(b)] = rows[static_cast<std::size_t>(b)][i];
            const auto one = static_cast<float>(fit->temperature_c(s.data()));
            differ += !(one == row[i] || (std::isnan(one) && std::isnan(row[i])));
            read += std::isfinite(row[i]);
          }
          EXPECT_EQ(differ, 0u) << static_cast<int>(partial);
          EXPECT_GT(read, n / 10) << static_cast<int>(partial);
        }
      }
    }
  }
}

// The kernels on rows padded to whole lanes of four: the weights are zero past the bands and
// below the weighing threshold, sss and chi2 are their sums (to rounding, against long double),
// and for 3 and 25 bands (the shipped cameras) the padded sums are those over the bands alone,
// bit for bit.
TEST(LikelihoodKernels, padded_rows_sum_the_bands_alone) {
  Uniform uniform{7};
  for (const int bands : {3, 5, 7, 25}) {
    const int width = padded_bands(bands);
    alignas(32) double s[kMaxBands], gain[kMaxBands], floor[kMaxBands];
    alignas(32) double w[kMaxBands], ws[kMaxBands];
    std::vector<double> m(static_cast<std::size_t>(3 * width), 0.0), m2(m.size(), 0.0);
    for (int b = 0; b < kMaxBands; ++b) w[b] = ws[b] = NAN;  // what padding must overwrite
    for (int b = 0; b < bands; ++b) {
      // Band 1 below the weighing threshold of 5, band 2 between it and the dim threshold of 10.
      s[b] = b == 1 ? 2.0 : b == 2 ? 7.0 : 20 + 500 * uniform();
      gain[b] = 0.5 + uniform();
      floor[b] = 10 + 5 * uniform();
      for (int row = 0; row < 3; ++row) {
        const double v = 0.1 + uniform();
        m[static_cast<std::size_t>(row * width + b)] = v;
        m2[static_cast<std::size_t>(row * width + b)] = v * v;
      }
    }
    double sss = 0;
    int bright = -1;
    EXPECT_EQ(weigh_bands(s, bands, 5.0, 10.0, gain, floor, w, ws, &sss, &bright), bands - 1);
    EXPECT_EQ(bright, bands - 2);
    long double want_sss = 0;
    for (int b = 0; b < width; ++b) {
      if (b >= bands || b == 1) {
        EXPECT_EQ(w[b], 0.0) << bands << " bands, band " << b;
        EXPECT_EQ(ws[b], 0.0) << bands << " bands, band " << b;
      } else {
        EXPECT_EQ(w[b], 1.0 / (gain[b] * s[b] + floor[b]));
        want_sss += static_cast<long double>(ws[b]) * s[b];
      }
    }
    EXPECT_NEAR(sss, static_cast<double>(want_sss), 1e-13 * sss) << bands << " bands";
    double chi2[3];
    profiled_chi2_three(m.data(), m2.data(), ws, w, width, sss, chi2);
    for (int row = 0; row < 3; ++row) {
      const double* r = &m[static_cast<std::size_t>(row * width)];
      const double* r2 = &m2[static_cast<std::size_t>(row * width)];
      long double ssm = 0, smm = 0;
      for (int b = 0; b < bands; ++b)
        ssm += static_cast<long double>(ws[b]) * r[b], smm += w[b] * r2[b];
      const double want = static_cast<double>(sss - ssm * ssm / smm);
      EXPECT_NEAR(chi2[row], want, 1e-11 * sss) << bands << " bands, row " << row;
      EXPECT_EQ(chi2[row], profiled_chi2(r, r2, ws, w, width, sss));
      if (bands == 3 || bands == 25) {
        // Unpadded rows of the same values: the tail's terms land in the lanes padding gives.
        std::vector<double> tight(r, r + bands), tight2(r2, r2 + bands);
        EXPECT_EQ(chi2[row], profiled_chi2(tight.data(), tight2.data(), ws, w, bands, sss));
      }
    }
  }
}

}  // namespace
}  // namespace pyrocam::test
