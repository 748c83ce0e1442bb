#include "pyrocam/image_io.h"

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "pyrocam/spectrum.h"

namespace pyrocam {
namespace {

// OpenCV pads a short PGM/PPM with zeros instead of failing, so check the payload size first.
void check_pnm_length(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::string magic;
  in >> magic;
  if (magic != "P5") return;  // other formats are checked by their decoders
  long values[3];
  for (long& v : values) {
    in >> std::ws;
    while (in.peek() == '#') {
      std::string comment;
      std::getline(in, comment);
      in >> std::ws;
    }
    if (!(in >> v) || v <= 0) throw InputError(path.string() + ": malformed PGM header");
  }
  in.get();  // the single whitespace after maxval
  const long bytes_per_sample = values[2] > 255 ? 2 : 1;
  const auto header = static_cast<long>(in.tellg());
  const auto size = static_cast<long>(std::filesystem::file_size(path));
  const long needed = values[0] * values[1] * bytes_per_sample;
  if (size - header < needed)
    throw InputError(path.string() + ": truncated PGM (" + std::to_string(size - header) + " of " +
                     std::to_string(needed) + " bytes of pixel data)");
}

}  // namespace

cv::Mat read_raw_image(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw InputError(path.string() + ": image not found");
  check_pnm_length(path);
  cv::Mat image;
  try {
    image = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw InputError(path.string() + ": cannot decode image (" + e.what() + ")");
  }
  if (image.empty()) throw InputError(path.string() + ": unreadable or truncated image");
  if (image.channels() != 1)
    throw InputError(path.string() + ": " + std::to_string(image.channels()) +
                     " channels; raw mosaic images must be single-channel");
  if (image.depth() != CV_8U && image.depth() != CV_16U)
    throw InputError(path.string() + ": samples must be 8- or 16-bit unsigned integers");
  return image;
}

void write_raw_image(const std::filesystem::path& path, const cv::Mat& image) {
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw InputError(path.string() + ": only 8- or 16-bit single-channel images are written");
  bool ok = false;
  try {
    ok = cv::imwrite(path.string(), image);
  } catch (const cv::Exception& e) {
    throw InputError(path.string() + ": cannot write image (" + e.what() + ")");
  }
  if (!ok) throw InputError(path.string() + ": cannot write image");
}

}  // namespace pyrocam
