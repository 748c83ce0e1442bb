// Test scenes for the simulated camera: temperature maps (CV_32F, degC, NaN = cold background).
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pyrocam/simulation/simulator.h"

namespace pyrocam {

enum class SceneKind { kPlate, kFilament, kMeltPool };
SceneKind parse_scene_kind(const std::string& name);  // "plate", "filament", "melt-pool"
std::string scene_kind_name(SceneKind kind);

// A plate at t_c filling the central 60 % of the frame.
cv::Mat plate_scene(int width, int height, double t_c);
// A centred plate at t_c covering `area_fraction` (0..1] of the frame, with the frame's aspect
// ratio; 0.36 gives the same plate as the form above.
cv::Mat plate_scene(int width, int height, double t_c, double area_fraction);
// A vertical filament at t_c, about width/12 wide, cooler over its last two pixels per side.
cv::Mat filament_scene(int width, int height, double t_c);
// Frame `index` of a melt pool crossing the frame: a hot spot whose peak swings between
// 1500 and 2500 degC with a cooling tail behind it.
cv::Mat melt_pool_scene(int width, int height, int index, int count);
double melt_pool_peak_c(int index, int count);

// How the scenes are filmed unless told otherwise: by `pyrocam-calib simulate` (scene sequences)
// and by the pyrocamsrc element alike.
struct SceneDefaults {
  // Automatic exposure puts the brightest band this far above the dark level at the scene's
  // nominal temperature: with the shipped profiles' 50 DN dark offset the raw peak stays under
  // their 220 DN inference saturation threshold, noise included.
  double target_dn = 140;
  // A melt pool is filmed at one exposure, set for this temperature: its hottest frames
  // saturate, its coolest are dim.
  double melt_pool_exposure_c = 2000;
  double plate_emissivity = 0.7, filament_emissivity = 0.4, melt_pool_emissivity = 0.35;

  constexpr double emissivity(SceneKind kind) const {
    return kind == SceneKind::kPlate      ? plate_emissivity
           : kind == SceneKind::kFilament ? filament_emissivity
                                          : melt_pool_emissivity;
  }
};
inline constexpr SceneDefaults kSceneDefaults{};

// A target in DN above the dark level (such as SceneDefaults::target_dn) is for the shipped 8-bit
// profiles' usable range, 170 DN from their 50 DN dark offset to their 220 DN inference
// saturation threshold; another camera's target is the same share of its own range (a 12-bit
// camera's frames would otherwise sit below its dim threshold).
inline double scaled_target_dn(double target_dn, const CameraProfile& profile) {
  return target_dn * (profile.thresholds.inference_saturation_dn - profile.dark_offset_dn) / 170;
}

struct SceneSequenceSettings {
  SceneKind kind = SceneKind::kMeltPool;
  int frames = 20;                     // melt pool only; plate/filament: one per temperature
  std::vector<double> temperatures_c;  // plate/filament (default: a sweep suited to the kind)
  int width = 256, height = 256;
  double exposure_us = 0;  // 0: each frame exposed so its hottest band reaches target_dn
  double target_dn = kSceneDefaults.target_dn;  // brightest band above the dark (scaled_target_dn)
  double emissivity = 0;                        // 0: kSceneDefaults.emissivity(kind)
  std::string image_extension = ".pgm";
};

// Writes a dataset-format folder: frames/, darks/ (one per exposure), truth/ (16-bit PNG of the
// true temperature in 0.1 K, 0 = background), manifest.csv (temperature_c is the frame's nominal
// temperature: the plate's, the filament's, or the melt pool's peak) and roi.png (pixels at the
// nominal temperature in the first frame).
void write_scene_sequence(const std::filesystem::path& folder, Simulator& camera,
                          SceneSequenceSettings settings, const Progress& progress = {});

}  // namespace pyrocam
