// What the CLI test files share: running pyrocam-calib as a child process, the test models,
// simulated plates.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>
#include <string>

#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam::test {

inline std::string q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

// Runs pyrocam-calib quietly with `args` (shell-quoted where needed), stdin closed; returns its
// exit code.
inline int calib(const std::string& args) {
  const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' -q " + args +
                              " < /dev/null > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

struct ToolRun {
  int exit_code = -1;
  std::string err;
};

// Runs pyrocam-calib with `args` (already shell-quoted where needed), stdin closed; stderr is
// kept in `dir`. A timeout ends a run that hangs (a FIFO opened for reading blocks forever).
inline ToolRun run_tool(const std::string& args, const ScratchDir& dir) {
  const auto err = dir / "stderr.txt";
  const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' " + args +
                              " < /dev/null > /dev/null 2> '" + err.string() + "'";
  const int status = std::system(command.c_str());
  ToolRun r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.err = read_text(err);
  return r;
}

// Said when one is missing: meson test sets the folder, and a test without its model fails.
inline constexpr const char* kNoTestModels =
    "the build's test models are missing; run the test through meson test, or set "
    "PYROCAM_TEST_MODEL_DIR to build/tests/data";

// A test model of the build (PYROCAM_TEST_MODEL_DIR) by file name.
inline std::filesystem::path test_model(const std::string& name) {
  const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
  return std::filesystem::path(dir ? dir : ".") / name;
}

// A dataset of one plate frame at t_c by the typical unit `seed` of `profile`, its brightest band
// `exposure_scale` times the scenes' usual level above dark.
inline void write_plate(const std::filesystem::path& folder, const std::string& profile,
                        std::uint64_t seed, double t_c, int size, double exposure_scale = 1) {
  Simulator camera(load_profile_by_name(profile), UnitPerturbation{"typical", seed});
  SceneSequenceSettings s;
  s.kind = SceneKind::kPlate;
  s.temperatures_c = {t_c};
  s.width = size;
  s.height = size;
  s.target_dn = exposure_scale * kSceneDefaults.target_dn;
  write_scene_sequence(folder, camera, s);
}

// The first frame's row of stats.csv, by column name.
inline std::map<std::string, std::string> first_stats_row(const std::filesystem::path& folder) {
  std::istringstream in(read_text(folder / "stats.csv"));
  std::string header, row;
  std::getline(in, header);
  std::getline(in, row);
  std::map<std::string, std::string> fields;
  std::istringstream h(header), r(row);
  for (std::string name, value; std::getline(h, name, ',');) {
    std::getline(r, value, ',');
    fields[name] = value;
  }
  return fields;
}

}  // namespace pyrocam::test
