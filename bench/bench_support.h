// Shared by the benchmarks: simulated raw frames of a scene through a model's camera.
#pragma once

#include <cstdlib>
#include <ctime>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "pyrocam/runtime/model.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::bench {

// A scene by name: "plate:T[:P]", "filament:T" (T in degC) or "melt-pool"; P: the plate's share
// of the frame's area in % (default 36: the central 60 % of each side). A suffix "@F" exposes
// the frame F times longer than render's default (brightest pixels at 140 DN): "@1.3" saturates
// the brightest bands of most hot pixels, "@0.3" drops the dimmest 5x5 bands below the dim
// threshold.
struct Scene {
  std::string name = "plate:1500";
  cv::Mat temperature_c;  // NaN: cold background
  double emissivity = 0.7;
  double exposure_factor = 1;
};

inline Scene make_scene(const std::string& name, int width, int height) {
  Scene s;
  s.name = name;
  const auto at = name.find('@');
  const std::string spec = name.substr(0, at);
  if (at != std::string::npos) {
    s.exposure_factor = std::atof(name.c_str() + at + 1);
    if (!(s.exposure_factor > 0 && s.exposure_factor <= 100))
      throw std::invalid_argument("scene '" + name + "': the exposure factor lies in (0, 100]");
  }
  const auto colon = spec.find(':');
  const std::string kind = spec.substr(0, colon);
  const double t = colon == std::string::npos ? 1500 : std::atof(spec.c_str() + colon + 1);
  if (kind == "plate") {
    const auto share = colon == std::string::npos ? colon : spec.find(':', colon + 1);
    if (share == std::string::npos) {
      s.temperature_c = plate_scene(width, height, t);
    } else {
      const double percent = std::atof(spec.c_str() + share + 1);
      if (!(percent > 0 && percent <= 100))
        throw std::invalid_argument("scene '" + spec + "': the plate's share lies in (0, 100] %");
      s.temperature_c = plate_scene(width, height, t, percent / 100);
    }
    s.emissivity = 0.7;
  } else if (kind == "filament") {
    s.temperature_c = filament_scene(width, height, t);
    s.emissivity = 0.4;
  } else if (kind == "melt-pool") {
    s.temperature_c = melt_pool_scene(width, height, 3, 10);
    s.emissivity = 0.35;
  } else {
    throw std::invalid_argument("unknown scene '" + spec +
                                "' (plate:T[:P], filament:T or melt-pool)");
  }
  return s;
}

// A raw frame of the scene through the model's camera (a typical unit), exposed so that its
// hottest pixels read 140 DN above the dark level (under the 220 DN raw saturation level),
// times the scene's exposure factor.
inline cv::Mat render(const ThermalModel& m, const Scene& scene) {
  double peak = 0;
  cv::minMaxLoc(scene.temperature_c, nullptr, &peak, nullptr, nullptr,
                scene.temperature_c == scene.temperature_c);
  Simulator camera(m.profile(), UnitPerturbation::parse("typical", 1));
  return camera.render(scene.temperature_c,
                       scene.exposure_factor * camera.exposure_for(peak, 140, scene.emissivity),
                       scene.emissivity);
}

// Fraction of the frame on the hot object.
inline double hot_fraction(const Scene& scene) {
  return static_cast<double>(cv::countNonZero(scene.temperature_c == scene.temperature_c)) /
         static_cast<double>(scene.temperature_c.total());
}

// Process CPU time (all threads), s.
inline double process_cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

}  // namespace pyrocam::bench
