#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <deque>
#include <vector>

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

// A camera with exposure and gain seen through `latency` frames, the scene's brightness
// stepping from rate_before to rate_after (DN per us at 0 dB) at frame `step_at`.
struct GainRun {
  int settled_at = -1;    // first frame within 10 % of the target after the step; -1: never
  int changes_after = 0;  // commands once settled (oscillation)
  bool left = false;      // left the target again after settling
  double exposure_us = 0, gain_db = 0;  // as set at the end
  bool gain_before_exposure = false;    // gain above 0 dB set with an exposure below the longest
  double max_gain_seen_db = 0;          // after the step
};

GainRun run_with_gain(double rate_before, double rate_after, int step_at, ExposureSetting start,
                      int latency, bool carry, double max_exposure_us, double max_gain_db) {
  ExposureControlSettings s = settings();
  s.max_exposure_us = max_exposure_us;
  s.max_gain_db = max_gain_db;
  ExposureController control(s);
  const double target_level = 50 + 0.7 * 170;
  ExposureSetting set = start;
  std::deque<ExposureSetting> in_flight(static_cast<std::size_t>(latency), start);
  GainRun run;
  for (int frame = 0; frame < step_at + 60; ++frame) {
    in_flight.push_back(set);
    const ExposureSetting taken = in_flight.front();
    in_flight.pop_front();
    const double rate = frame < step_at ? rate_before : rate_after;
    const double level =
        std::min(255.0, 50 + rate * taken.exposure_us * std::pow(10.0, taken.gain_db / 20));
    HotLevel h;
    h.level_dn = std::floor(level);
    h.clipped = h.level_dn >= 220;
    if (frame >= step_at) {
      const bool near = std::abs(level - target_level) <= 0.1 * (target_level - 50);
      if (near && run.settled_at < 0) run.settled_at = frame - step_at;
      if (!near && run.settled_at >= 0) run.left = true;
    }
    auto command =
        control.update(h, carry ? std::optional<ExposureSetting>(taken) : std::nullopt, set);
    if (command) {
      set = ExposureSetting{command->exposure_us, command->gain_db};
      if (set.gain_db > 0 && set.exposure_us < max_exposure_us * (1 - 1e-9))
        run.gain_before_exposure = true;
      if (frame >= step_at && run.settled_at >= 0) ++run.changes_after;
    }
    if (frame >= step_at) run.max_gain_seen_db = std::max(run.max_gain_seen_db, set.gain_db);
  }
  run.exposure_us = set.exposure_us;
  run.gain_db = set.gain_db;
  return run;
}

TEST(ExposureController, WithGainSettlesWithinTenFramesOfATenfoldStepEitherWay) {
  // At most 200 us: the dim scene (1000 us at 0 dB for the target) needs 5x = 14 dB of gain.
  const double rate = 0.119;
  for (int latency : {0, 1, 3}) {
    for (bool carry : {true, false}) {
      SCOPED_TRACE("latency " + std::to_string(latency) + (carry ? ", frames carry" : ""));
      // From 10x too dark at the longest exposure: the gain goes up.
      const GainRun up = run_with_gain(rate, rate, 0, {100, 0}, latency, carry, 200, 24);
      EXPECT_GE(up.settled_at, 0);
      EXPECT_LE(up.settled_at, 10);
      EXPECT_FALSE(up.left);
      EXPECT_EQ(up.changes_after, 0);
      EXPECT_FALSE(up.gain_before_exposure);
      EXPECT_DOUBLE_EQ(up.exposure_us, 200);
      EXPECT_NEAR(up.gain_db, 20 * std::log10(5.0), 1.0);
      // Settled on the gain, then a 10x brighter scene (saturated): the gain goes back to 0 dB
      // and the exposure shortens (no gain is ever set below the longest exposure).
      const GainRun down =
          run_with_gain(rate, 10 * rate, 30, {200, 20 * std::log10(5.0)}, latency, carry, 200, 24);
      std::printf(
          "[ figures  ] latency %d%s: up %d frames (%.0f us, %.2f dB), down %d frames "
          "(%.1f us, %.2f dB)\n",
          latency, carry ? ", frames carry" : "", up.settled_at, up.exposure_us, up.gain_db,
          down.settled_at, down.exposure_us, down.gain_db);
      EXPECT_GE(down.settled_at, 0);
      EXPECT_LE(down.settled_at, 10);
      EXPECT_FALSE(down.left);
      EXPECT_EQ(down.changes_after, 0);
      EXPECT_FALSE(down.gain_before_exposure);
      EXPECT_EQ(down.gain_db, 0);
      EXPECT_NEAR(down.exposure_us, 100, 10);
    }
  }
}

