#include "pyrocam/core/image_io.h"

#include <tiffio.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

// The size a header declares, before any check; wide enough for any value a header can hold.
struct DeclaredSize {
  const char* format = "";
  std::uint64_t width = 0, height = 0;
  std::uint64_t pnm_maxval = 0;       // PGM only
  std::uint64_t pnm_data_offset = 0;  // PGM only: where the samples start
  bool pnm_binary_gray = false;       // P5: its payload length can be checked
};

[[noreturn]] void malformed(const std::filesystem::path& path, const std::string& format) {
  throw InputError(path.string() + ": malformed or truncated " + format + " header");
}

// PNM header: magic, width, height and (except for bitmaps) maxval, with '#' comments. Each
// number is read digit by digit and refused past 10 digits, so none can overflow.
DeclaredSize read_pnm_header(std::ifstream& in, const std::filesystem::path& path, char kind) {
  DeclaredSize d;
  d.format = "PGM";
  const bool bitmap = kind == '1' || kind == '4';
  std::array<std::uint64_t, 3> values{0, 0, 0};
  for (int i = 0; i < (bitmap ? 2 : 3); ++i) {
    int c = in.get();
    while (c == '#' || std::isspace(c)) {
      if (c == '#')
        while (c != '\n' && c != EOF) c = in.get();
      c = in.get();
    }
    int digits = 0;
    for (; c != EOF && std::isdigit(c); c = in.get()) {
      if (++digits > 10) malformed(path, "PGM");
      values[i] = values[i] * 10 + static_cast<std::uint64_t>(c - '0');
    }
    if (digits == 0 || (c != EOF && !std::isspace(c))) malformed(path, "PGM");
  }
  d.width = values[0];
  d.height = values[1];
  d.pnm_maxval = bitmap ? 1 : values[2];
  if (d.pnm_maxval < 1 || d.pnm_maxval > 65535) malformed(path, "PGM");
  d.pnm_data_offset = static_cast<std::uint64_t>(in.tellg());
  d.pnm_binary_gray = kind == '5';
  return d;
}

std::uint64_t read_unsigned(std::ifstream& in, int bytes, bool big_endian) {
  std::array<unsigned char, 8> b{};
  if (!in.read(reinterpret_cast<char*>(b.data()), bytes)) return UINT64_MAX;
  std::uint64_t v = 0;
  for (int i = 0; i < bytes; ++i)
    v |= std::uint64_t{b[i]} << (8 * (big_endian ? bytes - 1 - i : i));
  return v;
}

// PNG: the IHDR chunk must come first, right after the signature.
DeclaredSize read_png_header(std::ifstream& in, const std::filesystem::path& path) {
  in.seekg(8);
  const std::uint64_t length = read_unsigned(in, 4, true);
  char type[4] = {};
  in.read(type, 4);
  if (!in || length != 13 || std::string(type, 4) != "IHDR") malformed(path, "PNG");
  DeclaredSize d;
  d.format = "PNG";
  d.width = read_unsigned(in, 4, true);
  d.height = read_unsigned(in, 4, true);
  if (d.width == UINT64_MAX || d.height == UINT64_MAX) malformed(path, "PNG");
  return d;
}

