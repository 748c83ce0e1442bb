// High dynamic range by exposure bracketing (targets): melt pools with a peak of 1500-2500 degC
// filmed at six exposures, the longest for the rim (its hotter part saturates), the shortest
// for the core (its rim is dim), read one by one and fused (BracketFusion: each pixel from the
// most exposed frame where it reads), and fused before demosaicking (MosaicBracketFusion, the
// mosaicfuse element: each sample from the most exposed frame where it is a number and no
// neighbour of its band near the level saturates). Target:
// readings on >= 90 % of the pixels hotter than 1300 degC, with no more than 0.5 % of them wild
// (more than max(150 degC, 10 %) off the truth). With demosaic25's default, matched, measured
// 63.2 % read and 0.02 % wild fusing readings, 87.2 % and 0.45 % fusing mosaics.
// What the 12 % left unread are: 1176 pixels within 2 of a parabolic pool's sharp edge (matched's
// kernels reach the cold background there) and 481 near the simulator pools' 1300 degC
// isotherm, where the blue band's kernel reaches the cooler tail, dim even at the longest
// exposure. A bracket of seven exposures starting three times longer reads those (90.9 %), and
// more of the steep tails then read: 1.11 % wild, each 150-250 degC high on a side falling by
// about 150 degC a pixel, the matched kernel's blur of a signal exponential in temperature
// (blur_bias.h). With the blur correction 0.35 % are wild: the target is met that way.
// Bilinear demosaicking read 90.6 %, but 11 % of its fused readings were wild: on the steep
// sides of the simulator's pools (a factor 2.5 in brightness per pixel) a band interpolated
// from the neighbours at +-1 pixel is off by tens of percent; matched's kernels reach +-2
// pixels, a brightness range no exposure holds between the dim and the saturation thresholds
// there, so those pixels have no reading instead. The model is the camera's true QE with the
// likelihood fit, so that the dynamic range is measured, not the calibration. The scene holds
// still over the bracket.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <vector>

#include "../lib/true_model.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/bracket_fusion.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

constexpr int kW = 320, kH = 240;

// As in the mixed-pixel targets: parabolic from the peak to 1300 degC at the rim, then a sharp
// edge to a cold background; a shape the simulator's scenes do not have.
cv::Mat parabolic_pool(double peak_c) {
  cv::Mat t(kH, kW, CV_32F);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double r2 = std::pow((x - 150.3) / 40.5, 2) + std::pow((y - 121.7) / 17.2, 2);
      t.at<float>(y, x) = static_cast<float>(r2 <= 1 ? peak_c - (peak_c - 1300) * r2 : 300);
    }
  return t;
}

struct Coverage {
  long hot = 0;                 // pixels hotter than 1300 degC
  long read = 0;                // of those, with a reading
  long readings = 0, wild = 0;  // all readings, and those far off
  void add(const cv::Mat& truth, const cv::Mat& codes) {
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const double t = truth.at<float>(y, x);
        const std::uint16_t c = codes.at<std::uint16_t>(y, x);
        if (t > 1300) {
          ++hot;
          read += c != kNoReadingCode;
        }
        if (c == kNoReadingCode) continue;
        ++readings;
        if (!(std::abs(code_to_celsius(c) - t) <= std::max(150.0, 0.1 * t))) ++wild;
      }
  }
  double read_percent() const { return 100.0 * read / std::max(hot, 1L); }
  double wild_percent() const { return 100.0 * wild / std::max(readings, 1L); }
};

struct BracketStudy {
  Coverage long_only, short_only, fused, fused_mosaics;
  // Moving: fused readings (and readings of fused mosaics) far from every frame's truth.
  long readings_of_no_moment = 0, mosaics_of_no_moment = 0;
  // How consecutive frames agreed, over the study (mosaicfuse's motion warning).
  MosaicBracketFusion::Agreement agreement;
  std::vector<cv::Point2d> velocities;  // the mosaic fusion's, at each fused frame
};

// A bracket of `n` exposures, each a third of the one before, the longest `longest` times the
// one that puts a 1400 degC surface's brightest band at 70 % of the usable range.
struct Bracket {
  double longest = 1;
  int n = 6;
  bool blur_correction = false;
  bool moving = false;         // the simulator's pool 0.67 pixels further each frame
  bool follows_motion = true;  // MosaicBracketFusion's
};

