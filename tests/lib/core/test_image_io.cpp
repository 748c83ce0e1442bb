// Raw image reading: sizes come from the header before any decoding, so that a file claiming an
// absurd size is refused by name instead of overflowing arithmetic or allocating gigabytes.
#include <gtest/gtest.h>
#include <sys/stat.h>
// libtiff 4.5 marks its own int64 deprecated, which OpenCV declares again.
#define TIFF_DISABLE_DEPRECATED
#include <tiffio.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::png_header;
using test::ScratchDir;

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// A little-endian TIFF whose first directory holds ImageWidth and ImageLength as LONGs.
std::string tiff_header(std::uint32_t width, std::uint32_t height) {
  auto le16 = [](std::uint16_t v) {
    return std::string{static_cast<char>(v), static_cast<char>(v >> 8)};
  };
  auto le32 = [](std::uint32_t v) {
    return std::string{static_cast<char>(v), static_cast<char>(v >> 8), static_cast<char>(v >> 16),
                       static_cast<char>(v >> 24)};
  };
  std::string s = std::string("II*\0", 4) + le32(8) + le16(2);
  s += le16(256) + le16(4) + le32(1) + le32(width);
  s += le16(257) + le16(4) + le32(1) + le32(height);
  return s + le32(0);
}

std::string rejection(const std::filesystem::path& path) {
  try {
    read_raw_image(path);
  } catch (const InputError& e) {
    return e.what();
  }
  return "accepted";
}

void expect_rejected(const std::filesystem::path& path, const std::string& needle) {
  const std::string message = rejection(path);
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find(needle), std::string::npos) << message;
}

TEST(ImageHeader, sizes_agree_with_decoded_images) {
  ScratchDir dir("image-io");
  cv::Mat eight(32, 40, CV_8U), sixteen(18, 26, CV_16U);
  cv::randu(eight, 0, 255);
  cv::randu(sixteen, 0, 65535);
  for (const char* ext : {".pgm", ".png", ".tif"}) {
    for (const cv::Mat& image : {eight, sixteen}) {
      const auto path = dir / (std::to_string(image.depth()) + ext);
      write_raw_image(path, image);
      EXPECT_EQ(read_image_size(path), image.size()) << path;
      const cv::Mat back = read_raw_image(path);
      EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0) << path;
    }
  }
}

TEST(ImageHeader, pgm_with_comments_and_16_bit_samples_reads) {
  ScratchDir dir("image-io");
  std::string bytes = "P5\n# made by hand\n3 2\n# max\n1000\n";
  for (int i = 0; i < 6; ++i) bytes += {0, static_cast<char>(i)};
  write_bytes(dir / "a.pgm", bytes);
  const cv::Mat image = read_raw_image(dir / "a.pgm");
  ASSERT_EQ(image.size(), cv::Size(3, 2));
  EXPECT_EQ(image.at<std::uint16_t>(1, 2), 5);
}

// A file whose header alone is refused: its name, bytes and what the refusal says besides the
// file's path.
struct BadHeader {
  const char* label;
  const char* file;
  std::string bytes;
  const char* message;
};

// gtest prints a case by its label, not its bytes.
void PrintTo(const BadHeader& c, std::ostream* os) { *os << c.label; }

class ImageHeaderRejects : public ::testing::TestWithParam<BadHeader> {};

TEST_P(ImageHeaderRejects, by_name_n) {
  ScratchDir dir("image-io");
  write_bytes(dir / GetParam().file, GetParam().bytes);
  expect_rejected(dir / GetParam().file, GetParam().message);
}

