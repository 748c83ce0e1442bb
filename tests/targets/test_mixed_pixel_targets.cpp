// Sharp edges and mixed pixels (targets): the colour camera's readings of plates and melt pools
// with bilinear demosaicking, with and without the footprint check (mixed_pixels.h, at its
// suggested relative spread), and with moment-matched demosaicking (demosaic_matched.cpp) without
// the check. A reading is wild when it is more than max(150 degC, 10 % of the truth in degC) off
// the truth; interior pixels are those whose 5x5 neighbourhood is one temperature (within 1 % in
// kelvin) and that read bilinear without the check. Target: wild readings <= 0.5 % of all readings,
// >= 95 % of interior pixels keep a reading. The model is the camera's true QE with the likelihood
// fit, so that only the edges are measured, not the calibration. Scenes: the simulator's plates and
// melt pools, and melt pools of another shape (a parabolic profile from the peak down to 1300 degC,
// then a sharp edge to a cold background), which the simulator does not make.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "../lib/true_model.h"
#include "pyrocam/core/physics.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

constexpr int kW = 320, kH = 240;

// An elongated pool centred at (cx, cy): parabolic from peak_c at its centre to 1300 degC at
// its rim, then a sharp edge to 300 degC (no signal).
cv::Mat parabolic_pool(double peak_c, double cx, double cy, double rx, double ry, int w = kW,
                       int h = kH) {
  cv::Mat t(h, w, CV_32F);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double r2 = std::pow((x - cx) / rx, 2) + std::pow((y - cy) / ry, 2);
      t.at<float>(y, x) = static_cast<float>(r2 <= 1 ? peak_c - (peak_c - 1300) * r2 : 300);
    }
  return t;
}

struct Counts {
  long readings = 0, wild = 0, interior = 0, interior_read = 0;
  void add(const Counts& o) {
    readings += o.readings, wild += o.wild, interior += o.interior,
        interior_read += o.interior_read;
  }
};

Counts count(const cv::Mat& truth, const cv::Mat& plain, const cv::Mat& checked) {
  cv::Mat lo, hi;
  const cv::Mat kernel = cv::Mat::ones(5, 5, CV_8U);
  cv::erode(truth, lo, kernel);
  cv::dilate(truth, hi, kernel);
  Counts c;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double t = truth.at<float>(y, x), r = checked.at<float>(y, x);
      if (std::isfinite(r)) {
        ++c.readings;
        if (std::abs(r - t) > std::max(150.0, 0.1 * t)) ++c.wild;
      }
      const bool interior = hi.at<float>(y, x) - lo.at<float>(y, x) <= 0.01 * (t + kZeroCelsius);
      if (interior && std::isfinite(plain.at<float>(y, x))) {
        ++c.interior;
        if (std::isfinite(r)) ++c.interior_read;
      }
    }
  return c;
}

struct Study {
  Counts plates, pools, other_pools;
};

Study run(double spread, DemosaicMethod demosaic = DemosaicMethod::kBilinear) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  const auto model = test::true_model(p, unit);
  MeasureOptions plain_options;
  plain_options.method = Method::kLikelihood;
  plain_options.demosaic = DemosaicMethod::kBilinear;
  MeasureOptions checked_options = plain_options;
  checked_options.footprint_spread = spread;
  checked_options.demosaic = demosaic;
  FrameMeasurer plain(model, plain_options), checked(model, checked_options);
  Simulator camera(p, unit, 11);
  // The exposure that puts the brightest band of the hottest place at 70 % of the usable range,
  // as autoexposure keeps it.
  const double target_dn = 0.7 * (p.thresholds.inference_saturation_dn - 50);
  Study s;
  auto measure = [&](const cv::Mat& truth, Counts& into) {
    cv::Mat finite;
    cv::patchNaNs(finite = truth.clone(), 0);  // NaN: the scene's background
    double hottest;
    cv::minMaxLoc(finite, nullptr, &hottest);
    const double exposure = camera.exposure_for(hottest, target_dn);
    const cv::Mat raw = camera.render(truth, exposure);
    const cv::Mat dark = camera.render_dark(kW, kH, exposure);
    cv::Mat a, b;
    plain.measure(raw, dark, a);
    checked.measure(raw, dark, b);
    into.add(count(truth, a, b));
  };
  for (double t : {735.0, 1000.0, 1500.0, 2000.0, 2500.0})
    measure(plate_scene(kW, kH, t), s.plates);
  for (int i = 0; i < 60; i += 6) measure(melt_pool_scene(kW, kH, i, 60), s.pools);
  for (double peak : {1500.0, 2000.0, 2500.0})
    measure(parabolic_pool(peak, 150.3, 121.7, 40.5, 17.2), s.other_pools);
  return s;
}

