#include "test_support.h"

#include <cstdlib>
#include <fstream>
#include <random>

namespace pyrocam::test {

std::filesystem::path shared_data_dir() {
  if (const char* env = std::getenv("PYROCAM_SHARED_DATA"); env && *env) return env;
  return PYROCAM_TEST_SHARED_DATA;
}

ScratchDir::ScratchDir(const std::string& tag) {
  std::random_device rd;
  path_ =
      std::filesystem::temp_directory_path() / ("pyrocam-test-" + tag + "-" + std::to_string(rd()));
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path) << text;
}

}  // namespace pyrocam::test
