// Reading and writing raw single-channel images (PGM, PNG, TIFF) exactly as a camera gave them.
#pragma once

#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace pyrocam {

// The largest raw frame read: no camera this method serves comes near, and a file that claims
// more is refused from its header before anything is decoded or allocated.
inline constexpr int kMaxImageSide = 65535;
inline constexpr long long kMaxImagePixels = 1LL << 27;  // 134 217 728, e.g. 16384 x 8192

// The width and height a PGM, PNG or TIFF header declares, read without decoding the pixels.
// Throws InputError naming the file when it is not a regular file, not one of those formats,
// its header is malformed, it declares more than the limits above, or (binary PGM) its pixel
// data is shorter than the header says.
cv::Size read_image_size(const std::filesystem::path& path);

// Reads an 8- or 16-bit single-channel image unchanged. Throws InputError naming the file when
// it is missing, not a regular file, over the size limits, unreadable, truncated, colour, or of
// another sample type.
cv::Mat read_raw_image(const std::filesystem::path& path);
// The same, refusing from the header (before decoding) an image whose size is not `expected`;
// the message says "<file>: image is WxH, <expected_what> is WxH".
cv::Mat read_raw_image(const std::filesystem::path& path, cv::Size expected,
                       const std::string& expected_what);

// Throws InputError ("<what>: values up to N DN, above the M DN full scale of a B-bit camera
// ...") when a 16-bit image holds samples above 2^bit_depth - 1 (bit_depth 9 to 15): data
// left-justified in 16 bits, which read as it is would be saturated or too bright.
void check_within_bit_depth(const cv::Mat& image, int bit_depth, const std::string& what);

// Writes an 8- or 16-bit single-channel image; the format follows the extension (.pgm, .png,
// .tif/.tiff). Throws InputError on failure.
void write_raw_image(const std::filesystem::path& path, const cv::Mat& image);

}  // namespace pyrocam