INSTANTIATE_TEST_SUITE_P(
    ImageHeader, ImageHeaderRejects,
    ::testing::Values(
        BadHeader{"pgm_declaring_2_pow_32_squared_n", "a.pgm",
                  "P5\n4294967296 4294967296\n255\n" + std::string(64, '\0'),
                  "PGM header declares 4294967296x4294967296 pixels"},
        // 3037000500^2 is just above 2^63: the old check multiplied in a signed long.
        BadHeader{"pgm_whose_size_product_overflows_64_bits_n", "a.pgm",
                  "P5\n3037000500 3037000500\n65535\n" + std::string(64, '\0'),
                  "PGM header declares 3037000500x3037000500 pixels"},
        BadHeader{"pgm_with_an_overlong_number_n", "a.pgm",
                  "P5\n99999999999999999999999 2\n255\n" + std::string(64, '\0'),
                  "malformed or truncated PGM header"},
        BadHeader{"pgm_with_maxval_above_16_bits_n", "a.pgm",
                  "P5\n2 2\n70000\n" + std::string(8, '\0'), "malformed or truncated PGM header"},
        BadHeader{"truncated_pgm_n", "a.pgm", "P5\n100 100\n65535\n" + std::string(1000, '\0'),
                  "truncated PGM (1000 of 20000 bytes of pixel data)"},
        BadHeader{"png_of_30000_squared_before_decoding_n", "a.png", png_header(30000, 30000, 8),
                  "PNG header declares 30000x30000 pixels"},
        BadHeader{"16_bit_png_of_32768_squared_before_decoding_n", "a.png",
                  png_header(32768, 32768, 16), "PNG header declares 32768x32768 pixels"},
        BadHeader{"png_wider_than_the_side_limit_n", "a.png", png_header(70000, 1, 8),
                  "PNG header declares 70000x1 pixels; raw frames are limited"},
        BadHeader{"tiff_of_40000_squared_before_decoding_n", "a.tif", tiff_header(40000, 40000),
                  "TIFF header declares 40000x40000 pixels"},
        BadHeader{"tiff_cut_inside_its_header_n", "a.tif", tiff_header(40, 30).substr(0, 14),
                  "malformed or truncated TIFF header"}),
    [](const ::testing::TestParamInfo<BadHeader>& info) { return std::string(info.param.label); });

// A random 64x64 16-bit image written to `path`, then cut off half way.
void write_cut_in_half(const std::filesystem::path& path) {
  cv::Mat image(64, 64, CV_16U);
  cv::randu(image, 0, 65535);
  write_raw_image(path, image);
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
}

TEST(ImageHeader, rejects_truncated_png_n) {
  ScratchDir dir("image-io");
  write_cut_in_half(dir / "a.png");
  expect_rejected(dir / "a.png", "unreadable or truncated image");
}

TEST(ImageHeader, rejects_truncated_tiff_n) {
  ScratchDir dir("image-io");
  write_cut_in_half(dir / "a.tif");
  EXPECT_NE(rejection(dir / "a.tif").find(dir.path().string() + "/a.tif"), std::string::npos)
      << rejection(dir / "a.tif");
}

// OpenCV's decoder returned such a TIFF whole, the rows of its failed strips holding what the
// buffer held: a dark frame that read as valid and moved a plate's readings by tens of degC.
TEST(ImageHeader, rejects_a_tiff_whose_compressed_strips_fail_to_decode_n) {
  ScratchDir dir("image-io");
  cv::Mat image(240, 320, CV_8U);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) image.at<std::uint8_t>(y, x) = (x / 7 + y / 5) % 60 + 40;
  write_raw_image(dir / "a.tif", image);  // LZW-compressed strips
  ASSERT_EQ(cv::norm(read_raw_image(dir / "a.tif"), image, cv::NORM_INF), 0);
  std::string bytes;
  {
    std::ifstream in(dir / "a.tif", std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  for (std::size_t i = bytes.size() / 3; i < bytes.size() / 3 + 40; ++i) bytes[i] ^= 0x5a;
  write_bytes(dir / "a.tif", bytes);
  expect_rejected(dir / "a.tif", "corrupt or truncated TIFF");
}

TEST(ImageHeader, tiled_and_uncompressed_tiffs_read_n) {
  ScratchDir dir("image-io");
  cv::Mat image(37, 53, CV_16U);
  cv::randu(image, 0, 65535);
  ASSERT_TRUE(cv::imwrite((dir / "plain.tif").string(), image,
                          {cv::IMWRITE_TIFF_COMPRESSION, 1 /* none */}));
  EXPECT_EQ(cv::norm(read_raw_image(dir / "plain.tif"), image, cv::NORM_INF), 0);
  {  // 16x16 tiles, the last ones partial, big-endian, deflate
    TIFF* t = TIFFOpen((dir / "tiled.tif").c_str(), "wb");
    ASSERT_NE(t, nullptr);
    TIFFSetField(t, TIFFTAG_IMAGEWIDTH, image.cols);
    TIFFSetField(t, TIFFTAG_IMAGELENGTH, image.rows);
    TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, 16);
    TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
    TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
    TIFFSetField(t, TIFFTAG_COMPRESSION, COMPRESSION_ADOBE_DEFLATE);
    TIFFSetField(t, TIFFTAG_TILEWIDTH, 16);
    TIFFSetField(t, TIFFTAG_TILELENGTH, 16);
    std::vector<std::uint16_t> tile(16 * 16);
    for (int y = 0; y < image.rows; y += 16)
      for (int x = 0; x < image.cols; x += 16) {
        std::fill(tile.begin(), tile.end(), 0);
        for (int r = 0; r < 16 && y + r < image.rows; ++r)
          for (int c = 0; c < 16 && x + c < image.cols; ++c)
            tile[r * 16 + c] = image.at<std::uint16_t>(y + r, x + c);
        ASSERT_GE(TIFFWriteTile(t, tile.data(), x, y, 0, 0), 0);
      }
    TIFFClose(t);
  }
  EXPECT_EQ(cv::norm(read_raw_image(dir / "tiled.tif"), image, cv::NORM_INF), 0);
  cv::Mat colour(8, 8, CV_8UC3, cv::Scalar(1, 2, 3));
  ASSERT_TRUE(cv::imwrite((dir / "colour.tif").string(), colour));
  expect_rejected(dir / "colour.tif", "3 channels; raw mosaic images must be single-channel");
}

