// Ratio-scaled brightness readings (scaled_brightness.h): the tables, the readings on plates and
// melt pools against the ratio readings they start from, the pixels that fall back, codes, and
// bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "../true_model.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/scaled_brightness.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

constexpr int kW = 160, kH = 120;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::shared_ptr<ThermalModel> true_model(const CameraProfile& p, const UnitPerturbation& unit) {
  const auto model = test::true_model(p, unit);
  return model;
}

// A colour camera whose model is its true QE, so that only the reading is measured.
struct Colour {
  CameraProfile profile = load_profile_by_name("rgb-reference");
  UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  std::shared_ptr<ThermalModel> model = true_model(profile, unit);

  // Readings of `truth` exposed for `exposed_c` (brightest band at 70 % of the usable range),
  // by the ratio (radius 0) or with brightness readings of window radius r.
  cv::Mat read(const cv::Mat& truth, double exposed_c, int radius, bool noise,
               std::uint64_t seed = 13) const {
    Simulator camera(profile, unit, seed);
    camera.set_noise_enabled(noise);
    const double exposure =
        camera.exposure_for(exposed_c, 0.7 * (profile.thresholds.inference_saturation_dn - 50));
    const cv::Mat dark = camera.render_dark(truth.cols, truth.rows, exposure);
    const cv::Mat raw = camera.render(truth, exposure);
    MeasureOptions options;
    options.method = Method::kLikelihood;
    options.safe_partial = true;
    options.brightness_radius = radius;
    FrameMeasurer measurer(model, options);
    cv::Mat t;
    measurer.measure(raw, dark, t);
    return t;
  }
};

struct Stats {
  double mean = 0, sd = 0;
  long n = 0;
};

// Of the readings where the truth is `t_c` and the pixel lies in the frame's middle half.
Stats interior(const cv::Mat& read, const cv::Mat& truth, float t_c) {
  double s = 0, s2 = 0;
  long n = 0;
  for (int y = read.rows / 4; y < 3 * read.rows / 4; ++y)
    for (int x = read.cols / 4; x < 3 * read.cols / 4; ++x) {
      const float v = read.at<float>(y, x);
      if (truth.at<float>(y, x) != t_c || !std::isfinite(v)) continue;
      s += v - t_c, s2 += (v - t_c) * (v - t_c), ++n;
    }
  Stats st;
  st.n = n;
  st.mean = s / std::max(n, 1L);
  st.sd = std::sqrt(std::max(0.0, s2 / std::max(n, 1L) - st.mean * st.mean));
  return st;
}

TEST(ScaledBrightness, TablesInvertEachOther) {
  const Colour c;
  const ScaledBrightness sb(*c.model, 2);
  const Locus locus = make_locus(c.model->camera, 500, 3500, 1);
  for (int b = 0; b < 3; ++b) {
    for (int i = 0; i < locus.size(); i += 37)
      EXPECT_NEAR(sb.log_rate(b, locus.temperature_c[i]), std::log(locus.rates(i, b)), 1e-5);
    for (double t = 600; t < 3400; t += 7.3)
      EXPECT_NEAR(sb.temperature_of_log_rate(b, sb.log_rate(b, t)), t, 0.01) << "band " << b;
    EXPECT_TRUE(std::isnan(sb.log_rate(b, 499)));
    EXPECT_TRUE(std::isnan(sb.temperature_of_log_rate(b, sb.log_rate(b, 500) - 0.01)));
  }
}

// Without temporal noise (the sensor's fixed pattern and the 8-bit steps stay) the ratio reads a
// plate to a few degrees, worst near its corners where the windows are cut; every pixel's own
// sample reads it closer, the same pixels.
TEST(ScaledBrightness, ReadsAPlateWithoutTemporalNoiseCloserThanTheRatio) {
  const Colour c;
  for (float t_c : {800.f, 1500.f, 2500.f}) {
    const cv::Mat truth = plate_scene(kW, kH, t_c);
    const cv::Mat ratio = c.read(truth, t_c, 0, false), bright = c.read(truth, t_c, 2, false);
    double r2 = 0, b2 = 0, r_max = 0, b_max = 0, r_sum = 0, b_sum = 0;
    long both = 0;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const float r = ratio.at<float>(y, x), b = bright.at<float>(y, x);
        ASSERT_EQ(std::isfinite(r), std::isfinite(b)) << "the mask changed at " << x << "," << y;
        if (!std::isfinite(b)) continue;
        const double dr = r - truth.at<float>(y, x), db = b - truth.at<float>(y, x);
        r2 += dr * dr, b2 += db * db, r_sum += dr, b_sum += db;
        r_max = std::max(r_max, std::abs(dr)), b_max = std::max(b_max, std::abs(db));
        ++both;
      }
    ASSERT_GT(both, kW * kH / 4);
    const double r_rms = std::sqrt(r2 / both), b_rms = std::sqrt(b2 / both);
    std::printf(
        "%4.0f degC plate: ratio rms %.2f max %.1f mean %+.2f, brightness rms %.2f max %.1f "
        "mean %+.2f degC\n",
        t_c, r_rms, r_max, r_sum / both, b_rms, b_max, b_sum / both);
    EXPECT_LT(b_rms, 0.7 * r_rms) << t_c;
    EXPECT_LT(b_max, 0.7 * r_max) << t_c;
    EXPECT_LT(std::abs(b_sum - r_sum) / both, 0.5) << t_c;
  }
}

