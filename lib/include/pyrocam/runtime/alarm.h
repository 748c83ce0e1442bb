// A temperature alarm with persistence and hysteresis: raised when a region's statistic stays
// above a threshold for a number of frames, cleared when it stays below the threshold less the
// hysteresis as long. Frame-by-frame logic only; the thermalalarm element feeds it.
#pragma once

#include <cmath>

namespace pyrocam {

struct AlarmSettings {
  double threshold_c = NAN;  // degC; NaN: the alarm is off (never raised)
  double hysteresis_c = 10;  // degC, >= 0: cleared below threshold_c - hysteresis_c
  int frames = 5;            // >= 1: consecutive frames above (below) that raise (clear)
  double clear_below_c() const { return threshold_c - hysteresis_c; }
};

enum class AlarmChange { kNone, kRaised, kCleared };

class AlarmMonitor {
 public:
  AlarmMonitor() = default;
  // Throws InputError for frames < 1 or a negative or non-finite hysteresis.
  explicit AlarmMonitor(const AlarmSettings& settings);
  // New settings keep the alarm's state (a raised alarm stays raised until the new rule clears
  // it) and restart the run of frames. Same checks as the constructor.
  void configure(const AlarmSettings& settings);
  // One frame's statistic (degC). A frame without a reading (NaN) neither counts nor breaks a
  // run: a core that saturates now and then must not keep an alarm from being raised, nor
  // clear one. A part too bright to read (saturated) is +INFINITY: above any threshold. With
  // the alarm off (NaN threshold) a raised alarm is cleared at once.
  AlarmChange update(double value_c);
  bool active() const { return active_; }
  const AlarmSettings& settings() const { return settings_; }

 private:
  AlarmSettings settings_;
  bool active_ = false;
  int run_ = 0;  // consecutive frames beyond the level that would change the state
};

}  // namespace pyrocam