// TIFF and BigTIFF: ImageWidth (256) and ImageLength (257) of the first directory.
DeclaredSize read_tiff_header(std::ifstream& in, const std::filesystem::path& path, bool big_endian,
                              bool big_tiff) {
  in.seekg(4);
  std::uint64_t offset;
  if (big_tiff) {
    read_unsigned(in, 4, big_endian);  // offset size (8) and a zero
    offset = read_unsigned(in, 8, big_endian);
  } else {
    offset = read_unsigned(in, 4, big_endian);
  }
  if (offset == UINT64_MAX || offset > static_cast<std::uint64_t>(INT64_MAX))
    malformed(path, "TIFF");
  in.seekg(static_cast<std::streamoff>(offset));
  const std::uint64_t entries = read_unsigned(in, big_tiff ? 8 : 2, big_endian);
  if (entries == UINT64_MAX || entries > 65535) malformed(path, "TIFF");
  DeclaredSize d;
  d.format = "TIFF";
  for (std::uint64_t e = 0; e < entries && !(d.width && d.height); ++e) {
    const std::uint64_t tag = read_unsigned(in, 2, big_endian);
    const std::uint64_t type = read_unsigned(in, 2, big_endian);
    read_unsigned(in, big_tiff ? 8 : 4, big_endian);  // value count
    // A SHORT (3), LONG (4) or LONG8 (16) value sits left-justified in the value field.
    const int field = big_tiff ? 8 : 4;
    const int size = type == 3 ? 2 : type == 4 ? 4 : type == 16 ? 8 : 0;
    std::array<char, 8> raw{};
    if (!in.read(raw.data(), field)) malformed(path, "TIFF");
    if ((tag != 256 && tag != 257) || size == 0 || size > field) continue;
    std::uint64_t v = 0;
    for (int i = 0; i < size; ++i)
      v |= std::uint64_t{static_cast<unsigned char>(raw[i])}
           << (8 * (big_endian ? size - 1 - i : i));
    (tag == 256 ? d.width : d.height) = v;
  }
  if (!d.width || !d.height) malformed(path, "TIFF");
  return d;
}

DeclaredSize read_declared_size(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open image");
  std::array<char, 8> magic{};
  in.read(magic.data(), magic.size());
  const std::string m(magic.data(), static_cast<std::size_t>(in.gcount()));
  in.clear();
  if (m.size() >= 3 && m[0] == 'P' && m[1] >= '1' && m[1] <= '6' &&
      std::isspace(static_cast<unsigned char>(m[2]))) {
    in.seekg(2);
    return read_pnm_header(in, path, m[1]);
  }
  if (m == std::string("\x89PNG\r\n\x1a\n", 8)) return read_png_header(in, path);
  if (m.size() >= 4 && (m.compare(0, 4, std::string("II*\0", 4)) == 0 ||
                        m.compare(0, 4, std::string("MM\0*", 4)) == 0))
    return read_tiff_header(in, path, m[0] == 'M', false);
  if (m.size() >= 4 && (m.compare(0, 4, std::string("II+\0", 4)) == 0 ||
                        m.compare(0, 4, std::string("MM\0+", 4)) == 0))
    return read_tiff_header(in, path, m[0] == 'M', true);
  throw InputError(path.string() + ": not a PGM, PNG or TIFF image");
}

// libtiff's first error on one file, through the file's own handler (libtiff 4.5): OpenCV's
// TIFF decoder returned an image whose LZW strips had failed to decode (the rows then hold
// whatever the buffer held), so TIFFs are decoded here and any decoding error refuses the file.
struct TiffErrors {
  std::string first;
};

// (The module libtiff names is mostly the file's name, which the message already has.)
int note_tiff_error(TIFF*, void* user, const char*, const char* format, va_list args) {
  auto* errors = static_cast<TiffErrors*>(user);
  if (errors->first.empty()) {
    char text[512];
    std::vsnprintf(text, sizeof text, format, args);
    errors->first = text;
  }
  return 1;  // handled: not printed
}

int ignore_tiff_warning(TIFF*, void*, const char*, const char*, va_list) {
  return 1;  // unknown tags and the like: the samples decode all the same
}