// With noise: the same mean as the ratio, with the noise of one sample. Measured 2.4-2.8 times
// less spread on these plates; the bound 1.8 leaves room for the spread's own sampling error
// (a few per cent over some 200 independent footprints of the ratio readings).
TEST(ScaledBrightness, ReadsANoisyPlateWithLessSpread) {
  const Colour c;
  for (float t_c : {1200.f, 2000.f}) {
    const cv::Mat truth = plate_scene(kW, kH, t_c);
    const Stats ratio = interior(c.read(truth, t_c, 0, true), truth, t_c);
    const Stats bright = interior(c.read(truth, t_c, 2, true), truth, t_c);
    ASSERT_GT(ratio.n, 2000);
    ASSERT_EQ(bright.n, ratio.n);
    EXPECT_LT(bright.sd * 1.8, ratio.sd) << t_c << " degC";
    // The scale is the ratio's over 9 x 9 pixels: the means differ by the ratio's noise
    // averaged over windows, a fraction of its spread.
    EXPECT_LT(std::abs(bright.mean - ratio.mean), 0.2 * ratio.sd) << t_c << " degC";
    EXPECT_LT(std::abs(bright.mean), 3) << t_c << " degC";
  }
}

// The simulator's melt pool has a kink at its peak, which the bands' footprints sample
// differently by Bayer column: the ratio's core median was 56 degC rms off over these frames
// without noise, the brightness readings' 14 degC.
TEST(ScaledBrightness, ReadsTheMeltPoolCoreCloserThanTheRatio) {
  const Colour c;
  double ratio2 = 0, bright2 = 0;
  int frames = 0;
  for (int i = 0; i < 60; i += 6) {
    const cv::Mat truth = melt_pool_scene(320, 240, i, 60);
    cv::Mat finite;
    cv::patchNaNs(finite = truth.clone(), 0);
    double peak;
    cv::minMaxLoc(finite, nullptr, &peak);
    const cv::Mat ratio = c.read(truth, peak, 0, false), bright = c.read(truth, peak, 2, false);
    std::vector<float> real, r, b;
    for (int y = 0; y < truth.rows; ++y)
      for (int x = 0; x < truth.cols; ++x) {
        if (!(truth.at<float>(y, x) >= peak - 50)) continue;
        real.push_back(truth.at<float>(y, x));
        if (std::isfinite(ratio.at<float>(y, x))) r.push_back(ratio.at<float>(y, x));
        if (std::isfinite(bright.at<float>(y, x))) b.push_back(bright.at<float>(y, x));
      }
    ASSERT_EQ(r.size(), b.size());
    if (r.empty()) continue;
    const auto median = [](std::vector<float> v) {
      std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    ratio2 += std::pow(median(r) - median(real), 2);
    bright2 += std::pow(median(b) - median(real), 2);
    ++frames;
  }
  ASSERT_GE(frames, 8);
  const double ratio_rms = std::sqrt(ratio2 / frames), bright_rms = std::sqrt(bright2 / frames);
  std::printf("core median rms over %d frames: ratio %.1f degC, brightness %.1f degC\n", frames,
              ratio_rms, bright_rms);
  EXPECT_LT(bright_rms, 0.5 * ratio_rms);
  EXPECT_LT(bright_rms, 25);
}

// The assumption's limit: a plate whose emissivity steps from 0.3 to 0.6 half way across. The
// ratio is wrong only where its footprints straddle the step; the brightness readings take the
// step's share of their window's scale, so they move within the window's reach of the step and
// nowhere else (why they are off by default). Prints the columns' mean errors for the docs.
TEST(ScaledBrightness, AnEmissivityStepMovesReadingsWithinTheWindowOnly) {
  const Colour c;
  constexpr int kWindow = 2;  // Bayer cells: 4 pixels each side
  for (float t_c : {1500.f, 2000.f}) {
    const cv::Mat truth(kH, kW, CV_32F, cv::Scalar(t_c));
    Simulator camera(c.profile, c.unit, 13);
    const double exposure = camera.exposure_for(t_c, 150, 0.6);
    const cv::Mat dull = camera.render(truth, exposure, 0.3),
                  bright = camera.render(truth, exposure, 0.6);
    cv::Mat raw = dull.clone();
    bright(cv::Rect(kW / 2, 0, kW / 2, kH)).copyTo(raw(cv::Rect(kW / 2, 0, kW / 2, kH)));
    const cv::Mat dark = camera.render_dark(kW, kH, exposure);
    cv::Mat read[2];
    for (int k = 0; k < 2; ++k) {
      MeasureOptions options;
      options.method = Method::kLikelihood;
      options.brightness_radius = k ? kWindow : 0;
      FrameMeasurer(c.model, options).measure(raw, dark, read[k]);
    }
    std::printf("%4.0f degC, emissivity 0.3 | 0.6 from column 0; mean error of rows 20-99 (degC)\n",
                t_c);
    for (int x = kW / 2 - 8; x < kW / 2 + 8; ++x) {
      double error[2] = {0, 0};
      for (int k = 0; k < 2; ++k) {
        int n = 0;
        for (int y = 20; y < 100; ++y)
          if (std::isfinite(read[k].at<float>(y, x)))
            error[k] += read[k].at<float>(y, x) - t_c, ++n;
        ASSERT_GT(n, 70) << x;
        error[k] /= n;
      }
      std::printf("  column %+3d: ratio %+7.1f, brightness-radius=%d %+7.1f\n", x - kW / 2,
                  error[0], kWindow, error[1]);
      // Beyond the window's reach plus the ratio's footprint (2 pixels) both read the plate.
      if (std::abs(x + 0.5 - kW / 2) > 4 * kWindow + 2.5) {
        EXPECT_LT(std::abs(error[0]), 10) << x;
        EXPECT_LT(std::abs(error[1]), 10) << x;
      }
    }
  }
}

// A uniform 1500 degC surface as noiseless samples, every ratio reading 1500 degC.
struct Uniform {
  Colour c;
  ScaledBrightness sb{*c.model, 1};
  // Parentheses: braces would take cv::Mat's initializer-list constructor.
  cv::Mat signal = cv::Mat(16, 16, CV_32F), ratio = cv::Mat(16, 16, CV_32F, cv::Scalar(1500));
  Uniform() {
    const Eigen::VectorXd rates = c.model->camera.rates(1500);
    const double scale = 150 / rates.maxCoeff();
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x)
        signal.at<float>(y, x) = static_cast<float>(scale * rates[c.profile.mosaic.band_at(x, y)]);
  }
};

