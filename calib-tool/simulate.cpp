// `pyrocam-calib simulate`: furnace campaigns and test scenes from the simulated camera.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "commands.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::cli {
namespace {

struct CameraOptions {
  std::string profile = "rgb-reference";
  std::string unit = "typical";
  std::uint64_t unit_seed = 1;
  std::uint64_t noise_seed = 7;
};

// An unsigned option would take -3 as 2^64 - 3.
CLI::Validator seed_check() {
  return CLI::Validator(
      [](std::string& value) {
        // Digits that fit 64 bits (more were taken as 2^64 - 1, two seeds as one unit).
        const bool digits =
            !value.empty() && value.find_first_not_of("0123456789") == std::string::npos;
        const std::string largest = "18446744073709551615";
        const std::string v = value.substr(std::min(value.find_first_not_of('0'), value.size()));
        const bool fits = v.size() < largest.size() || (v.size() == largest.size() && v <= largest);
        return digits && fits ? std::string()
                              : "a seed is a whole number from 0 to " + largest + ", not " + value;
      },
      "SEED");
}

void add_camera_options(CLI::App* cmd, CameraOptions& o) {
  cmd->add_option(
         "--profile", o.profile,
         "Camera profile: a shipped name (rgb-reference, nir5x5-reference) or a .json path")
      ->capture_default_str();
  cmd->add_option(
         "--unit", o.unit,
         "How the simulated unit differs from its datasheet: datasheet, typical, hostile or "
         "foreign")
      ->check(CLI::IsMember({"datasheet", "typical", "hostile", "foreign"}))
      ->capture_default_str();
  cmd->add_option("--unit-seed", o.unit_seed, "Seed of the unit's deviation")
      ->check(seed_check())
      ->capture_default_str();
  cmd->add_option("--noise-seed", o.noise_seed, "Seed of the sensor noise")
      ->check(seed_check())
      ->capture_default_str();
}

Simulator make_camera(const CameraOptions& o) {
  const CameraProfile profile = load_profile_by_name(o.profile);
  return Simulator(profile, UnitPerturbation::parse(o.unit, o.unit_seed), o.noise_seed);
}

// The default frame size: `side` rounded to whole mosaic periods (128 -> 130 for 5x5).
void default_size(const Simulator& camera, int side, int& w, int& h) {
  const MosaicLayout& m = camera.profile().mosaic;
  w = std::max(1, static_cast<int>(std::lround(static_cast<double>(side) / m.period_width))) *
      m.period_width;
  h = std::max(1, static_cast<int>(std::lround(static_cast<double>(side) / m.period_height))) *
      m.period_height;
}

// --format: the image file type the simulator writes.
void add_format_option(CLI::App* cmd, std::string& extension) {
  cmd->add_option("--format", extension, "Image file type")
      ->check(CLI::IsMember({".pgm", ".png", ".tif"}))
      ->capture_default_str();
}

void parse_size(const std::string& text, int& w, int& h) {
  int used = 0;
  if (std::sscanf(text.c_str(), "%dx%d%n", &w, &h, &used) != 2 ||
      used != static_cast<int>(text.size()) || w < 1 || h < 1)
    throw CLI::ValidationError("--size", "expected WIDTHxHEIGHT, e.g. 128x128");
}

}  // namespace