void print(const char* what, const Counts& c) {
  std::printf("  %-22s readings %7ld, wild %5ld (%.3f %%), interior %6ld, kept %.2f %%\n", what,
              c.readings, c.wild, 100.0 * c.wild / std::max(c.readings, 1L), c.interior,
              100.0 * c.interior_read / std::max(c.interior, 1L));
}

double percent(long part, long whole) { return 100.0 * part / std::max(whole, 1L); }

TEST(MixedPixelTargets, FewWildReadingsOnPlatesAndTheInteriorKept) {
  const Study off = run(0), on = run(kDefaultFootprintSpread);
  std::printf("footprint check off\n");
  print("plates", off.plates);
  print("melt pools", off.pools);
  print("other melt pools", off.other_pools);
  std::printf("footprint check on (relative spread %.2f)\n", kDefaultFootprintSpread);
  print("plates", on.plates);
  print("melt pools", on.pools);
  print("other melt pools", on.other_pools);
  const Study matched = run(0, DemosaicMethod::kMatched);
  std::printf("moment-matched demosaicking, no footprint check\n");
  print("plates", matched.plates);
  print("melt pools", matched.pools);
  print("other melt pools", matched.other_pools);
  // Plates: the edges' mixed pixels are most of the wild readings, and the check removes them.
  EXPECT_GT(percent(off.plates.wild, off.plates.readings), 0.5);
  EXPECT_LE(percent(on.plates.wild, on.plates.readings), 0.5);
  EXPECT_GE(percent(on.plates.interior_read, on.plates.interior), 95);
  EXPECT_GE(percent(on.other_pools.interior_read, on.other_pools.interior), 95);
  // Melt pools (not met, see docs/elements.md): their wild readings are not mixed pixels. No
  // footprint of one holds a sample without light, and each is within 2.7 of its own standard
  // uncertainty (90-680 degC): dim bands in the parabolic pools' cooler part, and on the
  // simulator's pools noise on the steep sides and bilinear's curvature error at the peak. The
  // check must not add to them beyond what it removes, nor take the pools' steep sides (measured:
  // 510 of the simulator pools' 600 readings stay, 2690 of the parabolic pools' 2693; with a
  // relative spread of 0.2, 114 and 2557, before the dim-edge check).
  EXPECT_LE(on.other_pools.wild, off.other_pools.wild);
  EXPECT_GE(on.pools.readings, off.pools.readings * 8 / 10);
  EXPECT_GE(on.other_pools.readings, off.other_pools.readings * 95 / 100);
  // Matched: the bands' interpolation errors cancel in their ratios, and samples without light
  // (a cold background) make a band dim instead of mixing into it: the target on every scene
  // without the check. It loses the ring of pixels whose 5x5 kernel reaches past an edge.
  for (const Counts* c : {&matched.plates, &matched.pools, &matched.other_pools})
    EXPECT_LE(percent(c->wild, c->readings), 0.5);
  EXPECT_GE(percent(matched.plates.interior_read, matched.plates.interior), 95);
  EXPECT_GE(percent(matched.other_pools.interior_read, matched.other_pools.interior), 95);
  EXPECT_GE(matched.pools.readings, off.pools.readings * 9 / 10);
}

// The melt pool's core: frames of the simulator's pool (its peak swings between 1500 and 2500
// degC) and of the parabolic pools, at one fixed exposure (the camera's for 2000 degC, as
// pyrocamsrc's default: the hotter cores saturate the red band, the cooler ones are dim) or at
// the exposure autoexposure keeps (the peak's brightest band at 70 % of the usable range), with
// the default demosaicking (matched). The core is the pixels within 50 degC of the frame's peak;
// its reading is the median of its readings, against the median of its true temperatures.
struct CoreFigures {
  int frames = 0, within_10 = 0, without_reading = 0;
  double read_fraction = 0;    // of the core pixels, over all frames
  std::vector<double> errors;  // core median read - true, degC, per frame with a reading
};

