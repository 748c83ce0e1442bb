#include "pyrocam/runtime/alarm.h"

#include <string>

#include "pyrocam/core/error.h"

namespace pyrocam {

AlarmMonitor::AlarmMonitor(const AlarmSettings& settings) { configure(settings); }

void AlarmMonitor::configure(const AlarmSettings& settings) {
  if (settings.frames < 1)
    throw InputError("alarm frames must be at least 1, not " + std::to_string(settings.frames));
  if (!(settings.hysteresis_c >= 0) || !std::isfinite(settings.hysteresis_c))
    throw InputError("alarm hysteresis must be a finite number >= 0 degC, not " +
                     std::to_string(settings.hysteresis_c));
  settings_ = settings;
  run_ = 0;
}

AlarmChange AlarmMonitor::update(double value_c) {
  if (std::isnan(settings_.threshold_c)) {
    run_ = 0;
    if (!active_) return AlarmChange::kNone;
    active_ = false;
    return AlarmChange::kCleared;
  }
  if (std::isnan(value_c)) return AlarmChange::kNone;
  const bool beyond =
      active_ ? value_c < settings_.clear_below_c() : value_c > settings_.threshold_c;
  run_ = beyond ? run_ + 1 : 0;
  if (run_ < settings_.frames) return AlarmChange::kNone;
  run_ = 0;
  active_ = !active_;
  return active_ ? AlarmChange::kRaised : AlarmChange::kCleared;
}

}  // namespace pyrocam
