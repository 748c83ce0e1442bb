// Following a moving scene over an exposure bracket: the shift between two frames of one
// exposure, and samples taken from where the content moved.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>

#include "pyrocam/runtime/bracket_fusion.h"
#include "runtime/bracket_motion.h"

namespace pyrocam {
namespace {

using bracket_motion::cell_logs;
using bracket_motion::find_shift;

constexpr int kW = 96, kH = 64;

// Sample (x, y) of a frame whose content moved since (d).
float displaced_sample(const cv::Mat& signal, const cv::Mat& near_level,
                       const bracket_motion::Displacement& d, int x, int y, bool* near) {
  return bracket_motion::DisplacedRow(signal, near_level, bracket_motion::sample_logs(signal), d, y)
      .at(x, near);
}

// A mosaic whose every sample is `field` at its position (a band's scale makes no difference
// to the interpolation along its own samples).
template <typename F>
cv::Mat mosaic(F field) {
  cv::Mat m(kH, kW, CV_32F);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) m.at<float>(y, x) = static_cast<float>(field(x, y));
  return m;
}

// A hot spot of 160 DN at (cx, cy), 2 sigma (12 pixels by default) across, on a background of
// 2 DN.
cv::Mat spot(double cx, double cy, double scale = 1, double sigma = 6) {
  return mosaic([&](double x, double y) {
    const double r2 = (x - cx) * (x - cx) + (y - cy) * (y - cy);
    return 2 + scale * 160 * std::exp(-r2 / (2 * sigma * sigma));
  });
}

TEST(BracketMotion, ADisplacedSampleIsTheFieldWhereTheContentWas) {
  // Brightness exponential in position (a steep side): interpolated in the logarithm, exact.
  auto side = [](double x, double y) { return 40 * std::exp(0.04 * x - 0.03 * y); };
  const cv::Mat signal = mosaic(side);
  const cv::Mat none = cv::Mat::zeros(kH, kW, CV_8U);
  for (const cv::Point2d shift : {cv::Point2d(1.3, -0.7), cv::Point2d(-3.6, 2.2),
                                  cv::Point2d(4.0, 0.0), cv::Point2d(0.5, 0.5)})
    for (const cv::Point p : {cv::Point(40, 30), cv::Point(41, 31), cv::Point(20, 45)}) {
      bool near = true;
      const float v = displaced_sample(signal, none, {shift, 2}, p.x, p.y, &near);
      EXPECT_NEAR(v, side(p.x - shift.x, p.y - shift.y), 1e-4 * v) << shift << " at " << p;
      EXPECT_FALSE(near);
    }
  // Under the log's floor (noise about no light) linearly: a plane stays a plane.
  const cv::Mat dim = mosaic([](double x, double y) { return 0.2 + 0.005 * x + 0.002 * y; });
  bool near;
  EXPECT_NEAR(displaced_sample(dim, none, {cv::Point2d(1.5, -0.5), 2}, 40, 30, &near),
              0.2 + 0.005 * 38.5 + 0.002 * 30.5, 1e-6);
  // A dim side (2-6 DN, under the dim threshold) still in the logarithm, as its brighter
  // neighbours are: bands interpolated in different ways would meet in one footprint.
  auto faint = [](double x, double y) { return 2 * std::exp(0.01 * x + 0.005 * y); };
  EXPECT_NEAR(displaced_sample(mosaic(faint), none, {cv::Point2d(1.5, -0.5), 2}, 40, 30, &near),
              faint(38.5, 30.5), 1e-5);
}

// Across a peak, and beside a saturated zone, the logarithm curves: a field whose logarithm is
// quadratic (a melt pool's peak) is interpolated exactly, by the cubic where all four nodes
// along each axis are known, by a quadratic where the inner one saturates; the nearest two's
// chord alone would be several percent low.
TEST(BracketMotion, ACurvedLogarithmIsInterpolatedAlongItsCurve) {
  auto peak = [](double x, double y) {
    return 150 * std::exp(-((x - 40) * (x - 40) + 0.5 * (y - 30) * (y - 30)) / 60);
  };
  cv::Mat signal = mosaic(peak);
  const cv::Mat none = cv::Mat::zeros(kH, kW, CV_8U);
  const cv::Point2d shift(1.4, -0.6);
  bool near;
  for (const cv::Point p : {cv::Point(40, 30), cv::Point(42, 31), cv::Point(46, 28)}) {
    const double truth = peak(p.x - shift.x, p.y - shift.y);
    EXPECT_NEAR(displaced_sample(signal, none, {shift, 2}, p.x, p.y, &near), truth, 1e-4 * truth)
        << p;
    // The nearest two's chord, without the frame's logarithms: off by more than 1 %.
    const float chord =
        bracket_motion::DisplacedRow(signal, none, cv::Mat(), {shift, 2}, p.y).at(p.x, &near);
    EXPECT_GT(std::abs(chord - truth), 0.01 * truth) << p;
  }
  // Pixel (47, 30) shifted by (1.4, 0) lies between samples 45 and 47; the cubic's inner node,
  // 43, saturated: the quadratic on 45, 47, 49 is exact too.
  signal.at<float>(30, 43) = std::numeric_limits<float>::infinity();
  const double truth = peak(47 - 1.4, 30);
  EXPECT_NEAR(displaced_sample(signal, none, {cv::Point2d(1.4, 0), 2}, 47, 30, &near), truth,
              1e-4 * truth);
}

TEST(BracketMotion, ADisplacedSampleKeepsNoReadingSaturationAndTheLevelsNeighbourhood) {
  cv::Mat signal(kH, kW, CV_32F, cv::Scalar(50));
  cv::Mat near_level = cv::Mat::zeros(kH, kW, CV_8U);
  signal.at<float>(30, 38) = std::numeric_limits<float>::infinity();
  signal.at<float>(10, 38) = std::numeric_limits<float>::quiet_NaN();
  near_level.at<std::uint8_t>(50, 40) = 1;
  bool near;
  // (40, 30) shifted by (1, 0) takes its band's samples at x = 38 and 40.
  EXPECT_EQ(displaced_sample(signal, near_level, {cv::Point2d(1, 0), 2}, 40, 30, &near),
            std::numeric_limits<float>::infinity());
  EXPECT_TRUE(
      std::isnan(displaced_sample(signal, near_level, {cv::Point2d(1, 0), 2}, 40, 10, &near)));
  EXPECT_FLOAT_EQ(displaced_sample(signal, near_level, {cv::Point2d(1, 0), 2}, 40, 50, &near), 50);
  EXPECT_TRUE(near);
  // (Equal to float rounding: a sample's logarithm is kept in single precision.) A whole cell's
  // shift takes the one sample: the one at 38 is not part of (42, 50)'s.
  EXPECT_FLOAT_EQ(displaced_sample(signal, near_level, {cv::Point2d(2, 0), 2}, 42, 50, &near), 50);
  EXPECT_TRUE(near);
  EXPECT_FLOAT_EQ(displaced_sample(signal, near_level, {cv::Point2d(2, 0), 2}, 44, 50, &near), 50);
  EXPECT_FALSE(near);
  // From outside the frame: no reading.
  EXPECT_TRUE(
      std::isnan(displaced_sample(signal, near_level, {cv::Point2d(2.5, 0), 2}, 1, 30, &near)));
}

TEST(BracketMotion, TheShiftBetweenTwoFramesOfOneExposure) {
  const float low = 16, high = 150;
  const cv::Mat now = cell_logs(spot(50, 30), 2, low, high);
  cv::Point2d shift;
  ASSERT_TRUE(find_shift(now, cell_logs(spot(44.8, 33.0), 2, low, high), 2, shift));
  EXPECT_NEAR(shift.x, 5.2, 0.3);
  EXPECT_NEAR(shift.y, -3.0, 0.3);
  // The spot brighter then (a pool's peak changes): the same shift.
  ASSERT_TRUE(find_shift(now, cell_logs(spot(44.8, 33.0, 0.8), 2, low, high), 2, shift));
  EXPECT_NEAR(shift.x, 5.2, 0.3);
  EXPECT_NEAR(shift.y, -3.0, 0.3);
  // Still, or too little in view: none.
  EXPECT_FALSE(find_shift(now, now, 2, shift));
  EXPECT_FALSE(find_shift(now, cell_logs(spot(50.6, 30), 2, low, high), 2, shift));
  const cv::Mat dark(kH, kW, CV_32F, cv::Scalar(2));
  EXPECT_FALSE(find_shift(cell_logs(dark, 2, low, high), cell_logs(dark, 2, low, high), 2, shift));
  // Farther than the search reaches: none.
  EXPECT_FALSE(find_shift(cell_logs(spot(72, 30), 2, low, high),
                          cell_logs(spot(24, 30), 2, low, high), 2, shift));
  // A 5x5 mosaic's cells (a larger spot, so that whole cells of 25 samples are well exposed).
  ASSERT_TRUE(find_shift(cell_logs(spot(50, 30, 1, 15), 5, low, high),
                         cell_logs(spot(41.5, 35.0, 1, 15), 5, low, high), 5, shift));
  EXPECT_NEAR(shift.x, 8.5, 0.75);
  EXPECT_NEAR(shift.y, -5.0, 0.75);
}

// Two exposures a factor 4 apart, the spot moving 1.5 pixels a frame: after a cycle the fusion
// knows the velocity, and the fused sample at the spot's front is the latest frame's (scaled),
// where without following it is the long exposure's of a frame before, when the front was
// behind.
TEST(BracketMotion, TheFusionFollowsASpotMovingAtAConstantVelocity) {
  const double lights[2] = {4, 1};
  for (bool follows : {true, false}) {
    MosaicBracketFusion fusion(2, 2);
    fusion.set_follows_motion(follows);
    cv::Mat out;
    for (int frame = 0; frame < 6; ++frame) {
      const double light = lights[frame % 2];
      fusion.add(spot(30 + 1.5 * frame, 32, light / 4), light, out);
    }
    // The spot where it is now, as the long exposure would see it.
    const cv::Mat now_long = spot(30 + 1.5 * 5, 32);
    if (!follows) {
      EXPECT_EQ(fusion.velocity(), cv::Point2d());
      // The front's long-exposure sample from a frame before: too dim for where the front is.
      EXPECT_LT(out.at<float>(32, 45), 0.8f * now_long.at<float>(32, 45));
      continue;
    }
    EXPECT_NEAR(fusion.velocity().x, 1.5, 0.15);
    EXPECT_NEAR(fusion.velocity().y, 0, 0.15);
    for (int x = 38; x <= 46; ++x)  // the spot's front
      EXPECT_NEAR(out.at<float>(32, x), now_long.at<float>(32, x), 0.03 * now_long.at<float>(32, x))
          << x;
  }
}

// The brightness change a frame between two frames of one exposure, where the content moved:
// a steep side (brightness exponential in position, which cells interpolate exactly in the
// logarithm) 20 % brighter over two frames reads log(1.2) / 2 a frame; where the frames differ
// by their noise only, the change is 0 on nearly every cell (the 3-sigma gate).
TEST(BracketMotion, TheBrightnessChangeBetweenTwoFramesOfOneExposure) {
  using bracket_motion::brightness_change;
  using bracket_motion::log_rates;
  const float low = 16, high = 1e6;
  auto side = [](double scale) {
    return mosaic([=](double x, double y) { return scale * 40 * std::exp(0.04 * x - 0.03 * y); });
  };
  const cv::Point2d shift(5.2, -3.0);
  const cv::Mat now = cell_logs(side(1.2), 2, low, high);
  // The content moved by `shift`: what is at x now was at x - shift.
  const cv::Mat before =
      cell_logs(mosaic([&](double x, double y) {
                  return 40 * std::exp(0.04 * (x + shift.x) - 0.03 * (y + shift.y));
                }),
                2, low, high);
  const cv::Mat rates = log_rates(now, before, shift, 2, 2);
  const cv::Mat change = brightness_change({rates}, {cv::Point2d()}, 2);
  ASSERT_EQ(change.size(), now.size());
  for (const cv::Point c : {cv::Point(10, 5), cv::Point(30, 10), cv::Point(40, 20)}) {
    EXPECT_NEAR(rates.at<cv::Vec2f>(c)[0], std::log(1.2) / 2, 1e-4) << c;
    EXPECT_NEAR(change.at<float>(c), std::log(1.2) / 2, 1e-4) << c;
  }
  // Too dim (under 16 DN: the lower left) or outside `before`: no rate; no change far from one.
  EXPECT_TRUE(std::isnan(rates.at<cv::Vec2f>(31, 0)[0]));
  EXPECT_TRUE(std::isnan(rates.at<cv::Vec2f>(30, 40)[0]));
  EXPECT_EQ(change.at<float>(31, 0), 0.0f);
  // A frame's rates from an older frame are read where its content is now: 6 pixels (3 cells)
  // further along x, and none in the 3 columns of cells it has not reached.
  const cv::Mat moved =
      brightness_change({cv::Mat(), rates}, {cv::Point2d(), cv::Point2d(6, 0)}, 2);
  EXPECT_NEAR(moved.at<float>(10, 30), std::log(1.2) / 2, 1e-4);
  EXPECT_EQ(moved.at<float>(10, 0), 0.0f);
  // A steady scene with each sample's noise as the rates assume (cv::RNG: the same draws on
  // every machine): of its 1536 cells a few may pass the gate by chance (each about 0.3 %).
  cv::RNG rng(7);
  auto noisy = [&](double level) {
    cv::Mat m(kH, kW, CV_32F);
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x)
        m.at<float>(y, x) = static_cast<float>(
            level + rng.gaussian(std::sqrt(bracket_motion::kRateShotDnPerDn * level +
                                           bracket_motion::kRateFloorDn2)));
    return m;
  };
  const cv::Mat steady = brightness_change(
      {log_rates(cell_logs(noisy(60), 2, low, high), cell_logs(noisy(60), 2, low, high), {}, 2, 2)},
      {cv::Point2d()}, 2);
  EXPECT_LE(cv::countNonZero(steady), 1536 / 20);
}