// The simulator's pool (every third of 60 frames) and five parabolic pools.
std::vector<cv::Mat> pool_frames() {
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 60; i += 3) frames.push_back(melt_pool_scene(kW, kH, i, 60));
  for (double peak : {1500.0, 1750.0, 2000.0, 2250.0, 2500.0})
    frames.push_back(parabolic_pool(peak, 150.3, 121.7, 40.5, 17.2));
  return frames;
}

CoreFigures core_study(bool safe_partial, bool exposed_for_the_peak, int brightness_radius = 0,
                       const std::vector<cv::Mat>& scenes = pool_frames()) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  const auto model = test::true_model(p, unit);
  MeasureOptions options;
  options.method = Method::kLikelihood;
  options.safe_partial = safe_partial;
  options.brightness_radius = brightness_radius;
  FrameMeasurer measurer(model, options);
  Simulator camera(p, unit, 13);
  CoreFigures f;
  long core_pixels = 0, core_read = 0;
  auto frame = [&](const cv::Mat& truth) {
    cv::Mat finite;
    cv::patchNaNs(finite = truth.clone(), 0);
    double peak;
    cv::minMaxLoc(finite, nullptr, &peak);
    const double exposure =
        exposed_for_the_peak
            ? camera.exposure_for(peak, 0.7 * (p.thresholds.inference_saturation_dn - 50))
            : camera.exposure_for(2000, 140);
    cv::Mat t;
    measurer.measure(camera.render(truth, exposure), camera.render_dark(kW, kH, exposure), t);
    std::vector<float> read, real;
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        if (!(truth.at<float>(y, x) >= peak - 50)) continue;  // NaN: the scene's background
        real.push_back(truth.at<float>(y, x));
        if (std::isfinite(t.at<float>(y, x))) read.push_back(t.at<float>(y, x));
      }
    core_pixels += static_cast<long>(real.size());
    core_read += static_cast<long>(read.size());
    ++f.frames;
    if (read.empty()) {
      ++f.without_reading;
      return;
    }
    auto median = [](std::vector<float> v) {
      std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
      return v[v.size() / 2];
    };
    const double error = median(read) - median(real);
    f.within_10 += std::abs(error) <= 10;
    f.errors.push_back(error);
  };
  for (const cv::Mat& truth : scenes) frame(truth);
  f.read_fraction = static_cast<double>(core_read) / std::max(core_pixels, 1L);
  return f;
}

double rms(const CoreFigures& f) {
  double s = 0;
  for (double e : f.errors) s += e * e;
  return std::sqrt(s / static_cast<double>(std::max<std::size_t>(f.errors.size(), 1)));
}

TEST(MeltPoolCoreTargets, TheCoreReadsWhenExposedForThePeak) {
  const CoreFigures fixed = core_study(true, false), ratio = core_study(true, true),
                    exposed = core_study(true, true, 2);
  for (const auto& [name, f] : {std::pair{"fixed exposure", fixed},
                                {"exposed for the peak", ratio},
                                {"brightness-radius 2", exposed}})
    std::printf(
        "%-20s %d frames: core median within 10 degC in %d, no core reading in %d; "
        "%.1f %% of core pixels read\n",
        name, f.frames, f.within_10, f.without_reading, 100 * f.read_fraction);
  for (const auto& [name, f] :
       {std::pair{"exposed for the peak", ratio}, {"brightness-radius 2", exposed}}) {
    std::printf("core median errors, %s (degC, %.1f rms):", name, rms(f));
    for (double e : f.errors) std::printf(" %.0f", e);
    std::printf("\n");
  }
  // A fixed exposure leaves most cores without a reading (saturated or dim); exposed for the
  // peak (autoexposure) every core reads. The 10 degC target on the core median is not met (see
  // the figures): the simulated pools' cores are a few pixels across around a kink at the peak.
  // The ratio readings alias the kink by Bayer column (-27..-125 degC with the peak on a red
  // column, +8..+57 degC on a green one); the brightness readings (opt-in: one emissivity over
  // the window) read each pixel's own sample and leave the noise of a few samples and the
  // window's share of the ratio's error.
  EXPECT_GE(fixed.without_reading, fixed.frames / 2);
  EXPECT_EQ(ratio.without_reading, 0);
  EXPECT_GE(ratio.read_fraction, 0.95);
  EXPECT_EQ(ratio.read_fraction, exposed.read_fraction);  // the same pixels read
  EXPECT_LT(rms(exposed), 0.6 * rms(ratio));
}