void add_simulate_command(CLI::App& app, const GlobalOptions& global, Command& selected) {
  CLI::App* sim = app.add_subcommand("simulate", "Make data with the simulated camera");
  sim->require_subcommand(1);

  static CameraOptions campaign_camera;
  static CampaignSettings campaign;
  static std::string campaign_out, campaign_size;
  CLI::App* c = sim->add_subcommand(
      "campaign",
      "Write a furnace calibration dataset like the paper's (Sala et al. 2025, section 3)");
  c->footer(
      "Example:\n  pyrocam-calib simulate campaign --profile rgb-reference --unit typical "
      "--frames 10 --out furnace-rgb\n  pyrocam-calib simulate campaign --profile "
      "nir5x5-reference --reference 1324,1738,2474 --out furnace-nir");
  add_camera_options(c, campaign_camera);
  c->add_option("--out", campaign_out, "Output folder (created)")->required();
  c->add_option("--temperatures", campaign.temperatures_c,
                "Plate temperatures, degC (100 to 4000, space or comma separated; default "
                "700..1100 step 10 colour, 800..1100 for 5x5)")
      ->delimiter(',')
      ->check(finite_range(100.0, 4000.0));
  c->add_option("--first-exposure", campaign.first_exposure_us,
                "Shortest exposure, us (up to 1e8; 0: 100 colour, 10000 for 5x5)")
      ->check(finite_range(0.0, 1e8));
  c->add_option("--exposure-factor", campaign.exposure_factor,
                "Exposure ratio between steps (1.01 to 10)")
      ->check(finite_range(1.01, 10.0))
      ->capture_default_str();
  c->add_option("--exposures", campaign.exposure_count, "Number of exposures")
      ->check(CLI::Range(1, 200))
      ->capture_default_str();
  c->add_option("--frames", campaign.frames_per_setting, "Frames per setting")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  c->add_option("--furnace-error", campaign.furnace_error_sigma_c,
                "Standard deviation, degC, of the plate's true temperature about the nominal one "
                "at each step (furnace and thermocouple; 0: exact; truth in furnace-truth.csv)")
      ->check(finite_range(0.0, 50.0))
      ->capture_default_str();
  c->add_option("--furnace-seed", campaign.furnace_seed,
                "Seed of the plate's temperature errors (--furnace-error): campaigns that differ "
                "in it are independent furnace runs")
      ->check(seed_check())
      ->capture_default_str();
  c->add_option("--black-level-drift", campaign.black_level_drift_dn,
                "The furnace frames' black level moves since the darks were taken, linearly "
                "from 0 at the first temperature to this at the last, DN (-50 to 50; a sensor "
                "that warms up; 0: none)")
      ->check(finite_range(-50.0, 50.0))
      ->capture_default_str();
  c->add_option("--reference", campaign.reference_temperatures_c,
                "Reference sources beyond the furnace, nominal degC, comma separated (e.g. "
                "1324,1738,2474: fixed-point cells): manifest rows of kind reference, each with "
                "its own exposure sweep and darks, an unknown scale (aperture, distance) and a "
                "true temperature off the nominal (truth in furnace-truth.csv)")
      ->delimiter(',')
      ->check(finite_range(100.0, 4000.0));
  c->add_option("--reference-uncertainty", campaign.reference_uncertainty_c,
                "Standard uncertainty of the reference temperatures, degC (k=1): the manifest's "
                "temperature_uncertainty_c and the spread of their true values")
      ->check(finite_range(0.001, 100.0))
      ->capture_default_str();
  c->add_option("--size", campaign_size,
                "Image size WIDTHxHEIGHT, whole mosaic periods (default 128x128 rounded to "
                "whole periods: 130x130 for 5x5)");
  c->add_option("--roi-area", campaign.roi_area_px, "Elliptical ROI area, pixels")
      ->check(finite_range(1.0, 1e9))
      ->capture_default_str();
  add_format_option(c, campaign.image_extension);
  c->callback([&global, &selected] {
    if (!campaign_size.empty()) parse_size(campaign_size, campaign.width, campaign.height);
    selected = [&global] {
      Simulator camera = make_camera(campaign_camera);
      if (campaign_size.empty()) default_size(camera, 128, campaign.width, campaign.height);
      ProgressPrinter progress(global, "writing campaign");
      write_furnace_campaign(campaign_out, camera, campaign, std::ref(progress));
      if (!global.quiet)
        std::cout << "furnace campaign (" << camera.profile().name << ", unit "
                  << campaign_camera.unit << " seed " << campaign_camera.unit_seed
                  << ") written to " << campaign_out << "/manifest.csv in " << progress.elapsed_s()
                  << " s\n";
      return kExitOk;
    };
  });

  static CameraOptions scene_camera;
  static SceneSequenceSettings scene;
  static std::string scene_out, scene_kind = "melt-pool", scene_size;
  CLI::App* s =
      sim->add_subcommand("scene", "Write a test scene sequence (plate, filament, melt pool)");
  s->footer(
      "Examples:\n  pyrocam-calib simulate scene --scene melt-pool --frames 30 --out pool\n"
      "  pyrocam-calib simulate scene --scene filament --profile nir5x5-reference "
      "--temperatures 1000 1800 2600 --out filament");
  add_camera_options(s, scene_camera);
  s->add_option("--out", scene_out, "Output folder (created)")->required();
  s->add_option("--scene", scene_kind, "plate, filament or melt-pool")
      ->check(CLI::IsMember({"plate", "filament", "melt-pool"}))
      ->capture_default_str();
  s->add_option("--frames", scene.frames, "Frames (melt pool)")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  s->add_option("--temperatures", scene.temperatures_c,
                "Temperatures, degC (plate, filament; 100 to 4000, space or comma separated)")
      ->delimiter(',')
      ->check(finite_range(100.0, 4000.0));
  s->add_option("--size", scene_size,
                "Image size WIDTHxHEIGHT, whole mosaic periods (default 256x256 rounded to "
                "whole periods: 255x255 for 5x5)");
  s->add_option("--exposure", scene.exposure_us, "Exposure, us (up to 1e8; 0: automatic)")
      ->check(finite_range(0.0, 1e8))
      ->capture_default_str();
  s->add_option("--emissivity", scene.emissivity, "Graybody emissivity (0: the scene's default)")
      ->check(finite_range(0.0, 1.0));
  add_format_option(s, scene.image_extension);
  s->callback([&global, &selected] {
    if (!scene_size.empty()) parse_size(scene_size, scene.width, scene.height);
    selected = [&global] {
      scene.kind = parse_scene_kind(scene_kind);
      Simulator camera = make_camera(scene_camera);
      if (scene_size.empty()) default_size(camera, 256, scene.width, scene.height);
      ProgressPrinter progress(global, "writing " + scene_kind);
      write_scene_sequence(scene_out, camera, scene, std::ref(progress));
      if (!global.quiet)
        std::cout << scene_kind << " scene (" << camera.profile().name << ", unit "
                  << scene_camera.unit << " seed " << scene_camera.unit_seed << ") written to "
                  << scene_out << "/manifest.csv\n";
      return kExitOk;
    };
  });
}

}  // namespace pyrocam::cli
