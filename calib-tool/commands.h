// Sub-commands of pyrocam-calib; each registers its options and returns what to run.
#pragma once

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <sstream>
#include <string>

namespace pyrocam::cli {

// Exit codes: 0 ok, 1 failed, 2 bad usage.
inline constexpr int kExitOk = 0, kExitFailed = 1, kExitUsage = 2;

struct GlobalOptions {
  bool quiet = false;
};

// Progress on stderr with counts and elapsed time; silent with --quiet.
class ProgressPrinter {
 public:
  ProgressPrinter(const GlobalOptions& g, std::string what)
      : quiet_(g.quiet), what_(std::move(what)) {}
  void operator()(std::size_t done, std::size_t total) {
    if (quiet_) return;
    const double s = elapsed_s();
    if (done != total && s - last_ < 0.25) return;
    last_ = s;
    std::fprintf(stderr, "\r%s: %zu/%zu (%.1f s)%s", what_.c_str(), done, total, s,
                 done == total ? "\n" : "");
  }
  double elapsed_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  bool quiet_;
  std::string what_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  double last_ = -1;
};

using Command = std::function<int()>;

// CLI::Range for a number that must be finite: CLI::Range lets "nan" through (every comparison
// with it fails) and takes "inf" as a number.
inline CLI::Validator finite_range(double min, double max) {
  std::ostringstream name;
  name << "FLOAT in [" << min << " - " << max << "]";
  return CLI::Validator(
      [min, max](std::string& value) {
        double v = 0;
        if (!CLI::detail::lexical_cast(value, v)) return value + " is not a number";
        if (!std::isfinite(v) || v < min || v > max) {
          std::ostringstream m;
          m << value << " is not a finite number from " << min << " to " << max;
          return m.str();
        }
        return std::string();
      },
      name.str());
}

void add_simulate_command(CLI::App& app, const GlobalOptions& global, Command& selected);
void add_calibrate_command(CLI::App& app, const GlobalOptions& global, Command& selected);
void add_measure_command(CLI::App& app, const GlobalOptions& global, Command& selected);
void add_export_command(CLI::App& app, const GlobalOptions& global, Command& selected);
void add_prebuild_command(CLI::App& app, const GlobalOptions& global, Command& selected);

}  // namespace pyrocam::cli