// Smooth pools, as the independent scenes: parabolic from the peak (1500-2500 degC in
// steps of 125) to 1300 degC at the rim, 40.5 x 17.2 and 20.3 x 8.6 pixels in semi-axes, at two
// sub-pixel places, exposed for the peak (cores of 21-546 pixels). Target: the core median
// within 10 degC in 95 % of frames, NOT MET: 23 of 36 measured (13.8 degC rms); 15 of the 18
// larger pools (cores of 89-546 pixels, where the median's own noise is 3-9 degC), 8 of the 18
// smaller ones. There every core reading is 15-30 degC low: a reading is the field seen through
// the matched kernels' blur, which lowers a peak by half its Laplacian times the kernels'
// variance (1 px^2 a side): -17 degC predicted for the smaller 2375 degC pool, -18 measured over
// four noise draws. Brightness readings: 31 of 36 (9.1 degC rms). Regression bounds, five and
// six frames below the counts measured. What is left is the sensor's noise, not a bias: without
// it (Simulator::set_noise_enabled(false)) the brightness readings put 36 of 36 within 10 degC
// at radius 1-8, and so does taking half a 2-pixel-stencil Laplacian off the ratio readings
// (2.5 degC rms; 23 of 36 with noise). With noise a small pool's core median moves with the
// mean noise of the ratio readings its window holds; neighbouring readings share samples, so
// one scale pooled over the four Bayer phases did no better (58 against 57 of 72 over two
// draws at radius 4), and weighting the scales by signal did worse (the core's readings carry
// the blur's share).
std::vector<cv::Mat> smooth_pool_frames() {
  std::vector<cv::Mat> frames;
  for (double size : {1.0, 0.5})
    for (double peak = 1500; peak <= 2500; peak += 125)
      for (double offset : {0.0, 0.5})
        frames.push_back(
            parabolic_pool(peak, 150.3 + offset, 121.7 + offset, 40.5 * size, 17.2 * size));
  return frames;
}

TEST(MeltPoolCoreTargets, SmoothPoolsCoreMedian) {
  const std::vector<cv::Mat> scenes = smooth_pool_frames();
  const CoreFigures ratio = core_study(true, true, 0, scenes),
                    brightness = core_study(true, true, 2, scenes);
  for (const auto& [name, f] :
       {std::pair{"ratio readings", ratio}, std::pair{"brightness-radius 2", brightness}}) {
    std::printf("smooth pools, %s: core median within 10 degC in %d of %d frames, %.1f rms:", name,
                f.within_10, f.frames, rms(f));
    for (double e : f.errors) std::printf(" %.0f", e);
    std::printf("\n");
  }
  EXPECT_EQ(ratio.without_reading, 0);
  EXPECT_GE(ratio.read_fraction, 0.99);
  EXPECT_GE(ratio.within_10, 18);
  EXPECT_LT(rms(ratio), 18);
  EXPECT_GE(brightness.within_10, 25);
}

// The 5x5 camera on parabolic pools (peaks 1500-2500 degC, 160x70 and 80x35 pixels, two noise
// seeds each; 640x480 pixels, 128x96 macro-pixels), exposed for the peak, the camera's true QE,
// likelihood with partial bands: binned, each band is read where it sits in its cell, up to 2
// pixels from the others, so in the pool's gradient one cell's bands see different
// temperatures; matched reads them all at the cell's centre. The core is the cells whose centre
// is within 50 degC of the peak; a reading is wild as above.
struct SnapshotFigures {
  double core_rms_c = 0;
  double wild_percent = 0;
  int frames = 0, within_10 = 0;  // frames whose core median is within 10 degC
};

