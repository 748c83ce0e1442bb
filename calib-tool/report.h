// The calibration report: a self-contained HTML page with inline plots, and a JSON summary.
#pragma once

#include <filesystem>

#include "pyrocam/calibration/calibrate.h"

namespace pyrocam::cli {

void write_report_html(const CalibrationOutcome& outcome, const std::filesystem::path& path);
void write_report_json(const CalibrationOutcome& outcome, const std::filesystem::path& path);

}  // namespace pyrocam::cli
