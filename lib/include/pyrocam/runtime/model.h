// The thermal model file that pyrocam-calib writes and the elements load: versioned,
// self-describing, checksummed JSON (format in docs/model-format.md).
#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pyrocam/core/locus.h"
#include "pyrocam/runtime/mlp.h"

namespace pyrocam {

inline constexpr int kModelFormatVersion = 1;
inline constexpr const char* kModelFormat = "pyrocam-thermal-model";

// What load_model accepts (docs/model-format.md): a file outside these ranges is corrupt or was
// not written by pyrocam-calib, and would give readings that look right and are not.
inline constexpr double kModelMinTemperatureC = 0, kModelMaxTemperatureC = 5000;
inline constexpr double kModelMaxUncertaintyC = 1000;  // any table value or tolerance
inline constexpr double kModelMinCoverageFactor = 1, kModelMaxCoverageFactor = 10;
inline constexpr double kModelMaxBandScale = 1e6;
// A model file is a few MB (the QE on the wavelength grid dominates); parsing holds about as much
// again in memory, so a larger file is refused before it is read.
inline constexpr std::uintmax_t kModelMaxFileBytes = 64u << 20;

// What inference needs for a per-pixel GUM uncertainty (METHOD.md section 7). Signal noise is
// propagated per pixel from the profile's noise model; these are the temperature-dependent
// terms that do not depend on the pixel's noise.
struct UncertaintyModel {
  std::vector<double> temperature_c;    // table grid
  std::vector<double> u_calibration_c;  // standard uncertainty from the thermocouple (MC refits)
  std::vector<double> u_emissivity_c;   // |dT/d alpha| u(alpha)
  // What the furnace (and reference rows) leave open in the QE: the spread of the readings of
  // plausible QE solutions (posterior samples of the fit). Grows where the model extrapolates.
  // Empty in models made before it existed, or with the datasheet QE or the paper's solver.
  std::vector<double> u_qe_model_c;
  double thermocouple_tolerance_c = 4.4;  // IEC 60584-2 class 1, rectangular
  double emissivity_slope_u = 0.01;       // u(alpha): relative emissivity change per 100 nm
  int monte_carlo_refits = 0;
  double coverage_factor = 2;

  // Interpolated combined systematic standard uncertainty at T (calibration, QE model and
  // emissivity).
  double systematic_u_c(double temperature_c) const;
};

struct ThermalModel {
  CameraModel camera;  // profile (curves inline), optimised system QE, band scale k_b
  Eigen::MatrixXd datasheet_qe;
  std::string qe_solver;  // "paper" or "regularised"
  double min_temperature_c = 500, max_temperature_c = 3500;
  // The hottest temperature the calibration saw (furnace or reference source); above it a colour
  // model reads from one band ratio (extrapolation_pair.h). NaN: not known (models made before
  // it existed, or built in code), every band reads at every temperature.
  double calibrated_up_to_c = NAN;
  // Not in the file: where that ratio hands back to every band, at the top of the range
  // (extrapolation_pair.h); NaN: max_temperature_c. A reader that widens the range to see
  // readings beyond it (the network's training copies) keeps the model's top here.
  double pair_top_c = NAN;
  Mlp mlp;  // normalised ratios -> degC
  UncertaintyModel uncertainty;
  nlohmann::json provenance;  // tool version, date, dataset hash, profile source
  nlohmann::json summary;     // calibration figures, for people
  // The file's checksum_fnv1a64 (16 hex digits), set by load_model: names the model's content
  // in recordings, whatever the file is called.
  std::string fingerprint;

  const CameraProfile& profile() const { return camera.profile; }
};

// Writes atomically (temporary file, then rename): a failed write never leaves a partial model.
void save_model(const ThermalModel& model, const std::filesystem::path& path);
// Throws InputError naming the file: missing, truncated, edited (checksum), another format
// version, or inconsistent content.
ThermalModel load_model(const std::filesystem::path& path);

// FNV-1a 64-bit of a text, as 16 hex digits (for checksums and provenance, not for security).
std::string fnv1a_hex(const std::string& text);

}  // namespace pyrocam
