// Small helpers the calibration stages share: wall-clock seconds and optional progress reports.
#pragma once

#include <chrono>
#include <string>

#include "pyrocam/calibration/calibration_outcome.h"

namespace pyrocam::calibration_detail {

using Clock = std::chrono::steady_clock;
inline double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Reports a stage's progress when the caller asked for reports.
inline void report_stage(const StageProgress& progress, const std::string& name, std::size_t done,
                         std::size_t total) {
  if (progress) progress(name, done, total);
}

}  // namespace pyrocam::calibration_detail