TEST(ExposureController, GainStaysAtZeroWhenTheExposureSuffices) {
  const double rate = 0.119;  // 1000 us gives the target level, within 1e6 us
  for (int latency : {0, 1, 3}) {
    for (bool carry : {true, false}) {
      SCOPED_TRACE("latency " + std::to_string(latency) + (carry ? ", frames carry" : ""));
      const GainRun dark = run_with_gain(rate, rate, 0, {100, 0}, latency, carry, 1e6, 24);
      EXPECT_GE(dark.settled_at, 0);
      EXPECT_LE(dark.settled_at, 10);
      EXPECT_EQ(dark.changes_after, 0);
      EXPECT_EQ(dark.max_gain_seen_db, 0);
      const GainRun bright = run_with_gain(rate, rate, 0, {10000, 0}, latency, carry, 1e6, 24);
      EXPECT_GE(bright.settled_at, 0);
      EXPECT_LE(bright.settled_at, 10);
      EXPECT_EQ(bright.changes_after, 0);
      EXPECT_EQ(bright.max_gain_seen_db, 0);
    }
  }
}

TEST(ExposureController, WithoutMaxGainLeavesTheFramesGainAlone) {
  // max_gain_db 0: a frame at 6 dB gets an exposure for its gain, and the gain it came with.
  ExposureController control(settings());
  HotLevel dim;
  dim.level_dn = 50 + 0.7 * 170 / 2;  // half the target
  auto c = control.update(dim, ExposureSetting{100, 6}, ExposureSetting{100, 6});
  ASSERT_TRUE(c);
  EXPECT_NEAR(c->exposure_us, 200, 1e-9);
  EXPECT_EQ(c->gain_db, 6);
}

