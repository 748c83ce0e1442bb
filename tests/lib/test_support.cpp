#include "test_support.h"

#include <cstdlib>
#include <fstream>
#include <iterator>
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

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

namespace {
std::string big_endian32(std::uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>(v >> 16), static_cast<char>(v >> 8),
          static_cast<char>(v)};
}
// CRC-32 of a PNG chunk's type and data.
std::uint32_t png_crc(const std::string& bytes) {
  std::uint32_t c = 0xffffffffu;
  for (const unsigned char b : bytes) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
  }
  return c ^ 0xffffffffu;
}
}  // namespace

std::string png_header(std::uint32_t width, std::uint32_t height, int bits) {
  std::string ihdr = "IHDR" + big_endian32(width) + big_endian32(height);
  ihdr += {static_cast<char>(bits), 0, 0, 0, 0};
  return std::string("\x89PNG\r\n\x1a\n", 8) + big_endian32(13) + ihdr +
         big_endian32(png_crc(ihdr));
}

}  // namespace pyrocam::test
