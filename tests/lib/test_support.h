// Helpers shared by the library tests: scratch folders and the reference data location.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>

namespace pyrocam::test {

// tests/reference-data (or $PYROCAM_SHARED_DATA).
std::filesystem::path shared_data_dir();
// A fresh, empty folder under the system temp dir, removed when the object goes.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag);
  ~ScratchDir();
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& rel) const { return path_ / rel; }

 private:
  std::filesystem::path path_;
};
void write_text(const std::filesystem::path& path, const std::string& text);
// The file's bytes; empty when it cannot be read.
std::string read_text(const std::filesystem::path& path);
// A PNG signature and IHDR chunk (valid CRC) declaring width x height, gray, `bits` deep, cut off
// there: all a decoder needs to decide what to allocate.
std::string png_header(std::uint32_t width, std::uint32_t height, int bits);

}  // namespace pyrocam::test
