// A simulated camera: renders raw mosaic frames of a temperature map through a "true" camera
// whose QE differs from the datasheet the way a real unit does, with EMVA 1288 noise.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pyrocam/core/dataset.h"
#include "pyrocam/core/profile.h"

namespace pyrocam {

// A named, seeded deviation of a real unit from its datasheet.
struct UnitPerturbation {
  // "datasheet" (none), "typical" (the profile's unit_variation) or "hostile": typical plus
  // what no solver here is built around: the filter's pass-band edges moved 3-10 nm, narrow
  // leaks within 50 nm outside an edge at 0.2-3 % transmission, a neutral-density glass sloping
  // +-30 % over 700-1000 nm, and per-band shape changes (curvature, skew, a bump) of ~5 %.
  // "foreign": typical plus deviations of other kinds, to check the QE fit on cameras it was
  // not built around (no setting is chosen by them): the filter moved as a whole by -12..+3 nm
  // and its edges softened by a 1-6 nm Gaussian, blocking that passes 0.05-0.5 % everywhere
  // outside the pass band, a lens whose transmission bends smoothly over the grid (~10 %), and
  // each band stretched about its peak (3 % rms) with a smooth random change of shape (~10 %).
  std::string name = "datasheet";
  std::uint64_t seed = 1;

  static UnitPerturbation parse(const std::string& name, std::uint64_t seed);
};

// System QE (bands x wavelengths) of the unit: the datasheet's, or perturbed by a filter leak,
// per-band scale and tilt, and per-band wavelength shift (and the hostile changes), all drawn
// from `seed`.
Eigen::MatrixXd true_system_qe(const CameraProfile& profile, const UnitPerturbation& unit);

class Simulator {
 public:
  Simulator(CameraProfile profile, Eigen::MatrixXd system_qe, std::uint64_t noise_seed = 7);
  Simulator(const CameraProfile& profile, const UnitPerturbation& unit,
            std::uint64_t noise_seed = 7)
      : Simulator(profile, true_system_qe(profile, unit), noise_seed) {}

  const CameraProfile& profile() const { return profile_; }
  const Eigen::MatrixXd& system_qe() const { return system_qe_; }
  void set_noise_enabled(bool on) { noise_ = on; }
  // Added to the profile's dark offset in every frame rendered from now on, DN (before
  // quantisation): a black level that moved since the dark frames were taken (the sensor warmed
  // up, say).
  void set_black_level_shift(double dn) { black_level_shift_dn_ = dn; }
  // A sensor that clamps its black level (to its optically black pixels, as many industrial
  // cameras do): the mean of the dark current leaves every frame, its shot noise stays, and the
  // dark level is the profile's offset at any exposure. Off by default (the dark current's
  // mean is in the frames, and dark frames of the same exposure take it out).
  void set_black_level_clamp(bool on) { black_level_clamp_ = on; }

  // Raw mosaic (CV_8U for bit depth 8, else CV_16U) of a temperature map (CV_32F, degC; NaN or
  // below 100 degC emits nothing). Deterministic for a given noise seed and call sequence.
  // gain_db: analogue gain, multiplying the collected electrons' signal (shot noise and dark
  // current included) by 10^(gain_db / 20) before the read noise, which stays as it is in DN (a
  // simplification: a real sensor's read noise referred to the output partly grows with gain).
  cv::Mat render(const cv::Mat& temperature_c, double exposure_us, double emissivity = 1.0,
                 double gain_db = 0.0);
  cv::Mat render_dark(int width, int height, double exposure_us);

  // Mean signal above the dark level per band, DN, noise-free and unclipped.
  Eigen::VectorXd mean_signal_dn(double temperature_c, double exposure_us,
                                 double emissivity = 1.0) const;
  // Exposure that puts the brightest band at target_dn above the dark level.
  double exposure_for(double temperature_c, double target_dn, double emissivity = 1.0) const;

 private:
  double electron_rate(int band, double temperature_c) const;
  void ensure_pixel_maps(int width, int height);

  CameraProfile profile_;
  Eigen::MatrixXd system_qe_;
  Eigen::MatrixXd rate_table_;  // bands x temperatures (1 K steps from kTableStartC), e-/s
  std::uint64_t seed_;
  std::uint64_t frame_counter_ = 0;
  bool noise_ = true;
  double black_level_shift_dn_ = 0;
  bool black_level_clamp_ = false;
  cv::Mat dark_fpn_, prnu_;  // per pixel, fixed for the unit
};

// A furnace campaign like the paper's (METHOD.md section 3).
struct CampaignSettings {
  std::vector<double> temperatures_c;  // empty: 700..1100 step 10 (colour), 800..1100 (5x5)
  double first_exposure_us = 0;        // 0: 100 us colour, 10000 us multispectral
  double exposure_factor = 1.26;
  int exposure_count = 30;
  int frames_per_setting = 10;
  double dark_temperature_c = 100;
  // The plate's true temperature at each step differs from the nominal (thermocouple) value the
  // manifest records: furnace non-uniformity, stabilisation and the thermocouple's tolerance.
  // Normal, this standard deviation in degC, drawn per step from furnace_seed; 0: exact. The
  // true values are written to furnace-truth.csv beside the manifest.
  double furnace_error_sigma_c = 1.0;
  std::uint64_t furnace_seed = 11;
  // Reference sources beyond the furnace (fixed-point cells such as Co-C 1324, Pt-C 1738, Re-C
  // 2474 degC), nominal degC; none by default. Each gets manifest rows of kind reference: its own
  // sweep of exposure_count exposures exposure_factor apart, the first putting the brightest band
  // at half the profile's calibration_dim_dn, frames_per_setting frames each, and dark frames of
  // every exposure the dataset has no dark of yet. Its absolute scale is unknown to the
  // calibration (aperture, distance): rendered with an emissivity drawn in [0.05, 0.5]. Its true
  // temperature is off the nominal by a normal draw of reference_uncertainty_c (the manifest's
  // temperature_uncertainty_c); scale and error come from reference_seed, and the true
  // temperatures follow the furnace steps in furnace-truth.csv. Without references the campaign
  // is the same, byte for byte, as before references existed.
  std::vector<double> reference_temperatures_c;
  double reference_uncertainty_c = kDefaultReferenceUncertaintyC;
  std::uint64_t reference_seed = 13;
  // The black level of the furnace frames moves since the darks were taken: linearly from 0 at
  // the first temperature step to this at the last, DN (a sensor that warms up over the
  // campaign). References keep the darks' black level. 0: none.
  double black_level_drift_dn = 0;
  int width = 128, height = 128;
  double roi_area_px = 6000;  // elliptical, centred
  std::string image_extension = ".pgm";
};

using Progress = std::function<void(std::size_t done, std::size_t total)>;

// Writes manifest.csv, frames, dark frames for every exposure, the reference sweeps and roi.png
// into `folder`. Throws InputError for settings it cannot render (no exposure or frame, a frame
// too small for the ROI, a reference uncertainty <= 0 or a reference without signal).
void write_furnace_campaign(const std::filesystem::path& folder, Simulator& camera,
                            CampaignSettings settings, const Progress& progress = {});

}  // namespace pyrocam
