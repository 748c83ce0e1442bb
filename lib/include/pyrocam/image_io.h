// Reading and writing raw single-channel images (PGM, PNG, TIFF) exactly as a camera gave them.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>

namespace pyrocam {

// Reads an 8- or 16-bit single-channel image unchanged. Throws InputError naming the file when
// it is missing, unreadable, truncated, colour, or of another sample type.
cv::Mat read_raw_image(const std::filesystem::path& path);

// Writes an 8- or 16-bit single-channel image; the format follows the extension (.pgm, .png,
// .tif/.tiff). Throws InputError on failure.
void write_raw_image(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace pyrocam