cv::Mat read_tiff(const std::filesystem::path& path) {
  TiffErrors errors;
  TIFFOpenOptions* options = TIFFOpenOptionsAlloc();
  if (!options) throw InputError(path.string() + ": cannot decode TIFF (out of memory)");
  TIFFOpenOptionsSetErrorHandlerExtR(options, note_tiff_error, &errors);
  TIFFOpenOptionsSetWarningHandlerExtR(options, ignore_tiff_warning, nullptr);
  const std::unique_ptr<TIFF, void (*)(TIFF*)> tiff(TIFFOpenExt(path.c_str(), "r", options),
                                                    TIFFClose);
  TIFFOpenOptionsFree(options);
  const auto refuse = [&](const std::string& why) {
    return InputError(path.string() + ": " + why);
  };
  const auto corrupt = [&]() {
    return refuse("corrupt or truncated TIFF (" +
                  (errors.first.empty() ? std::string("a strip or tile is short") : errors.first) +
                  ")");
  };
  if (!tiff) throw corrupt();
  TIFF* t = tiff.get();
  std::uint32_t width = 0, height = 0;
  std::uint16_t bits = 0, samples = 0, format = 0, photometric = PHOTOMETRIC_MINISBLACK;
  if (!TIFFGetField(t, TIFFTAG_IMAGEWIDTH, &width) ||
      !TIFFGetField(t, TIFFTAG_IMAGELENGTH, &height))
    throw corrupt();
  TIFFGetFieldDefaulted(t, TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(t, TIFFTAG_SAMPLEFORMAT, &format);
  TIFFGetField(t, TIFFTAG_PHOTOMETRIC, &photometric);
  if (samples != 1)
    throw refuse(std::to_string(samples) + " channels; raw mosaic images must be single-channel");
  if ((bits != 8 && bits != 16) || format != SAMPLEFORMAT_UINT)
    throw refuse("samples must be 8- or 16-bit unsigned integers");
  if (photometric != PHOTOMETRIC_MINISBLACK)
    throw refuse("TIFF photometric interpretation " + std::to_string(photometric) +
                 "; raw mosaic images are grey, 0 = black");
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), bits == 8 ? CV_8U : CV_16U);
  const std::size_t pixel_bytes = bits / 8;
  if (TIFFIsTiled(t)) {
    std::uint32_t tile_width = 0, tile_height = 0;
    TIFFGetField(t, TIFFTAG_TILEWIDTH, &tile_width);
    TIFFGetField(t, TIFFTAG_TILELENGTH, &tile_height);
    const tmsize_t tile_bytes = TIFFTileSize(t);
    if (tile_width == 0 || tile_height == 0 || tile_bytes <= 0) throw corrupt();
    std::vector<unsigned char> tile(static_cast<std::size_t>(tile_bytes));
    for (std::uint32_t y = 0; y < height; y += tile_height)
      for (std::uint32_t x = 0; x < width; x += tile_width) {
        if (TIFFReadTile(t, tile.data(), x, y, 0, 0) != tile_bytes) throw corrupt();
        const std::uint32_t rows = std::min(tile_height, height - y);
        const std::size_t row_bytes = std::min(tile_width, width - x) * pixel_bytes;
        for (std::uint32_t r = 0; r < rows; ++r)
          std::memcpy(image.ptr(static_cast<int>(y + r)) + x * pixel_bytes,
                      &tile[r * tile_width * pixel_bytes], row_bytes);
      }
  } else {
    std::uint32_t rows_per_strip = 0;
    TIFFGetFieldDefaulted(t, TIFFTAG_ROWSPERSTRIP, &rows_per_strip);
    rows_per_strip = std::clamp<std::uint32_t>(rows_per_strip, 1, height);
    for (std::uint32_t y = 0, strip = 0; y < height; y += rows_per_strip, ++strip) {
      const std::uint32_t rows = std::min(rows_per_strip, height - y);
      const tmsize_t bytes = TIFFVStripSize(t, rows);
      if (bytes != static_cast<tmsize_t>(rows * width * pixel_bytes) ||
          TIFFReadEncodedStrip(t, strip, image.ptr(static_cast<int>(y)), bytes) != bytes)
        throw corrupt();
    }
  }
  if (!errors.first.empty()) throw corrupt();
  return image;
}