TEST(ScaledBrightness, KeepsTheMaskAndFallsBackToNeighboursOrTheRatio) {
  Uniform u;
  u.signal.at<float>(8, 8) = std::numeric_limits<float>::infinity();  // saturated
  u.ratio.at<float>(8, 8) = 1490;
  u.ratio.at<float>(4, 4) = kNaN;  // the ratio did not read here: nor will the brightness
  // A dim sample whose four neighbours have no reading: it keeps its ratio reading.
  u.signal.at<float>(0, 13) = 1;
  u.ratio.at<float>(0, 13) = 1234;
  for (const auto& [y, x] : {std::pair{1, 13}, {0, 12}, {0, 14}}) u.ratio.at<float>(y, x) = kNaN;
  cv::Mat t = u.ratio.clone();
  u.sb.apply(u.signal, t);
  EXPECT_TRUE(std::isnan(t.at<float>(4, 4)));
  EXPECT_NEAR(t.at<float>(8, 8), 1500, 0.05);  // the neighbours' mean, not its ratio's 1490
  EXPECT_EQ(t.at<float>(0, 13), 1234.f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      if (std::isfinite(t.at<float>(y, x)) && t.at<float>(y, x) != 1234.f) {
        EXPECT_NEAR(t.at<float>(y, x), 1500, 0.05) << x << "," << y;
      }
    }
}

// Each sample reads through its own band: a red pixel twice as bright reads hotter, its
// neighbours (other bands, or red pixels whose window it joins only as one of several) less so.
TEST(ScaledBrightness, ASampleReadsThroughItsOwnBand) {
  Uniform u;
  const int y = 6, x = 6;
  ASSERT_EQ(u.c.profile.mosaic.band_at(x, y), 0);  // red
  u.signal.at<float>(y, x) *= 2;
  cv::Mat t = u.ratio.clone();
  u.sb.apply(u.signal, t);
  // Its log signal is ln 2 higher, its window's mean scale ln 2 / 9 higher (a radius-1 window
  // holds 3 x 3 red pixels).
  const double expected =
      u.sb.temperature_of_log_rate(0, u.sb.log_rate(0, 1500) + std::log(2.0) * (1 - 1.0 / 9));
  EXPECT_GT(expected, 1580);
  EXPECT_NEAR(t.at<float>(y, x), expected, 0.05);
  EXPECT_NEAR(t.at<float>(y, x + 1), 1500, 0.05);  // green: its own window has no such pixel
  EXPECT_LT(t.at<float>(y, x + 2), 1500);  // red, its window's mean raised by the bright one
}

