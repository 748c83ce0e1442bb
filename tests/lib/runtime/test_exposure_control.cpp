#include <gtest/gtest.h>

#include <cmath>
#include <deque>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/exposure_control.h"

namespace pyrocam {
namespace {

TEST(HotLevel, IsTheNthBrightestValueSoAFewHotPixelsDoNotSetIt) {
  cv::Mat raw(20, 20, CV_8U, cv::Scalar(30));
  raw(cv::Rect(5, 5, 10, 10)) = 120;  // 100 pixels of the object
  raw.at<std::uint8_t>(0, 0) = 255;   // two hot pixels
  raw.at<std::uint8_t>(0, 1) = 250;
  EXPECT_EQ(hot_level(raw, 50, 220).level_dn, 120);
  EXPECT_FALSE(hot_level(raw, 50, 220).clipped);
  EXPECT_EQ(hot_level(raw, 1, 220).level_dn, 255);
  EXPECT_TRUE(hot_level(raw, 1, 220).clipped);
  EXPECT_EQ(hot_level(raw, 1000, 220).level_dn, 30);  // more than the frame: its minimum
  cv::Mat raw16(4, 4, CV_16U, cv::Scalar(4000));
  EXPECT_EQ(hot_level(raw16, 3, 4095).level_dn, 4000);
  EXPECT_THROW(hot_level(cv::Mat(4, 4, CV_32F), 1, 1), InputError);
  EXPECT_THROW(hot_level(raw, 0, 220), InputError);
}

ExposureControlSettings settings() {
  ExposureControlSettings s;
  s.dark_dn = 50;
  s.saturation_dn = 220;
  s.min_exposure_us = 10;
  s.max_exposure_us = 1e6;
  return s;
}

// Frames until the level is within 10 % of the target (and stays there for 30 frames), after
// starting at exposure `start_us`; -1 if it never settles or leaves again.
int frames_to_settle(double rate_per_us, double start_us, int latency, bool frames_carry_exposure,
                     int* changes_after = nullptr) {
  ExposureController control(settings());
  const double target_level = 50 + 0.7 * 170;
  double set_us = start_us;
  std::deque<double> in_flight(static_cast<std::size_t>(latency), start_us);
  int settled_at = -1, changes = 0;
  for (int frame = 0; frame < 80; ++frame) {
    in_flight.push_back(set_us);
    const double taken = in_flight.front();
    in_flight.pop_front();
    const double level = std::min(255.0, 50 + rate_per_us * taken);
    HotLevel h;
    h.level_dn = std::floor(level);
    h.clipped = h.level_dn >= 220;
    const bool near = std::abs(level - target_level) <= 0.1 * (target_level - 50);
    if (near && settled_at < 0) settled_at = frame;
    if (!near && settled_at >= 0) return -1;
    auto command = control.update(
        h, frames_carry_exposure ? std::optional<double>(taken) : std::nullopt, set_us);
    if (command) {
      set_us = command->exposure_us;
      if (settled_at >= 0) ++changes;
    }
  }
  if (changes_after) *changes_after = changes;
  return settled_at;
}

TEST(ExposureController, SettlesWithinTenFramesOfATenfoldStepEitherWay) {
  const double rate = 0.119;  // 1000 us gives the target level
  for (int latency : {0, 1, 3}) {
    for (bool carry : {true, false}) {
      SCOPED_TRACE("latency " + std::to_string(latency) + (carry ? ", frames carry" : ""));
      int changes = -1;
      // 10x too bright (saturated at the start) and 10x too dark.
      const int bright = frames_to_settle(rate, 10000, latency, carry, &changes);
      EXPECT_GE(bright, 0);
      EXPECT_LE(bright, 10);
      EXPECT_EQ(changes, 0);  // no change once settled: no oscillation
      const int dark = frames_to_settle(rate, 100, latency, carry, &changes);
      EXPECT_GE(dark, 0);
      EXPECT_LE(dark, 10);
      EXPECT_EQ(changes, 0);
    }
  }
}

TEST(ExposureController, ClampsToTheCameraRangeAndSaysSo) {
  ExposureController control(settings());
  HotLevel dim;
  dim.level_dn = 51;  // 1 DN of signal: wants 119x the exposure, max_step allows 8x
  auto c = control.update(dim, 500000.0, 500000.0);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->exposure_us, 1e6);
  EXPECT_TRUE(c->clamped);
  EXPECT_TRUE(control.at_limit());
  // Asked again with a frame at the limit: nothing new to set, still at the limit.
  EXPECT_FALSE(control.update(dim, 1e6, 1e6));
  EXPECT_TRUE(control.at_limit());
}

TEST(ExposureController, RefusesSettingsOutOfRange) {
  auto bad = settings();
  bad.target = 1;
  EXPECT_THROW(ExposureController{bad}, InputError);
  bad = settings();
  bad.min_exposure_us = 0;
  EXPECT_THROW(ExposureController{bad}, InputError);
  bad = settings();
  bad.saturation_dn = bad.dark_dn;
  EXPECT_THROW(ExposureController{bad}, InputError);
  bad = settings();
  bad.max_step = 1;
  EXPECT_THROW(ExposureController{bad}, InputError);
}

}  // namespace
}  // namespace pyrocam
