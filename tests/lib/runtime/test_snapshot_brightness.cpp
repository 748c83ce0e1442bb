// Ratio-scaled brightness readings of snapshot band planes (snapshot_brightness.h): plates with
// and without noise, melt-pool cores and an emissivity step against the likelihood fit's
// readings they start from, the cells that keep the fit's reading, codes, and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "../true_model.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/snapshot_brightness.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

constexpr int kW = 320, kH = 240;  // sensor pixels: 64 x 48 cells
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

std::shared_ptr<ThermalModel> true_model(const CameraProfile& p, const UnitPerturbation& unit) {
  const auto model = test::true_model(p, unit);
  return model;
}

// A 5x5 camera whose model is its true QE, so that only the reading is measured.
struct Snapshot {
  CameraProfile profile = load_profile_by_name("nir5x5-reference");
  UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  std::shared_ptr<ThermalModel> model = true_model(profile, unit);

  // Cell readings of `truth` (sensor pixels) exposed for `exposed_c` (brightest band at 70 % of
  // the usable range), by the fit (radius 0) or with brightness readings of window radius r.
  cv::Mat read(const cv::Mat& truth, double exposed_c, int radius, bool noise,
               std::uint64_t seed = 13) const {
    Simulator camera(profile, unit, seed);
    camera.set_noise_enabled(noise);
    const double exposure = camera.exposure_for(
        exposed_c, 0.7 * (profile.thresholds.inference_saturation_dn - profile.dark_offset_dn));
    const cv::Mat dark = camera.render_dark(truth.cols, truth.rows, exposure);
    const cv::Mat raw = camera.render(truth, exposure);
    MeasureOptions options;
    options.method = Method::kLikelihood;
    options.demosaic = DemosaicMethod::kMatched;
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

// Of the cell readings in the frame's middle half, against a uniform truth t_c.
Stats interior(const cv::Mat& read, float t_c) {
  double s = 0, s2 = 0;
  long n = 0;
  for (int y = read.rows / 4; y < 3 * read.rows / 4; ++y)
    for (int x = read.cols / 4; x < 3 * read.cols / 4; ++x) {
      const float v = read.at<float>(y, x);
      if (!std::isfinite(v)) continue;
      s += v - t_c, s2 += (v - t_c) * (v - t_c), ++n;
    }
  Stats st;
  st.n = n;
  st.mean = s / std::max(n, 1L);
  st.sd = std::sqrt(std::max(0.0, s2 / std::max(n, 1L) - st.mean * st.mean));
  return st;
}

float median(std::vector<float> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Without temporal noise both read a plate's mean within a fraction of a degree; the same cells.
TEST(SnapshotBrightness, ReadsAPlateWithoutTemporalNoiseAsTheFit) {
  const Snapshot s;
  for (float t_c : {800.f, 1500.f, 2500.f}) {
    const cv::Mat truth = plate_scene(kW, kH, t_c);
    const cv::Mat fit = s.read(truth, t_c, 0, false), bright = s.read(truth, t_c, 2, false);
    ASSERT_EQ(fit.size(), cv::Size(kW / 5, kH / 5));
    long both = 0;
    for (int y = 0; y < fit.rows; ++y)
      for (int x = 0; x < fit.cols; ++x) {
        const float f = fit.at<float>(y, x), b = bright.at<float>(y, x);
        ASSERT_EQ(std::isfinite(f), std::isfinite(b)) << "the mask changed at " << x << "," << y;
        both += std::isfinite(b);
      }
    ASSERT_GT(both, fit.total() / 4);
    const Stats f = interior(fit, t_c), b = interior(bright, t_c);
    std::printf(
        "%4.0f degC plate without temporal noise: fit mean %+.2f sd %.2f, brightness "
        "mean %+.2f sd %.2f degC\n",
        t_c, f.mean, f.sd, b.mean, b.sd);
    EXPECT_LT(std::abs(b.mean - f.mean), 0.5) << t_c;
    EXPECT_LT(std::abs(b.mean), 1.0) << t_c;
    // The sensor's fixed pattern and 8-bit steps stay: measured a third of the fit's spread.
    EXPECT_LT(b.sd, 0.5 * f.sd) << t_c;
  }
}

// With noise: about the fit's mean, with far less spread (a cell's 25 bands read its
// brightness to tenths of a degree; what is left is the window's mean fit error).
TEST(SnapshotBrightness, ReadsANoisyPlateWithLessSpread) {
  const Snapshot s;
  for (float t_c : {1200.f, 2000.f}) {
    const cv::Mat truth = plate_scene(kW, kH, t_c);
    const Stats fit = interior(s.read(truth, t_c, 0, true), t_c);
    const Stats bright = interior(s.read(truth, t_c, 2, true), t_c);
    std::printf(
        "%4.0f degC noisy plate: fit mean %+.2f sd %.2f, brightness mean %+.2f sd %.2f "
        "degC over %ld cells\n",
        t_c, fit.mean, fit.sd, bright.mean, bright.sd, fit.n);
    ASSERT_GT(fit.n, 700);
    ASSERT_EQ(bright.n, fit.n);
    EXPECT_LT(bright.sd * 2, fit.sd) << t_c << " degC";
    EXPECT_LT(std::abs(bright.mean - fit.mean), 0.3 * fit.sd) << t_c << " degC";
  }
}

// Parabolic pools with a sharp rim (peaks 1500-2500 degC) exposed for the peak: the core (cells
// within 50 degC of the peak) is 16-60 cells, and the median of the fit's readings there moves
// with their noise; the brightness readings' much less.
TEST(SnapshotBrightness, ReadsMeltPoolCoresCloserThanTheFit) {
  const Snapshot s;
  double fit2 = 0, bright2 = 0;
  int frames = 0;
  for (double peak : {1500.0, 2000.0, 2500.0})
    for (int seed = 0; seed < 2; ++seed) {
      cv::Mat truth(kH, kW, CV_32F);
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
          const double r2 = std::pow((x - 160.3 - seed) / 80, 2) + std::pow((y - 121.7) / 35, 2);
          truth.at<float>(y, x) = static_cast<float>(r2 <= 1 ? peak - (peak - 1300) * r2 : 300);
        }
      const cv::Mat fit = s.read(truth, peak, 0, true, 200 + seed),
                    bright = s.read(truth, peak, 2, true, 200 + seed);
      std::vector<float> real, f, b;
      for (int y = 0; y < fit.rows; ++y)
        for (int x = 0; x < fit.cols; ++x) {
          const float t = truth.at<float>(5 * y + 2, 5 * x + 2);
          if (t < peak - 50) continue;
          real.push_back(t);
          if (std::isfinite(fit.at<float>(y, x))) f.push_back(fit.at<float>(y, x));
          if (std::isfinite(bright.at<float>(y, x))) b.push_back(bright.at<float>(y, x));
        }
      ASSERT_EQ(f.size(), b.size());
      ASSERT_GT(f.size(), real.size() / 2) << peak;
      fit2 += std::pow(median(f) - median(real), 2);
      bright2 += std::pow(median(b) - median(real), 2);
      ++frames;
    }
  const double fit_rms = std::sqrt(fit2 / frames), bright_rms = std::sqrt(bright2 / frames);
  std::printf("core median rms over %d pools: fit %.1f degC, brightness %.1f degC\n", frames,
              fit_rms, bright_rms);
  EXPECT_LT(bright_rms, fit_rms);
  EXPECT_LT(bright_rms, 8);
}

// The assumption's limit: a plate whose emissivity steps from 0.3 to 0.6 half way across. The
// brightness readings take the step's share of their window's scale, so they move within the
// window's reach of the step (and the matched kernels' cell) and nowhere else. Prints the
// columns' mean errors for the docs.
TEST(SnapshotBrightness, AnEmissivityStepMovesReadingsWithinTheWindowOnly) {
  const Snapshot s;
  constexpr int kWindow = 2;
  const float t_c = 2000;
  const cv::Mat truth = plate_scene(kW, kH, t_c);
  // Emissivity 0.3 on the left, 0.6 on the right from a whole cell column on.
  Simulator camera(s.profile, s.unit, 13);
  const double exposure = camera.exposure_for(t_c, 150, 0.6);
  cv::Mat raw = camera.render(truth, exposure, 0.3);
  const cv::Rect right(kW / 2, 0, kW / 2, kH);
  camera.render(truth, exposure, 0.6)(right).copyTo(raw(right));
  const cv::Mat dark = camera.render_dark(kW, kH, exposure);
  cv::Mat read[2];
  for (int k = 0; k < 2; ++k) {
    MeasureOptions options;
    options.method = Method::kLikelihood;
    options.demosaic = DemosaicMethod::kMatched;
    options.safe_partial = true;
    options.brightness_radius = k ? kWindow : 0;
    FrameMeasurer(s.model, options).measure(raw, dark, read[k]);
  }
  const int step = kW / 10;  // the first cell column of the brighter half
  std::printf("%4.0f degC, emissivity 0.3 | 0.6 from cell column 0; mean error (degC)\n", t_c);
  for (int x = step - 6; x < step + 6; ++x) {
    double error[2] = {0, 0};
    for (int k = 0; k < 2; ++k) {
      int n = 0;
      for (int y = 4; y < read[k].rows - 4; ++y)
        if (std::isfinite(read[k].at<float>(y, x))) error[k] += read[k].at<float>(y, x) - t_c, ++n;
      ASSERT_GT(n, read[k].rows / 2) << x;
      error[k] /= n;
    }
    std::printf("  cell column %+3d: fit %+7.1f, brightness-radius=%d %+7.1f\n", x - step, error[0],
                kWindow, error[1]);
    // Beyond the window's reach plus the matched kernels' cell they read the plate (the fit's
    // column means scatter by several degrees on the duller side: printed only).
    if (x < step - kWindow - 1 || x > step + kWindow) {
      EXPECT_LT(std::abs(error[1]), 10) << x;
    }
  }
}

// Noiseless planes of a uniform 1500 degC surface, every fit reading 1500 degC.
struct Uniform {
  Snapshot s;
  std::vector<cv::Mat> planes;
  cv::Mat fit = cv::Mat(12, 12, CV_32F, cv::Scalar(1500));
  Uniform() {
    const Eigen::VectorXd rates = s.model->camera.rates(1500);
    const double scale = 150 / rates.maxCoeff();
    for (Eigen::Index b = 0; b < rates.size(); ++b)
      planes.emplace_back(12, 12, CV_32F, cv::Scalar(scale * rates[b]));
  }
};

TEST(SnapshotBrightness, KeepsTheMaskAndReadsEachCellFromItsOwnBands) {
  Uniform u;
  u.fit.at<float>(2, 2) = kNaN;  // the fit did not read here: nor will the brightness
  u.fit.at<float>(6, 6) = 1490;  // a fit reading 10 degC off, alone in its windows
  for (cv::Mat& p : u.planes) p.at<float>(9, 9) *= 1.1f;                 // a cell 10 % brighter
  u.planes[3].at<float>(6, 7) = std::numeric_limits<float>::infinity();  // one band saturated
  cv::Mat t = u.fit.clone();
  SnapshotBrightness(*u.s.model, 1).apply(u.planes, t);
  EXPECT_TRUE(std::isnan(t.at<float>(2, 2)));
  // The 1490 reading's scale error is a ninth of its window's: that cell and its neighbours read
  // about a ninth of 10 degC low, not 10.
  EXPECT_NEAR(t.at<float>(6, 6), 1500 - 10.0 / 9, 0.3);
  EXPECT_NEAR(t.at<float>(6, 7), 1500 - 10.0 / 9, 0.3);  // 24 bands read it
  EXPECT_NEAR(t.at<float>(6, 9), 1500, 0.05);            // out of that window
  // The brighter cell reads hotter by most of its 10 %; its neighbours, whose windows it raises
  // a ninth, cooler.
  EXPECT_GT(t.at<float>(9, 9), 1510);
  EXPECT_LT(t.at<float>(9, 10), 1499);
  EXPECT_NEAR(t.at<float>(9, 11), 1500, 0.05);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 4; ++x)
      if (y != 2 || x != 2) {
        EXPECT_NEAR(t.at<float>(y, x), 1500, 0.05) << x << "," << y;
      }
}

TEST(SnapshotBrightness, CodesReadAsDegreesAndUnreadCellsKeepTheirs) {
  Uniform u;
  for (cv::Mat& p : u.planes) p.at<float>(5, 5) *= 1.1f;
  u.fit.at<float>(0, 0) = kNaN;
  SnapshotBrightness sb(*u.s.model, 2);
  cv::Mat t = u.fit.clone(), codes = encode_decikelvin(u.fit);
  sb.apply(u.planes, t);
  sb.apply_codes(u.planes, codes);
  EXPECT_EQ(codes.at<std::uint16_t>(0, 0), kNoReadingCode);
  // The codes start from 1500.05 degC (the 0.1 K step nearest 1500) and end rounded to a step.
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 12; ++x) {
      if (std::isfinite(t.at<float>(y, x))) {
        EXPECT_NEAR(code_to_celsius(codes.at<std::uint16_t>(y, x)), t.at<float>(y, x), 0.1);
      }
    }
}

