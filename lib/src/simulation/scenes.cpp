#include "pyrocam/simulation/scenes.h"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "detail/portable_math.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/temperature_codes.h"

namespace pyrocam {
namespace {
constexpr float kCold = std::numeric_limits<float>::quiet_NaN();
}

SceneKind parse_scene_kind(const std::string& name) {
  if (name == "plate") return SceneKind::kPlate;
  if (name == "filament") return SceneKind::kFilament;
  if (name == "melt-pool") return SceneKind::kMeltPool;
  throw InputError("unknown scene '" + name + "' (use plate, filament or melt-pool)");
}

std::string scene_kind_name(SceneKind kind) {
  switch (kind) {
    case SceneKind::kPlate:
      return "plate";
    case SceneKind::kFilament:
      return "filament";
    case SceneKind::kMeltPool:
      return "melt-pool";
  }
  return "?";
}

cv::Mat plate_scene(int width, int height, double t_c) {
  cv::Mat m(height, width, CV_32F, cv::Scalar(kCold));
  m(cv::Rect(width / 5, height / 5, width - 2 * (width / 5), height - 2 * (height / 5)))
      .setTo(static_cast<float>(t_c));
  return m;
}

cv::Mat plate_scene(int width, int height, double t_c, double area_fraction) {
  if (!(area_fraction > 0 && area_fraction <= 1))
    throw InputError("plate scene: the area fraction must lie in (0, 1]");
  // Rounded down like the 60 % plate's width / 5 margins (the epsilon absorbs the rounding of
  // sqrt), so that 0.36 gives that plate exactly.
  const double margin = (1 - std::sqrt(area_fraction)) / 2;
  const int mx = static_cast<int>(std::floor(width * margin + 1e-9));
  const int my = static_cast<int>(std::floor(height * margin + 1e-9));
  cv::Mat m(height, width, CV_32F, cv::Scalar(kCold));
  if (width > 2 * mx && height > 2 * my)
    m(cv::Rect(mx, my, width - 2 * mx, height - 2 * my)).setTo(static_cast<float>(t_c));
  return m;
}

cv::Mat filament_scene(int width, int height, double t_c) {
  cv::Mat m(height, width, CV_32F, cv::Scalar(kCold));
  const int half = std::max(3, width / 24);
  const int cx = width / 2;
  for (int y = height / 10; y < height - height / 10; ++y)
    for (int x = cx - half; x < cx + half; ++x) {
      const int from_edge = std::min(x - (cx - half), cx + half - 1 - x);
      // The outermost pixels are cooler, as on a real coil.
      const double t = from_edge == 0 ? t_c - 150 : from_edge == 1 ? t_c - 50 : t_c;
      m.at<float>(y, x) = static_cast<float>(t);
    }
  return m;
}

double melt_pool_peak_c(int index, int count) {
  return 2000.0 + 500.0 * portable::sin(2 * M_PI * 1.5 * index / std::max(1, count));
}

cv::Mat melt_pool_scene(int width, int height, int index, int count) {
  cv::Mat m(height, width, CV_32F, cv::Scalar(kCold));
  const double peak = melt_pool_peak_c(index, count);
  const double progress = count > 1 ? static_cast<double>(index) / (count - 1) : 0.5;
  // The peak sits on a pixel centre so the truth map holds the nominal peak temperature.
  const double x0 = std::floor(width * (0.25 + 0.5 * progress)) + 0.5;
  const double y0 = std::floor(height * 0.5) + 0.5;
  const double r = std::max(3.0, width / 32.0);  // pool radius, px
  const double tail = 4 * r;                     // cooling length behind the pool
  const double ambient = 20.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double dx = x + 0.5 - x0, dy = y + 0.5 - y0;
      double f;
      if (dx >= 0) {
        f = portable::exp(-(dx * dx + dy * dy) / (2 * r * r));
      } else {
        const double widen = r * (1.0 + (-dx) / (3 * r));
        f = portable::exp(dx / tail) * portable::exp(-dy * dy / (2 * widen * widen));
      }
      const double t = ambient + (peak - ambient) * f;
      if (t > 400) m.at<float>(y, x) = static_cast<float>(t);
    }
  return m;
}