// A spot brightening 10 % a frame while it moves: the long exposure's samples, a frame older,
// are brought forward by the brightness change as well as by the shift.
TEST(BracketMotion, TheFusionFollowsASpotThatBrightens) {
  const double lights[2] = {4, 1};
  MosaicBracketFusion fusion(2, 2);
  cv::Mat out;
  for (int frame = 0; frame < 6; ++frame) {
    const double light = lights[frame % 2];
    fusion.add(spot(30 + 1.5 * frame, 32, light / 4 * std::pow(1.1, frame)), light, out);
  }
  const cv::Mat now_long = spot(30 + 1.5 * 5, 32, std::pow(1.1, 5));
  EXPECT_NEAR(fusion.velocity().x, 1.5, 0.15);
  for (int x = 38; x <= 44; ++x)  // the spot's front, which the long exposure sees well
    EXPECT_NEAR(out.at<float>(32, x), now_long.at<float>(32, x), 0.03 * now_long.at<float>(32, x))
        << x;
  // Brightening 2.5 times a frame (more than the factor 2 a sample may be brought forward):
  // the earlier frame's samples are not fused; the latest frame's own, scaled, where it has one.
  MosaicBracketFusion sudden(2, 2);
  cv::Mat latest;
  for (int frame = 0; frame < 6; ++frame) {
    const double light = lights[frame % 2];
    latest = spot(30 + 1.5 * frame, 32, light / 4 * std::pow(2.5, frame));
    sudden.add(latest, light, out);
  }
  for (int x = 30; x <= 50; ++x) {
    const float own = latest.at<float>(32, x);
    if (std::isnan(own)) continue;
    EXPECT_FLOAT_EQ(out.at<float>(32, x), 4 * own) << x;
  }
}

}  // namespace
}  // namespace pyrocam