// The frames' analogue gain scales each sample's shot noise, and so the bands' weights: a cell
// whose bands disagree (a dim band 20 % brighter, a bright one 10 % duller) reads otherwise at
// 24 dB than at 0 dB, and at 0 dB again as before, bit for bit; cells whose bands agree read
// the same at any gain.
TEST(SnapshotBrightness, WeighsTheBandsAtTheFramesAnalogueGain) {
  Uniform u;
  const Eigen::VectorXd rates = u.s.model->camera.rates(1500);
  Eigen::Index dim_band = 0, bright_band = 0;
  rates.minCoeff(&dim_band);
  rates.maxCoeff(&bright_band);
  u.planes[static_cast<std::size_t>(dim_band)].at<float>(6, 6) *= 1.2f;
  u.planes[static_cast<std::size_t>(bright_band)].at<float>(6, 6) *= 0.9f;
  SnapshotBrightness sb(*u.s.model, 1);
  auto read = [&](double factor) {
    sb.set_analogue_gain(factor);
    cv::Mat t = u.fit.clone();
    sb.apply(u.planes, t);
    return t;
  };
  const cv::Mat unity = read(1), high = read(analogue_gain_factor(24)), again = read(1);
  std::printf("the disagreeing cell: %.3f degC at 0 dB, %.3f at 24 dB\n", unity.at<float>(6, 6),
              high.at<float>(6, 6));
  EXPECT_GT(std::abs(high.at<float>(6, 6) - unity.at<float>(6, 6)), 0.01);
  EXPECT_EQ(cv::countNonZero(again != unity), 0);
  EXPECT_NEAR(high.at<float>(11, 11), unity.at<float>(11, 11), 1e-3);  // out of its window
  EXPECT_THROW(sb.set_analogue_gain(0), InputError);
  EXPECT_THROW(sb.set_analogue_gain(std::numeric_limits<double>::quiet_NaN()), InputError);
}