SnapshotFigures snapshot_study(DemosaicMethod demosaic, int brightness_radius = 0, int seeds = 2,
                               const std::vector<double>& peaks = {1500, 2000, 2500}) {
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  const UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  const auto model = test::true_model(p, unit);
  MeasureOptions options;
  options.method = Method::kLikelihood;
  options.demosaic = demosaic;
  options.safe_partial = true;
  options.brightness_radius = brightness_radius;
  FrameMeasurer measurer(model, options);
  constexpr int kSensorW = 640, kSensorH = 480;
  SnapshotFigures f;
  double sum2 = 0;
  long readings = 0, wild = 0;
  for (double peak : peaks)
    for (double size : {1.0, 0.5})
      for (int seed = 0; seed < seeds; ++seed) {
        Simulator camera(p, unit, 200 + seed);
        const cv::Mat truth = parabolic_pool(peak, 321.3 + seed, 243.7 - seed, 160 * size,
                                             70 * size, kSensorW, kSensorH);
        const double exposure = camera.exposure_for(
            peak, 0.7 * (p.thresholds.inference_saturation_dn - p.dark_offset_dn));
        cv::Mat t;
        measurer.measure(camera.render(truth, exposure),
                         camera.render_dark(kSensorW, kSensorH, exposure), t);
        std::vector<float> read, real;
        for (int y = 0; y < t.rows; ++y)
          for (int x = 0; x < t.cols; ++x) {
            const float truth_c = truth.at<float>(y * 5 + 2, x * 5 + 2), r = t.at<float>(y, x);
            if (std::isfinite(r)) {
              ++readings;
              wild += std::abs(r - truth_c) > std::max(150.0, 0.1 * truth_c);
            }
            if (truth_c < peak - 50) continue;
            real.push_back(truth_c);
            if (std::isfinite(r)) read.push_back(r);
          }
        ++f.frames;
        if (read.empty()) {
          sum2 += 1e6;  // a core without a reading counts as 1000 degC off
          continue;
        }
        auto median = [](std::vector<float> v) {
          std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
          return v[v.size() / 2];
        };
        const double e = median(read) - median(real);
        sum2 += e * e;
        f.within_10 += std::abs(e) <= 10;
      }
  f.core_rms_c = std::sqrt(sum2 / f.frames);
  f.wild_percent = percent(wild, readings);
  return f;
}

TEST(SnapshotMeltPoolTargets, MatchedReadsTheCoreAndFewWildCells) {
  const SnapshotFigures binned = snapshot_study(DemosaicMethod::kBinCells);
  const SnapshotFigures matched = snapshot_study(DemosaicMethod::kMatched);
  for (const auto& [name, f] : {std::pair{"binned", binned}, {"matched", matched}})
    std::printf(
        "5x5 parabolic pools, %-8s %d frames: core median %.1f degC rms (within 10 degC in %d), "
        "wild %.2f %%\n",
        name, f.frames, f.core_rms_c, f.within_10, f.wild_percent);
  // Loose bounds on a seeded simulation (measured 5.4 degC and 0 of 7031 readings wild, against
  // 38 degC and 28 % of 7514; 5575 and 6140 readings before the fit weighed bands below the dim
  // threshold); the comparison shows the gradient error that matched removes. The wild bound is
  // the target's: before safe partial readings had to be precise (within max_partial_sigma_c),
  // 87 of 7155 readings (1.2 %) were wild, all at the pools' dim rim from a few bands near the
  // noise.
  EXPECT_LE(matched.core_rms_c, 15);
  EXPECT_LE(matched.wild_percent, 0.5);
  EXPECT_GT(binned.core_rms_c, 2 * matched.core_rms_c);
  EXPECT_GT(binned.wild_percent, 2 * matched.wild_percent);
}

// The core target on the 5x5 camera: peaks 1500-2500 degC in steps of 250, both sizes, four
// noise seeds (40 frames). The fit's core median is within 10 degC in 37 of 40 (4.9 degC rms):
// what misses is the noise of a median of 16-60 cells (a cell reads about 25 degC rms at 2500
// degC). Brightness readings (snapshot_brightness.h) read each cell from its own 25 bands, their
// scales the fit's over 5 x 5 cells: 39 of 40 (4.0 degC rms), the target of 95 % met on these
// scenes. Regression bounds two frames below the count.
TEST(SnapshotMeltPoolTargets, BrightnessReadingsPutTheCoreMedianWithinTenDegrees) {
  const std::vector<double> peaks = {1500, 1750, 2000, 2250, 2500};
  const SnapshotFigures fit = snapshot_study(DemosaicMethod::kMatched, 0, 4, peaks);
  const SnapshotFigures bright = snapshot_study(DemosaicMethod::kMatched, 2, 4, peaks);
  for (const auto& [name, f] : {std::pair{"fit", fit}, {"brightness-radius 2", bright}})
    std::printf(
        "5x5 parabolic pools, %-19s %d frames: core median within 10 degC in %d (%.1f degC "
        "rms), wild %.2f %%\n",
        name, f.frames, f.within_10, f.core_rms_c, f.wild_percent);
  ASSERT_EQ(bright.frames, 40);
  EXPECT_GE(bright.within_10, 37);
  EXPECT_LT(bright.core_rms_c, fit.core_rms_c);
  EXPECT_LE(bright.wild_percent, 0.5);
}

}  // namespace
}  // namespace pyrocam
