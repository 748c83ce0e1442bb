// libFuzzer target: pyrocam::load_profile, the camera profile JSON. The input is written beside a
// link to the shipped curves (profiles/curves), so that its relative curve paths resolve.
#include "fuzz_support.h"
#include "pyrocam/core/profile.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool linked = [] {
    std::error_code ec;
    std::filesystem::create_directory_symlink(
        std::filesystem::path(PYROCAM_FUZZ_PROFILES_DIR) / "curves",
        pyrocam::fuzz::work_dir() / "curves", ec);
    return true;
  }();
  (void)linked;
  const auto path = pyrocam::fuzz::write_input("profile.json", data, size);
  pyrocam::fuzz::expect_input_error_only([&] {
    const pyrocam::CameraProfile p = pyrocam::load_profile(path);
    p.system_qe();
  });
  return 0;
}