TEST(SnapshotBrightness, RefusesBadInput) {
  Uniform u;
  EXPECT_THROW(SnapshotBrightness(*u.s.model, 0), InputError);
  EXPECT_THROW(SnapshotBrightness(*u.s.model, SnapshotBrightness::kMaxWindowRadius + 1),
               InputError);
  const CameraProfile colour = load_profile_by_name("rgb-reference");
  EXPECT_THROW(SnapshotBrightness(*true_model(colour, UnitPerturbation::parse("typical", 3)), 2),
               InputError);
  SnapshotBrightness sb(*u.s.model, 2);
  std::vector<cv::Mat> fewer(u.planes.begin(), u.planes.end() - 1);
  cv::Mat t = u.fit.clone();
  EXPECT_THROW(sb.apply(fewer, t), InputError);
  std::vector<cv::Mat> smaller = u.planes;
  smaller[4] = smaller[4](cv::Rect(0, 0, 11, 12)).clone();
  EXPECT_THROW(sb.apply(smaller, t), InputError);
  std::vector<cv::Mat> doubles = u.planes;
  doubles[0].convertTo(doubles[0], CV_64F);
  EXPECT_THROW(sb.apply(doubles, t), InputError);
  cv::Mat codes = encode_decikelvin(u.fit);
  EXPECT_THROW(sb.apply(u.planes, codes), InputError);  // codes are not degC
  EXPECT_THROW(sb.apply_codes(u.planes, t), InputError);
}

}  // namespace
}  // namespace pyrocam