TEST(ImageHeader, rejects_other_formats_n) {
  ScratchDir dir("image-io");
  cv::imwrite((dir / "a.bmp").string(), cv::Mat::zeros(8, 8, CV_8U));
  expect_rejected(dir / "a.bmp", "not a PGM, PNG or TIFF image");
}

TEST(ImageHeader, rejects_a_directory_n) {
  ScratchDir dir("image-io");
  std::filesystem::create_directory(dir / "frame.pgm");
  expect_rejected(dir / "frame.pgm", "image is a directory");
}

TEST(ImageHeader, rejects_a_fifo_without_opening_it_n) {
  ScratchDir dir("image-io");
  ASSERT_EQ(mkfifo((dir / "frame.pgm").c_str(), 0600), 0);
  // Opening a FIFO with no writer would block; the reader must refuse it first.
  expect_rejected(dir / "frame.pgm", "image is not a regular file");
}

TEST(ImageHeader, rejects_a_missing_file_n) {
  ScratchDir dir("image-io");
  expect_rejected(dir / "none.pgm", "image not found");
}

TEST(ImageHeader, expected_size_is_checked_before_decoding_n) {
  ScratchDir dir("image-io");
  write_bytes(dir / "a.png", png_header(10000, 10000, 16));
  try {
    read_raw_image(dir / "a.png", cv::Size(40, 32), "the frame");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a.png: image is 10000x10000, the frame is 40x32"),
              std::string::npos)
        << e.what();
  }
}

// 12-bit data left-justified in 16 bits (every sample a multiple of 16, up to 65520) is not what
// a 12-bit camera gives: refused, with the shift that would make it so. Right-justified data, 8-bit
// images and 16-bit cameras pass.
TEST(ImageBitDepth, refuses_samples_above_the_cameras_full_scale_n) {
  cv::Mat right(4, 4, CV_16U, cv::Scalar(4095));
  EXPECT_NO_THROW(check_within_bit_depth(right, 12, "frame"));
  EXPECT_NO_THROW(check_within_bit_depth(right * 16, 16, "frame"));
  EXPECT_NO_THROW(check_within_bit_depth(cv::Mat(4, 4, CV_8U, cv::Scalar(255)), 8, "frame"));
  cv::Mat left = right.clone();
  left.at<std::uint16_t>(3, 2) = 4096;
  try {
    check_within_bit_depth(left, 12, "frame f.tif");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("frame f.tif: values up to 4096 DN, above the 4095 DN full scale of a "
                        "12-bit camera"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("Shift it right by 4 bits"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace pyrocam