// The declared size of an image, checked against the limits; for a binary PGM, its payload
// length too.
DeclaredSize checked_declared_size(const std::filesystem::path& path) {
  require_regular_file(path, "image");
  const DeclaredSize d = read_declared_size(path);
  const std::string declared = std::string(d.format) + " header declares " +
                               std::to_string(d.width) + "x" + std::to_string(d.height) + " pixels";
  if (d.width == 0 || d.height == 0) throw InputError(path.string() + ": " + declared);
  // Both sides are at most 2^16 here, so the product cannot overflow.
  if (d.width > kMaxImageSide || d.height > kMaxImageSide ||
      d.width * d.height > static_cast<std::uint64_t>(kMaxImagePixels))
    throw InputError(path.string() + ": " + declared + "; raw frames are limited to " +
                     std::to_string(kMaxImageSide) + " on a side and " +
                     std::to_string(kMaxImagePixels) + " pixels in all");
  if (d.pnm_binary_gray) {
    // OpenCV pads a short PGM with zeros instead of failing, so check the payload size first.
    const std::uint64_t needed = d.width * d.height * (d.pnm_maxval > 255 ? 2 : 1);
    const std::uint64_t size = std::filesystem::file_size(path);
    const std::uint64_t have = size > d.pnm_data_offset ? size - d.pnm_data_offset : 0;
    if (have < needed)
      throw InputError(path.string() + ": truncated PGM (" + std::to_string(have) + " of " +
                       std::to_string(needed) + " bytes of pixel data)");
  }
  return d;
}

}  // namespace

cv::Size read_image_size(const std::filesystem::path& path) {
  const DeclaredSize d = checked_declared_size(path);
  return {static_cast<int>(d.width), static_cast<int>(d.height)};
}

cv::Mat read_raw_image(const std::filesystem::path& path) {
  const DeclaredSize d = checked_declared_size(path);
  const cv::Size declared(static_cast<int>(d.width), static_cast<int>(d.height));
  cv::Mat image;
  try {
    image = std::string(d.format) == "TIFF" ? read_tiff(path)
                                            : cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw InputError(path.string() + ": cannot decode image (" + e.what() + ")");
  }
  if (image.empty()) throw InputError(path.string() + ": unreadable or truncated image");
  if (image.size() != declared)
    throw InputError(path.string() + ": decoded " + std::to_string(image.cols) + "x" +
                     std::to_string(image.rows) + " pixels, the header declares " +
                     std::to_string(declared.width) + "x" + std::to_string(declared.height));
  if (image.channels() != 1)
    throw InputError(path.string() + ": " + std::to_string(image.channels()) +
                     " channels; raw mosaic images must be single-channel");
  if (image.depth() != CV_8U && image.depth() != CV_16U)
    throw InputError(path.string() + ": samples must be 8- or 16-bit unsigned integers");
  return image;
}

cv::Mat read_raw_image(const std::filesystem::path& path, cv::Size expected,
                       const std::string& expected_what) {
  require_regular_file(path, "image");
  const DeclaredSize d = read_declared_size(path);
  if (d.width != static_cast<std::uint64_t>(expected.width) ||
      d.height != static_cast<std::uint64_t>(expected.height))
    throw InputError(path.string() + ": image is " + std::to_string(d.width) + "x" +
                     std::to_string(d.height) + ", " + expected_what + " is " +
                     std::to_string(expected.width) + "x" + std::to_string(expected.height));
  return read_raw_image(path);
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

void check_within_bit_depth(const cv::Mat& image, int bit_depth, const std::string& what) {
  if (image.depth() != CV_16U || bit_depth <= 8 || bit_depth >= 16) return;
  double highest = 0;
  cv::minMaxLoc(image, nullptr, &highest);
  const long full_scale = (1L << bit_depth) - 1;
  if (highest > static_cast<double>(full_scale))
    throw InputError(what + ": values up to " + std::to_string(static_cast<long>(highest)) +
                     " DN, above the " + std::to_string(full_scale) + " DN full scale of a " +
                     std::to_string(bit_depth) + "-bit camera. Data left-justified in 16 bits? " +
                     "Shift it right by " + std::to_string(16 - bit_depth) + " bits");
}

}  // namespace pyrocam