void write_scene_sequence(const std::filesystem::path& folder, Simulator& camera,
                          SceneSequenceSettings s, const Progress& progress) {
  if (s.width < 16 || s.height < 16) throw InputError("scene: needs at least 16x16 pixels");
  camera.profile().mosaic.check_whole_periods(s.width, s.height, "scene frame size");
  if (s.emissivity <= 0) s.emissivity = kSceneDefaults.emissivity(s.kind);
  if (s.temperatures_c.empty()) {
    if (s.kind == SceneKind::kPlate)
      for (double t = 705; t <= 1095; t += 30) s.temperatures_c.push_back(t);
    if (s.kind == SceneKind::kFilament)
      for (double t = 800; t <= 2600; t += 100) s.temperatures_c.push_back(t);
  }
  const int count =
      s.kind == SceneKind::kMeltPool ? s.frames : static_cast<int>(s.temperatures_c.size());
  if (count < 1) throw InputError("scene: no frames to write");

  std::vector<cv::Mat> maps;
  std::vector<double> nominal;
  for (int i = 0; i < count; ++i) {
    switch (s.kind) {
      case SceneKind::kPlate:
        maps.push_back(plate_scene(s.width, s.height, s.temperatures_c[i]));
        break;
      case SceneKind::kFilament:
        maps.push_back(filament_scene(s.width, s.height, s.temperatures_c[i]));
        break;
      case SceneKind::kMeltPool:
        maps.push_back(melt_pool_scene(s.width, s.height, i, count));
        break;
    }
    nominal.push_back(s.kind == SceneKind::kMeltPool ? melt_pool_peak_c(i, count)
                                                     : s.temperatures_c[i]);
  }
  const double target_dn = scaled_target_dn(s.target_dn, camera.profile());
  // A melt pool is filmed at one exposure; plates and filaments are each exposed for themselves.
  double fixed_exposure = s.exposure_us;
  if (s.kind == SceneKind::kMeltPool && fixed_exposure <= 0)
    fixed_exposure =
        camera.exposure_for(kSceneDefaults.melt_pool_exposure_c, target_dn, s.emissivity);

  // The manifest holds exposures to 0.001 us, and a camera's exposure ends somewhere (1e8 us,
  // as a campaign's): a faint scene's automatic exposure of 5e11 us made frames that were all
  // saturated, and --exposure 1e-9 was written as 0.
  std::vector<double> exposures;
  for (int i = 0; i < count; ++i) {
    const double wanted = fixed_exposure > 0
                              ? fixed_exposure
                              : camera.exposure_for(nominal[i], target_dn, s.emissivity);
    const double exposure = std::round(wanted * 1000) / 1000;
    if (!(exposure > 0 && exposure <= 1e8)) {
      std::ostringstream m;
      m << "scene: frame " << i << " (" << nominal[i] << " degC, emissivity " << s.emissivity
        << ") needs an exposure of " << wanted << " us, "
        << (exposure > 0 ? "past 1e8 us: a higher emissivity or temperature"
                         : "under the manifest's 0.001 us: a longer --exposure");
      throw InputError(m.str());
    }
    exposures.push_back(exposure);
  }
  for (const char* dir : {"frames", "darks", "truth"})
    std::filesystem::create_directories(folder / dir);

  std::vector<ManifestRow> rows;
  std::vector<double> dark_exposures;
  for (int i = 0; i < count; ++i) {
    const double exposure = exposures[static_cast<std::size_t>(i)];
    std::ostringstream stem;
    stem << std::setw(4) << std::setfill('0') << i;
    const std::string frame = "frames/" + stem.str() + s.image_extension;
    write_raw_image(folder / frame, camera.render(maps[i], exposure, s.emissivity));
    write_raw_image(folder / ("truth/" + stem.str() + ".png"), encode_decikelvin(maps[i]));
    rows.push_back({frame, FrameKind::kFrame, nominal[i], exposure});
    bool have_dark = false;
    for (double e : dark_exposures) have_dark |= same_exposure(e, exposure);
    if (!have_dark) {
      const std::string dark = "darks/" + stem.str() + s.image_extension;
      write_raw_image(folder / dark, camera.render_dark(s.width, s.height, exposure));
      rows.push_back({dark, FrameKind::kDark, 20.0, exposure});
      dark_exposures.push_back(exposure);
    }
    if (progress) progress(static_cast<std::size_t>(i + 1), static_cast<std::size_t>(count));
  }
  cv::Mat roi = (maps[0] == static_cast<float>(nominal[0]));
  if (s.kind == SceneKind::kMeltPool) roi = maps[0] >= static_cast<float>(nominal[0] - 100);
  write_raw_image(folder / "roi.png", roi);
  write_manifest(folder / "manifest.csv", rows);
  write_mosaic_pattern(folder, camera.profile().mosaic.pattern);
}

}  // namespace pyrocam