BracketStudy study(DemosaicMethod demosaic, Bracket bracket = {}) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const UnitPerturbation unit = UnitPerturbation::parse("typical", 3);
  const auto model = test::true_model(p, unit);
  MeasureOptions options;
  options.method = Method::kLikelihood;
  options.demosaic = demosaic;
  options.blur_correction = bracket.blur_correction;
  FrameMeasurer measurer(model, options);
  Simulator camera(p, unit, 17);
  // The longest exposure puts a 1400 degC surface's brightest band at 70 % of the usable range;
  // each next one is a third of the one before (6 exposures: 1 to 1/243). A colour pixel reads
  // only while all three bands lie between the dim and the saturation thresholds (20 and 170 DN
  // above dark), and its bands differ by up to 2.3 times: one exposure covers a brightness range
  // of less than 4 times, so steps of 3; and a 2500 degC surface is about 300 times brighter
  // than a 1400 degC one in the red band, so six of them.
  const double target_dn = 0.7 * (p.thresholds.inference_saturation_dn - 50);
  const double long_us = bracket.longest * camera.exposure_for(1400, target_dn);
  constexpr double ratio = 3;
  const int n = bracket.n;
  BracketStudy b;
  // Frame k of the bracket sees scene(k); the fused frame is scored against the last one.
  auto frame = [&](const std::function<cv::Mat(int)>& scene) {
    cv::Mat truth = scene(n - 1);
    cv::patchNaNs(truth, 0);  // NaN: the scene's cold background
    BracketFusion fusion(n);
    MosaicBracketFusion mosaic_fusion(n, 2);
    mosaic_fusion.set_follows_motion(bracket.follows_motion);
    cv::Mat codes[16], out, signal, fused_signal;
    double exposures[16];
    for (int k = 0; k < n; ++k) exposures[k] = long_us / std::pow(ratio, k);
    // A moving scene streams: the bracket's cycle before comes first (mosaicfuse finds the
    // velocity between frames of the same exposure).
    for (int k = bracket.moving ? -n : 0; k < n; ++k) {
      const double exposure = exposures[(k + n) % n];
      subtract_dark(camera.render(scene(k), exposure),
                    dark_from_image(camera.render_dark(kW, kH, exposure)),
                    p.thresholds.inference_saturation_dn, signal);
      if (k < 0) {
        mosaic_fusion.add(signal, exposure, fused_signal);
        continue;
      }
      cv::Mat t;
      measurer.measure_signal(signal, t);
      codes[k] = encode_decikelvin(t);
      fusion.add(codes[k], exposures[k], out);
      mosaic_fusion.add(signal, exposures[k], fused_signal);
      if (k == 0) continue;
      b.agreement += mosaic_fusion.last_agreement();
    }
    b.velocities.push_back(mosaic_fusion.velocity());
    b.long_only.add(truth, codes[0]);
    b.short_only.add(truth, codes[n - 1]);
    b.fused.add(truth, out);
    cv::Mat t;
    measurer.measure_signal(fused_signal, t);
    b.fused_mosaics.add(truth, encode_decikelvin(t));
    if (!bracket.moving) return;
    // Readings of no moment: far from the truth of every frame of the bracket.
    std::vector<cv::Mat> truths;
    for (int k = 0; k < n; ++k) truths.push_back(scene(k));
    auto of_no_moment = [&](const cv::Mat& codes) {
      long count = 0;
      for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
          const std::uint16_t c = codes.at<std::uint16_t>(y, x);
          if (c == kNoReadingCode) continue;
          bool near_one = false;
          for (const cv::Mat& m : truths) {
            const double tk = std::isfinite(m.at<float>(y, x)) ? m.at<float>(y, x) : 0.0;
            near_one |= std::abs(code_to_celsius(c) - tk) <= std::max(150.0, 0.1 * tk);
          }
          count += !near_one;
        }
      return count;
    };
    b.readings_of_no_moment += of_no_moment(out);
    b.mosaics_of_no_moment += of_no_moment(encode_decikelvin(t));
  };
  if (bracket.moving) {
    // 320 pixels at 0.5 / 239 of the width a frame: 0.67 pixels.
    for (int i = n; i < 240 - n; i += 16)
      frame([&](int k) { return melt_pool_scene(kW, kH, i + k, 240); });
    return b;
  }
  for (int i = 0; i < 60; i += 4) frame([&](int) { return melt_pool_scene(kW, kH, i, 60); });
  for (double peak : {1500.0, 2000.0, 2500.0}) frame([&](int) { return parabolic_pool(peak); });
  return b;
}

