#include <gtest/gtest.h>

#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/alarm.h"

namespace pyrocam {
namespace {

AlarmSettings rule(double threshold_c, double hysteresis_c, int frames) {
  AlarmSettings s;
  s.threshold_c = threshold_c;
  s.hysteresis_c = hysteresis_c;
  s.frames = frames;
  return s;
}

// The changes a sequence of frame values makes, as one letter per frame: '.' none, 'R' raised,
// 'C' cleared.
std::string run(AlarmMonitor& monitor, const std::vector<double>& values) {
  std::string out;
  for (double v : values) {
    switch (monitor.update(v)) {
      case AlarmChange::kRaised:
        out += 'R';
        break;
      case AlarmChange::kCleared:
        out += 'C';
        break;
      default:
        out += '.';
    }
  }
  return out;
}

TEST(AlarmMonitor, RaisesAfterTheGivenRunOfFramesAboveTheThreshold) {
  AlarmMonitor m(rule(2000, 10, 3));
  // Two frames above, one at the threshold (not above): the run starts again.
  EXPECT_EQ(run(m, {2001, 2005, 2000, 2001, 2002, 2003, 2004}), ".....R.");
  EXPECT_TRUE(m.active());
}

TEST(AlarmMonitor, ClearsOnlyBelowTheHysteresisBandForTheSameRun) {
  AlarmMonitor m(rule(2000, 10, 2));
  EXPECT_EQ(run(m, {2100, 2100}), ".R");
  // Inside the band (1990..2000) it stays raised however long; below 1990 twice clears it.
  EXPECT_EQ(run(m, {1995, 1991, 1990, 1995, 1989, 1995, 1989, 1980}), ".......C");
  EXPECT_FALSE(m.active());
}

TEST(AlarmMonitor, DoesNotOscillateOnNoiseAroundTheThreshold) {
  AlarmMonitor m(rule(2000, 10, 1));
  std::vector<double> noisy;
  for (int i = 0; i < 50; ++i) noisy.push_back(i % 2 ? 1996.0 : 2004.0);
  EXPECT_EQ(run(m, noisy), "R" + std::string(49, '.'));
}

TEST(AlarmMonitor, FramesWithoutAReadingNeitherCountNorBreakTheRun) {
  AlarmMonitor m(rule(2000, 10, 3));
  EXPECT_EQ(run(m, {2100, NAN, NAN, 2100, NAN, 2100}), ".....R");
  EXPECT_EQ(run(m, {NAN, NAN, NAN, NAN, NAN, NAN}), "......");
  EXPECT_TRUE(m.active());
}

TEST(AlarmMonitor, NewSettingsKeepTheStateAndTurningItOffClears) {
  AlarmMonitor m(rule(2000, 10, 1));
  EXPECT_EQ(run(m, {2100}), "R");
  m.configure(rule(2200, 10, 1));
  EXPECT_TRUE(m.active());
  EXPECT_EQ(run(m, {2195, 2185}), ".C");
  m.configure(rule(2000, 10, 1));
  EXPECT_EQ(run(m, {2100}), "R");
  m.configure(rule(NAN, 10, 1));
  EXPECT_EQ(run(m, {2100, 2100}), "C.");
}

TEST(AlarmMonitor, RefusesNonsenseSettings) {
  EXPECT_THROW(AlarmMonitor(rule(2000, 10, 0)), InputError);
  EXPECT_THROW(AlarmMonitor(rule(2000, -1, 1)), InputError);
  EXPECT_THROW(AlarmMonitor(rule(2000, NAN, 1)), InputError);
  AlarmMonitor m(rule(2000, 10, 2));
  EXPECT_THROW(m.configure(rule(2000, 10, -3)), InputError);
  EXPECT_EQ(m.settings().frames, 2);  // the old rule stays
}

}  // namespace
}  // namespace pyrocam
