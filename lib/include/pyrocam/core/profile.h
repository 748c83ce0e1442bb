// Camera profiles: everything the method needs to know about a camera, read from a versioned
// JSON file (format documented in docs/profile-format.md).
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pyrocam/core/mosaic.h"
#include "pyrocam/core/physics.h"
#include "pyrocam/core/spectrum.h"

namespace pyrocam {

inline constexpr int kProfileFormatVersion = 1;
// Bounds of what a profile may describe (docs/profile-format.md), checked before anything is
// allocated from them: every band is a row of every bands x wavelengths matrix. 64 bands is
// also what the estimators' per-pixel arrays hold.
inline constexpr int kMaxProfileBands = 64;
inline constexpr std::size_t kMaxMosaicPeriod = 16;           // band_map rows and columns
inline constexpr long kMaxProfileWavelengthSamples = 100001;  // e.g. 0.01 nm over 1000 nm

// EMVA 1288 linear camera model: DN = K (mu_e + mu_d) + offset.
struct NoiseModel {
  double system_gain_dn_per_e = 0.03;  // K at band gain 1
  double read_noise_e = 6.0;           // temporal dark noise, electrons rms
  double full_well_e = 8500.0;         // saturation capacity, electrons
  double dark_current_e_per_s = 50.0;  // thermal electrons per second
  double dark_fpn_dn = 0.5;            // dark signal non-uniformity, DN rms (fixed per pixel)
  double prnu = 0.005;                 // photo-response non-uniformity, relative rms
};

// Gray-value windows (DN after dark subtraction) for calibration fits and for inference.
struct Thresholds {
  double calibration_dim_dn = 10, calibration_saturation_dn = 240;  // paper section 2.6
  double inference_dim_dn = 20, inference_saturation_dn = 220;      // paper section 2.8
};

// Ratios that cancel exposure, geometry and emissivity: x_i = s_num_i / mean(s_reference).
struct Normalisation {
  std::vector<int> numerators;
  std::vector<int> reference;
};

// How a real unit differs from its datasheet, for the simulator's "true" camera.
struct UnitVariation {
  std::array<double, 2> leak_range_nm{700, 900};  // where the band-pass filter leaks
  double leak_system_qe = 0.01;                   // absolute system QE added there (peak)
  double scale_sigma = 0.03;                      // per-band relative scale, rms
  double tilt_sigma = 0.02;                       // per-band relative tilt per 100 nm, rms
  double shift_sigma_nm = 0.0;                    // per-band wavelength shift, rms
  // Deviations outside the QE solver's model family, so that simulated calibrations are not
  // judged on data the fit can explain exactly: the optical filter's edges moved (coating
  // thickness), and a smooth spectral ripple (thin-film interference in cover glass,
  // micro-lenses and dyes), common to all bands and per band.
  double filter_shift_sigma_nm = 0.0;  // wavelength shift of the optics curve, rms
  double ripple_rms = 0.0;             // relative rms of each ripple (common and per band)
  std::array<double, 2> ripple_period_nm{40, 160};  // periods drawn uniformly in this range
};

struct CameraProfile {
  std::filesystem::path source;  // the file it was read from
  std::string name;
  std::string description;
  MosaicLayout mosaic;
  WavelengthGrid grid;
  std::vector<std::string> band_names;
  Eigen::MatrixXd sensor_qe;            // bands x wavelengths, electrons per photon
  Eigen::VectorXd optics_transmission;  // lens x all filters, per wavelength
  Eigen::VectorXd band_gain;            // digital gain per band (white balance)
  std::array<double, 2> filter_pass_band_nm{0, 0};
  int bit_depth = 8;
  double dark_offset_dn = 50;
  double etendue_m2_sr = 3e-12;  // pixel area x solid angle seen through the lens
  NoiseModel noise;
  Thresholds thresholds;
  Normalisation normalisation;
  UnitVariation unit_variation;

  int band_count() const { return static_cast<int>(band_names.size()); }
  int max_dn() const { return (1 << bit_depth) - 1; }
  int band_index(const std::string& name) const;  // -1 if unknown
  // Sensor QE times optics: the Q_b(lambda) of the signal model.
  Eigen::MatrixXd system_qe() const;
  // Digital gain K_b in DN per electron of each band.
  Eigen::VectorXd dn_per_electron() const { return band_gain * noise.system_gain_dn_per_e; }
};

// Reads and validates a profile; relative paths inside resolve against its folder. Throws
// InputError naming the file and the problem.
CameraProfile load_profile(const std::filesystem::path& path);

// The same from parsed JSON; `origin` names it in messages and anchors relative paths.
CameraProfile profile_from_json(const nlohmann::json& j, const std::filesystem::path& origin);
// A self-contained profile: every curve written inline on the grid (used inside model files).
nlohmann::json profile_to_json(const CameraProfile& profile);

// Folder of the shipped profiles: $PYROCAM_PROFILE_DIR, else the installed or source copy.
std::filesystem::path builtin_profile_dir();
// A shipped profile by name ("rgb-reference", "nir5x5-reference") or a path to a JSON file.
CameraProfile load_profile_by_name(const std::string& name_or_path);

// Electrons per second per band from a graybody at temperature_k, for the given system QE.
Eigen::VectorXd electron_rates(const CameraProfile& profile, const Eigen::MatrixXd& system_qe,
                               double temperature_k, double emissivity = 1.0);
// The same in DN per second after dark subtraction (gain applied): s_b(T) of eq. 4.
Eigen::VectorXd signal_rates(const CameraProfile& profile, const Eigen::MatrixXd& system_qe,
                             double temperature_k, double emissivity = 1.0);

// Normalised ratios of band signals (any common scale cancels).
Eigen::VectorXd normalised_ratios(const Normalisation& norm, const Eigen::VectorXd& signals);

}  // namespace pyrocam