void print(const char* what, const BracketStudy& b) {
  std::printf("%s (samples consecutive frames disagree on: %zu of %zu)\n", what,
              b.agreement.disagreeing, b.agreement.compared);
  for (const auto& [name, c] : {std::pair{"long exposure", b.long_only},
                                {"shortest exposure", b.short_only},
                                {"readings fused", b.fused},
                                {"mosaics fused", b.fused_mosaics}})
    std::printf(
        "  %-22s %5.1f %% of %ld pixels hotter than 1300 degC read; %.2f %% of %ld "
        "readings wild\n",
        name, c.read_percent(), c.hot, c.wild_percent(), c.readings);
}

TEST(BracketTargets, TheCoreAndTheRimReadInOneFusedFrame) {
  const BracketStudy matched = study(DemosaicMethod::kAuto),
                     bilinear = study(DemosaicMethod::kBilinear);
  print("matched demosaicking (the default)", matched);
  print("bilinear demosaicking", bilinear);
  const Coverage& fused = matched.fused;
  // Seeded simulation: the loose bounds cover another libm's noise draws. Coverage: a regression
  // bound (measured 63.2 %; the target of 90 % is not met, see above).
  EXPECT_GE(fused.read_percent(), 58);
  EXPECT_GE(fused.read_percent(),
            2.5 * std::max(matched.long_only.read_percent(), matched.short_only.read_percent()));
  EXPECT_LE(fused.wild_percent(), 0.5);
  EXPECT_LE(fused.wild_percent(),
            std::max(matched.long_only.wild_percent(), matched.short_only.wild_percent()) + 0.05);
  // Fused before demosaicking (mosaicfuse): every band of a footprint has a number even on the
  // steep sides. Measured 87.2 % read (target 90, NOT MET: matched's ring at the parabolic
  // pools' sharp edges), 0.45 % of the readings wild (55 of 12323; the bound, 98, is 5.8 Poisson
  // standard deviations above that count).
  const Coverage& mosaics = matched.fused_mosaics;
  EXPECT_GE(mosaics.read_percent(), 85);
  EXPECT_GE(mosaics.read_percent(), fused.read_percent() + 15);
  EXPECT_LE(mosaics.wild_percent(), 0.8);
  // The scenes hold still: consecutive frames agree on every sample both expose well (0 of
  // 12269 measured; the bound on the noise is several times the sensor's).
  EXPECT_LE(matched.agreement.disagreeing, 2u);
  EXPECT_FALSE(matched.agreement.moved());
  // What the default gives up: bilinear reads more pixels, many of them wild.
  EXPECT_GT(bilinear.fused.read_percent(), fused.read_percent());
  EXPECT_GT(bilinear.fused.wild_percent(), 2);
}

TEST(BracketTargets, ALongerBracketWithTheBlurCorrectionReadsTheRim) {
  const Bracket longer{3, 7, false}, corrected{3, 7, true};
  const BracketStudy plain = study(DemosaicMethod::kAuto, longer),
                     fixed = study(DemosaicMethod::kAuto, corrected);
  print("matched, 7 exposures from 3 times longer", plain);
  print("the same with the blur correction", fixed);
  // Coverage: measured 90.9 % (12567 of 13825); most of what stays unread is the ring at the
  // parabolic pools' edges, fixed by geometry, and the count's binomial standard deviation is
  // about 34 pixels (0.25 %): the target itself is the bound, 3.6 of them below (another
  // libm's noise draws fall short with a probability of about 2e-4).
  EXPECT_GE(fixed.fused_mosaics.read_percent(), 90);
  // The correction changes readings, not which pixels read.
  EXPECT_EQ(fixed.fused_mosaics.read, plain.fused_mosaics.read);
  // Wild: measured 163 of 14661 readings (1.11 %) without the correction, 51 (0.35 %) with it.
  // Bounds about 8 Poisson standard deviations from those counts: at most 0.75 % with it (110),
  // and at most 0.7 times as many as without (114; the difference 112, its deviation 15).
  EXPECT_LE(fixed.fused_mosaics.wild_percent(), 0.75);
  EXPECT_LE(fixed.fused_mosaics.wild, 0.7 * plain.fused_mosaics.wild);
}