// A readout window that starts one column further on makes the model's rggb mosaic a grbg one.
// Read with that layout, a red sample twice as bright reads through the red band, as in the
// model's own phase (ASampleReadsThroughItsOwnBand); read as the model's rggb, through green's.
TEST(ScaledBrightness, ReadsTheStreamsBayerPhase) {
  Uniform u;
  const int y = 6, x = 6;
  ASSERT_EQ(u.c.profile.mosaic.band_at(x, y), 0);  // red
  u.signal.at<float>(y, x) *= 2;
  const cv::Mat shifted = u.signal.colRange(1, 15).clone();  // grbg, 14 x 16
  cv::Mat as_grbg = u.ratio.colRange(1, 15).clone(), as_rggb = as_grbg.clone();
  ScaledBrightness(*u.c.model, 1, MosaicLayout::bayer("GRBG")).apply(shifted, as_grbg);
  u.sb.apply(shifted, as_rggb);
  const double expected =
      u.sb.temperature_of_log_rate(0, u.sb.log_rate(0, 1500) + std::log(2.0) * (1 - 1.0 / 9));
  EXPECT_NEAR(as_grbg.at<float>(y, x - 1), expected, 0.05);
  EXPECT_GT(std::abs(as_rggb.at<float>(y, x - 1) - expected), 5) << as_rggb.at<float>(y, x - 1);
}

TEST(ScaledBrightness, CodesReadAsDegrees) {
  const Colour c;
  const cv::Mat truth = plate_scene(kW, kH, 1700);
  Simulator camera(c.profile, c.unit, 5);
  const double exposure = camera.exposure_for(1700, 150);
  cv::Mat signal;
  subtract_dark(camera.render(truth, exposure),
                dark_from_image(camera.render_dark(kW, kH, exposure)), 220, signal);
  MeasureOptions options;
  options.method = Method::kLikelihood;
  options.brightness_radius = 0;
  FrameMeasurer measurer(c.model, options);
  cv::Mat ratio;
  measurer.measure_signal(signal, ratio);
  cv::Mat codes = encode_decikelvin(ratio), t = decode_decikelvin(codes);
  ScaledBrightness sb(*c.model, 2);
  sb.apply(signal, t);
  sb.apply_codes(signal, codes);
  const cv::Mat from_codes = decode_decikelvin(codes);
  long read = 0;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const float a = t.at<float>(y, x), b = from_codes.at<float>(y, x);
      ASSERT_EQ(std::isfinite(a), std::isfinite(b));
      if (!std::isfinite(a)) continue;
      EXPECT_NEAR(a, b, 0.06) << x << "," << y;  // half a code, and float rounding
      ++read;
    }
  EXPECT_GT(read, kW * kH / 4);
}

TEST(ScaledBrightness, RefusesWhatItCannotRead) {
  const Colour c;
  EXPECT_THROW(ScaledBrightness(*c.model, 0), InputError);
  EXPECT_THROW(ScaledBrightness(*c.model, ScaledBrightness::kMaxWindowRadius + 1), InputError);
  const CameraProfile nir = load_profile_by_name("nir5x5-reference");
  EXPECT_THROW(ScaledBrightness(*true_model(nir, UnitPerturbation::parse("typical", 1)), 2),
               InputError);
  ScaledBrightness sb(*c.model, 2);
  cv::Mat t(16, 16, CV_32F, cv::Scalar(1500));
  EXPECT_THROW(sb.apply(cv::Mat(16, 18, CV_32F, cv::Scalar(100)), t), InputError);
  cv::Mat odd(15, 16, CV_32F, cv::Scalar(1500));
  EXPECT_THROW(sb.apply(cv::Mat(15, 16, CV_32F, cv::Scalar(100)), odd), InputError);
  EXPECT_THROW(sb.apply(cv::Mat(16, 16, CV_16U, cv::Scalar(100)), t), InputError);
  cv::Mat codes(16, 16, CV_16U, cv::Scalar(17732));
  EXPECT_THROW(sb.apply(cv::Mat(16, 16, CV_32F, cv::Scalar(100)), codes), InputError);
  EXPECT_THROW(sb.apply_codes(cv::Mat(16, 16, CV_32F, cv::Scalar(100)), t), InputError);
  // Binned planes are not one reading per sample.
  MeasureOptions options;
  options.demosaic = DemosaicMethod::kBinCells;
  options.brightness_radius = 2;
  EXPECT_THROW(FrameMeasurer(c.model, options), InputError);
  options.brightness_radius = 0;  // the default: off
  EXPECT_NO_THROW(FrameMeasurer(c.model, options));
}

}  // namespace
}  // namespace pyrocam