TEST(ExposureController, ClampsTheGainToItsMaximumAndSaysSo) {
  auto s = settings();
  s.max_exposure_us = 100;
  s.max_gain_db = 6;
  ExposureController control(s);
  HotLevel dim;
  dim.level_dn = 50 + 0.7 * 170 / 4;  // a quarter of the target: wants 12 dB at 100 us
  auto c = control.update(dim, ExposureSetting{100, 0}, ExposureSetting{100, 0});
  ASSERT_TRUE(c);
  EXPECT_EQ(c->exposure_us, 100);
  EXPECT_DOUBLE_EQ(c->gain_db, 6);
  EXPECT_TRUE(c->clamped);
  EXPECT_TRUE(control.at_limit());
  EXPECT_FALSE(control.update(dim, ExposureSetting{100, 6}, ExposureSetting{100, 6}));
  EXPECT_TRUE(control.at_limit());
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

// A level clipped at one setting and no signal at the setting max_step below it (dark_dn set
// above the frames' own black level of 50 DN: 104 DN at 1000 us, saturated at 8000 us): the
// controller went 1000 -> 8000 -> 1000 us for ever. It now looks in between and settles.
TEST(ExposureController, ClippedAtOneSettingAndDarkAtTheNextLooksInBetween) {
  ExposureControlSettings s = settings();
  s.dark_dn = 120;
  s.saturation_dn = 220;
  ExposureController control(s);
  const double rate = 0.054;  // DN per us above the real black level of 50
  double set_us = 1000;
  std::vector<double> settings_seen;
  for (int frame = 0; frame < 30; ++frame) {
    HotLevel h;
    h.level_dn = std::floor(std::min(255.0, 50 + rate * set_us));
    h.clipped = h.level_dn >= 220;
    if (auto c = control.update(h, set_us, set_us)) set_us = c->exposure_us;
    settings_seen.push_back(set_us);
  }
  // Settled: the last ten frames at one setting, whose level is within 10 % of the target.
  for (std::size_t i = 20; i < settings_seen.size(); ++i)
    EXPECT_EQ(settings_seen[i], settings_seen.back()) << "frame " << i;
  const double level = 50 + rate * set_us, target = 120 + 0.7 * (220 - 120);
  EXPECT_NEAR(level, target, 0.1 * (target - 120));
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
  bad = settings();
  bad.max_gain_db = -1;
  EXPECT_THROW(ExposureController{bad}, InputError);
}

// Frames without their own meta: the camera's setting once it has held for latency frames. A
// change at frame 5 (read as frame 5 passes) reaches frame 5 + latency first.
TEST(SettingInEffect, KnowsAFramesSettingOnlyOnceAChangeHasHadTimeToReachIt) {
  for (int latency : {0, 1, 3}) {
    SettingInEffect in_effect(latency);
    for (int frame = 0; frame < 12; ++frame) {
      const ExposureSetting current{frame < 5 ? 1000.0 : 250.0, frame < 5 ? 0.0 : 6.0};
      const std::optional<ExposureSetting> taken = in_effect.frame_setting(current);
      // Before the change: known from the first frame (the camera was set before it streamed).
      const bool known = frame < 5 || frame >= 5 + latency;
      ASSERT_EQ(taken.has_value(), known) << "latency " << latency << ", frame " << frame;
      if (!known) continue;
      EXPECT_EQ(taken->exposure_us, current.exposure_us);
      EXPECT_EQ(taken->gain_db, current.gain_db);
    }
  }
  // A gain change alone restarts the wait; an invalid setting is never a frame's.
  SettingInEffect in_effect(2);
  EXPECT_TRUE(in_effect.frame_setting({1000, 0}));
  EXPECT_FALSE(in_effect.frame_setting({1000, 3}));
  EXPECT_FALSE(in_effect.frame_setting({1000, 3}));
  EXPECT_TRUE(in_effect.frame_setting({1000, 3}));
  SettingInEffect no_exposure(0);
  EXPECT_FALSE(no_exposure.frame_setting({0, 0}));
  EXPECT_FALSE(no_exposure.frame_setting({NAN, 0}));
  EXPECT_THROW(SettingInEffect{-1}, InputError);
}

// Bracketing by the camera's setting: each factor is held for latency + 1 frames and the last
// frame of each step is the one kept; that frame's setting, as SettingInEffect sees it, is the
// step's (a camera whose property holds what was set after each frame passes).
TEST(CameraBracket, KeepsTheLastFrameOfEachStepTakenWithItsFactor) {
  const std::vector<double> factors{1, 8, 0.25};
  for (int latency : {0, 1, 3}) {
    CameraBracket bracket(factors, latency);
    SettingInEffect in_effect(latency);
    const double base = 400;
    double camera_us = 1000;  // as the camera streamed before the bracket began
    std::vector<double> kept_us;
    std::vector<int> kept_frames;
    int first_steps = 0;
    for (int frame = 0; frame < 40; ++frame) {
      const std::optional<ExposureSetting> taken = in_effect.frame_setting({camera_us, 0});
      const CameraBracket::Step step = bracket.next_frame();
      if (step.keep) {
        ASSERT_TRUE(taken.has_value()) << "latency " << latency << ", frame " << frame;
        EXPECT_EQ(taken->exposure_us, base * step.factor) << "latency " << latency;
        kept_us.push_back(taken->exposure_us);
        kept_frames.push_back(frame);
        first_steps += step.first;
        EXPECT_EQ(step.first, step.factor == factors[0]);
      }
      EXPECT_TRUE(step.set || frame == 0 || !step.keep);
      if (step.set) camera_us = base * step.next_factor;
    }
    // Frame 0 starts the first step; then one kept frame every latency + 1 frames, cycling.
    const int period = latency + 1;
    ASSERT_EQ(kept_frames.size(), static_cast<std::size_t>(39 / period)) << "latency " << latency;
    for (std::size_t i = 0; i < kept_frames.size(); ++i) {
      EXPECT_EQ(kept_frames[i], static_cast<int>(i + 1) * period);
      EXPECT_EQ(kept_us[i], base * factors[i % factors.size()]);
    }
    EXPECT_EQ(first_steps, static_cast<int>((kept_frames.size() + 2) / 3));
  }
  EXPECT_THROW(CameraBracket({1}, 1), InputError);      // nothing to bracket
  EXPECT_THROW(CameraBracket({1, 0}, 1), InputError);   // a factor out of range
  EXPECT_THROW(CameraBracket({1, 2}, -1), InputError);  // a negative latency
  EXPECT_THROW(CameraBracket(std::vector<double>(17, 1.0), 0), InputError);  // too many
}

}  // namespace
}  // namespace pyrocam