// The simulator's pool moving 0.67 pixels a frame over the bracket (six frames: about four
// pixels; in whole pixels, 0 or 1 a frame, and its peak changing by up to 20 degC a frame), each
// fused frame scored against the last frame's truth, the bracket's cycle before fused first.
// thermalfuse's readings are each of one frame, some of them older (where the pool was then).
// Without following the motion mosaicfuse's footprints hold samples of different moments, and
// on the pool's steep sides their ratios are of no temperature at all: 34-35 % of the fused
// mosaics' readings off the last frame's truth, 497-541 far from every frame's. (A check that
// left a sample without a number where the frames disagreed on it beyond a bound on its noise
// caught 18 of 535: each sample of such a footprint agrees with the frames that can see it, a
// short exposure's noise scaled up hides the rest; not kept.) Following it (the default), each
// earlier frame's samples are taken from where the pool has moved since (along the curve of
// their logarithm) and brought forward by the brightness change found between frames of one
// exposure: 93.1 % of the hot pixels read, 8.2 % of the readings wild (12.2 % before the
// brightness change was followed and displaced samples from 1 DN up were interpolated in the
// logarithm); with the longer bracket and the blur correction (README) 96.9 % and 10.2 % (a
// scratch run). What is left (scratch studies: the pool moving smoothly with its peak held 2.8 %
// wild, 1.2 % without noise) reads high at the pool's steep front, where a long exposure's
// sample interpolated beside its saturated zone and a dim one meet in a footprint. The bounds
// are about 8 Poisson deviations from the counts.
TEST(BracketTargets, OnAMovingPoolTheMosaicFusionFollowsThePool) {
  Bracket moving;
  moving.moving = true;
  moving.follows_motion = false;
  const BracketStudy still = study(DemosaicMethod::kAuto, moving);
  print("matched, the pool moving 0.67 pixels a frame, not followed", still);
  std::printf(
      "  far from every frame's truth: %ld of the fused readings, %ld of the fused mosaics'\n",
      still.readings_of_no_moment, still.mosaics_of_no_moment);
  moving.follows_motion = true;
  const BracketStudy followed = study(DemosaicMethod::kAuto, moving);
  print("the same, followed (the default)", followed);
  double sum = 0;
  for (const cv::Point2d& v : followed.velocities) sum += v.x;
  const double mean_vx = sum / static_cast<double>(followed.velocities.size());
  std::printf("  velocity found: %.3f pixels a frame along the track on average over %zu frames\n",
              mean_vx, followed.velocities.size());
  // mosaicfuse sees it move: consecutive frames disagreed on 107 of 6708 samples both expose
  // well (1.6 %; the bound is 40, about 7 Poisson deviations below).
  EXPECT_GE(still.agreement.disagreeing, 40u);
  EXPECT_TRUE(still.agreement.moved());
  EXPECT_LE(still.readings_of_no_moment, 20);
  EXPECT_GE(still.mosaics_of_no_moment, 350);
  EXPECT_LT(still.fused.wild_percent(), 0.5 * still.fused_mosaics.wild_percent());
  for (const cv::Point2d& v : still.velocities) EXPECT_EQ(v, cv::Point2d());
  // Followed: the velocity within 0.1 pixel a frame of the pool's mean (0.667; each frame's
  // from one cycle of whole-pixel steps, 0.33-1.0, a mean of 15), more of the hot pixels read
  // and about a quarter as many readings wild (measured 586 of 7139 against 35.0 %; the bound,
  // 0.35 of that share, is 870 readings, about 12 Poisson deviations above the count).
  EXPECT_NEAR(mean_vx, 0.667, 0.1);
  EXPECT_GE(followed.fused_mosaics.read_percent(), 90);
  EXPECT_GT(followed.fused_mosaics.read_percent(), still.fused_mosaics.read_percent() + 5);
  EXPECT_LT(followed.fused_mosaics.wild_percent(), 0.35 * still.fused_mosaics.wild_percent());
}

}  // namespace
}  // namespace pyrocam
