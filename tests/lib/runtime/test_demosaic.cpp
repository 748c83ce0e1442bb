// Demosaicking: bilinear and moment-matched Bayer, 2x2 binning, 5x5 macro-pixels binned and
// registered to the cell centre, mark propagation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/mixed_pixels.h"

namespace pyrocam {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// A mosaic whose band b at pixel (x, y) reads 100 b + x + 10 y: bilinear interpolation of a
// linear ramp is exact away from the mirrored borders.
cv::Mat ramp(const MosaicLayout& m, int w, int h) {
  cv::Mat img(h, w, CV_32F);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at<float>(y, x) = 100.f * m.band_at(x, y) + x + 10.f * y;
  return img;
}

TEST(Demosaic, bilinear_is_exact_on_a_ramp_for_every_bayer_pattern) {
  for (const char* p : {"RGGB", "BGGR", "GRBG", "GBRG"}) {
    const MosaicLayout m = MosaicLayout::bayer(p);
    std::vector<cv::Mat> planes;
    demosaic(ramp(m, 8, 6), m, DemosaicMethod::kBilinear, planes);
    ASSERT_EQ(planes.size(), 3u);
    ASSERT_EQ(planes[0].size(), cv::Size(8, 6));
    for (int b = 0; b < 3; ++b)
      for (int y = 1; y < 5; ++y)
        for (int x = 1; x < 7; ++x)
          EXPECT_FLOAT_EQ(planes[b].at<float>(y, x), 100.f * b + x + 10.f * y)
              << p << " band " << b << " at " << x << "," << y;
  }
}

TEST(Demosaic, bilinear_borders_mirror_the_pattern) {
  const MosaicLayout m = MosaicLayout::bayer("RGGB");
  cv::Mat img = ramp(m, 4, 4);
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kBilinear, planes);
  // B at the R pixel (0,0): its only diagonal neighbour (1,1), mirrored 4 times.
  EXPECT_FLOAT_EQ(planes[2].at<float>(0, 0), img.at<float>(1, 1));
  // G at (0,0): (1,0) and (0,1), each twice.
  EXPECT_FLOAT_EQ(planes[1].at<float>(0, 0), 0.5f * (img.at<float>(0, 1) + img.at<float>(1, 0)));
}

TEST(Demosaic, saturation_and_nan_marks_spread_to_every_value_computed_from_them) {
  const MosaicLayout m = MosaicLayout::bayer("RGGB");
  cv::Mat img(6, 6, CV_32F, cv::Scalar(10));
  img.at<float>(2, 2) = kInf;           // an R pixel
  img.at<float>(2, 3) = std::nanf("");  // a G pixel next to it
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kBilinear, planes);
  EXPECT_EQ(planes[0].at<float>(2, 2), kInf);
  EXPECT_EQ(planes[0].at<float>(3, 3), kInf);  // R at the B pixel diagonal to it
  EXPECT_EQ(planes[0].at<float>(2, 3), kInf);  // R at the NaN G pixel: mean of +INF and 10
  EXPECT_TRUE(std::isnan(planes[1].at<float>(2, 3)));
  EXPECT_EQ(planes[0].at<float>(0, 0), 10.f);
  std::vector<cv::Mat> bins;
  demosaic(img, m, DemosaicMethod::kBinCells, bins);
  EXPECT_EQ(bins[0].at<float>(1, 1), kInf);
  EXPECT_TRUE(std::isnan(bins[1].at<float>(1, 1)));
  EXPECT_EQ(bins[2].at<float>(1, 1), 10.f);
}

TEST(Demosaic, bin2x2_gives_r_mean_g_b_per_cell) {
  const MosaicLayout m = MosaicLayout::bayer("GRBG");
  cv::Mat img = (cv::Mat_<float>(2, 4) << 1, 2, 5, 6, 3, 4, 7, 8);  // G R / B G cells
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kBinCells, planes);
  ASSERT_EQ(planes[0].size(), cv::Size(2, 1));
  EXPECT_EQ(planes[0].at<float>(0, 0), 2.f);
  EXPECT_EQ(planes[1].at<float>(0, 0), 2.5f);
  EXPECT_EQ(planes[2].at<float>(0, 0), 3.f);
  EXPECT_EQ(planes[1].at<float>(0, 1), 6.5f);
}

TEST(Demosaic, snapshot_gives_one_reading_per_macro_pixel_in_band_map_order) {
  std::vector<int> map(25);
  std::iota(map.begin(), map.end(), 0);
  std::swap(map[0], map[24]);
  const MosaicLayout m = MosaicLayout::snapshot(5, 5, map);
  cv::Mat img(12, 11, CV_32F);  // 2x2 macro-pixels, a partial trailing cell
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 11; ++x) img.at<float>(y, x) = 1000.f * y + x;
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kBilinear, planes);  // the method is ignored
  ASSERT_EQ(planes.size(), 25u);
  ASSERT_EQ(planes[0].size(), cv::Size(2, 2));
  EXPECT_EQ(planes[7].at<float>(1, 0), img.at<float>(5 + 1, 0 + 2));
  EXPECT_EQ(planes[24].at<float>(0, 1), img.at<float>(0, 5));
  EXPECT_EQ(planes[0].at<float>(0, 1), img.at<float>(4, 9));
}

// Binning a frame large enough to be split over threads: every band of every cell is its
// sample (the band map's place), for the 5x5 period and another one (4x3), with a partial
// trailing cell (and, for 5x5, cells past the last group of four the vector path takes);
// Bayer's two greens are averaged.
TEST(Demosaic, binning_large_frames_takes_each_band_from_its_place_in_every_cell) {
  std::vector<int> map5(25);
  std::iota(map5.begin(), map5.end(), 0);
  std::reverse(map5.begin(), map5.end());
  std::vector<int> map43(12);
  std::iota(map43.begin(), map43.end(), 0);
  std::swap(map43[1], map43[10]);
  for (const MosaicLayout& m :
       {MosaicLayout::snapshot(5, 5, map5), MosaicLayout::snapshot(4, 3, map43)}) {
    cv::Mat img(1087, 1033, CV_32F);
    cv::randu(img, -5, 250);
    img.at<float>(7, 9) = kInf;
    img.at<float>(8, 9) = std::numeric_limits<float>::quiet_NaN();
    std::vector<cv::Mat> planes;
    demosaic(img, m, DemosaicMethod::kBinCells, planes);
    ASSERT_EQ(planes.size(), m.band_map.size());
    const int pw = m.period_width, ph = m.period_height;
    ASSERT_EQ(planes[0].size(), cv::Size(1033 / pw, 1087 / ph));
    long mismatches = 0;
    for (int cy = 0; cy < planes[0].rows; ++cy)
      for (int cx = 0; cx < planes[0].cols; ++cx)
        for (int y = 0; y < ph; ++y)
          for (int x = 0; x < pw; ++x) {
            const float want = img.at<float>(cy * ph + y, cx * pw + x);
            const float got = planes[static_cast<std::size_t>(m.band_at(x, y))].at<float>(cy, cx);
            mismatches += !(got == want || (std::isnan(got) && std::isnan(want)));
          }
    EXPECT_EQ(mismatches, 0) << m.pattern;
  }
  const MosaicLayout bayer = MosaicLayout::bayer("GRBG");
  cv::Mat img(1024, 1030, CV_32F);
  cv::randu(img, 0, 200);
  std::vector<cv::Mat> planes;
  demosaic(img, bayer, DemosaicMethod::kBinCells, planes);
  for (int cy : {0, 300, 511})
    for (int cx : {0, 400, 514}) {
      const int y = 2 * cy, x = 2 * cx;
      EXPECT_EQ(planes[0].at<float>(cy, cx), img.at<float>(y, x + 1));
      EXPECT_EQ(planes[2].at<float>(cy, cx), img.at<float>(y + 1, x));
      EXPECT_FLOAT_EQ(planes[1].at<float>(cy, cx),
                      0.5f * (img.at<float>(y, x) + img.at<float>(y + 1, x + 1)));
    }
}

// How many readings one sample reaches: for matched Bayer the span of its kernels' footprints,
// squared; for snapshots matched reads each band from the 3x3 cells around, other methods bin.
TEST(Demosaic, sample_reach_follows_the_footprints) {
  const MosaicLayout bayer = MosaicLayout::bayer("RGGB");
  int span = 0;
  for (int band = 0; band < 3; ++band)
    for (int py = 0; py < 2; ++py)
      for (int px = 0; px < 2; ++px)
        for (const cv::Point& p : matched_footprint(bayer, band, px, py))
          span = std::max({span, std::abs(p.x), std::abs(p.y)});
  EXPECT_EQ(demosaic_sample_reach(bayer, DemosaicMethod::kMatched),
            (2 * span + 1) * (2 * span + 1));
  EXPECT_EQ(demosaic_sample_reach(bayer, DemosaicMethod::kAuto), (2 * span + 1) * (2 * span + 1));
  EXPECT_EQ(demosaic_sample_reach(bayer, DemosaicMethod::kBilinear), 9);
  EXPECT_EQ(demosaic_sample_reach(bayer, DemosaicMethod::kBinCells), 1);
  std::vector<int> map(25);
  std::iota(map.begin(), map.end(), 0);
  const MosaicLayout snapshot = MosaicLayout::snapshot(5, 5, map);
  EXPECT_EQ(demosaic_sample_reach(snapshot, DemosaicMethod::kMatched), 9);
  EXPECT_EQ(demosaic_sample_reach(snapshot, DemosaicMethod::kBilinear), 1);
  EXPECT_EQ(demosaic_sample_reach(snapshot, DemosaicMethod::kBinCells), 1);
}

TEST(Demosaic, noise_areas_follow_the_kernels) {
  const MosaicLayout bayer = MosaicLayout::bayer("RGGB");
  std::vector<int> map(25);
  std::iota(map.begin(), map.end(), 0);
  const MosaicLayout snapshot = MosaicLayout::snapshot(5, 5, map);
  // Binning shares nothing between cells.
  EXPECT_DOUBLE_EQ(demosaic_noise_area(bayer, DemosaicMethod::kBinCells), 1);
  EXPECT_DOUBLE_EQ(demosaic_noise_area(snapshot, DemosaicMethod::kBilinear), 1);
  // Matched Bayer kernels: each band's 1 / (density x mean squared weights), 13.85 for both R
  // (1/4 of the samples, 0.289) and G (1/2, 0.144); bilinear shares less, matched cells more
  // than none.
  EXPECT_NEAR(demosaic_noise_area(bayer, DemosaicMethod::kMatched), 13.85, 0.01);
  EXPECT_NEAR(demosaic_noise_area(bayer, DemosaicMethod::kBilinear), 10 / 1.75, 1e-9);
  EXPECT_GT(demosaic_noise_area(snapshot, DemosaicMethod::kMatched), 2);
  EXPECT_LT(demosaic_noise_area(snapshot, DemosaicMethod::kMatched), 9);
}

TEST(Demosaic, writes_into_caller_planes) {
  const MosaicLayout m = MosaicLayout::bayer("RGGB");
  std::vector<float> buffer(3 * 2 * 2, -1.f);
  std::vector<cv::Mat> planes;
  for (int b = 0; b < 3; ++b) planes.emplace_back(2, 2, CV_32F, buffer.data() + 4 * b);
  demosaic(ramp(m, 4, 4), m, DemosaicMethod::kBinCells, planes);
  EXPECT_EQ(planes[2].ptr<float>(), buffer.data() + 8);
  EXPECT_EQ(buffer[0], 0.f);    // R of the first cell: band 0 at (0,0)
  EXPECT_EQ(buffer[8], 211.f);  // B at (1,1)
}

TEST(Demosaic, rejects_wrong_input_n) {
  const MosaicLayout m = MosaicLayout::bayer("RGGB");
  std::vector<cv::Mat> planes;
  EXPECT_THROW(demosaic(cv::Mat(4, 4, CV_8U), m, DemosaicMethod::kBinCells, planes), InputError);
  EXPECT_THROW(demosaic(cv::Mat(1, 4, CV_32F), m, DemosaicMethod::kBinCells, planes), InputError);
  EXPECT_THROW(parse_demosaic_method("vng"), InputError);
}

TEST(Demosaic, large_frames_split_over_threads_give_the_same_result) {
  const MosaicLayout m = MosaicLayout::bayer("BGGR");
  cv::Mat img(520, 600, CV_32F);
  cv::randu(img, 0, 200);
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kBilinear, planes);
  // Against a direct evaluation at a few interior points.
  for (int y : {1, 259, 518})
    for (int x : {1, 300, 598}) {
      const float b = img.at<float>(y, x);
      if (m.band_at(x, y) == 1)
        EXPECT_EQ(planes[1].at<float>(y, x), b);
      else
        EXPECT_FLOAT_EQ(planes[1].at<float>(y, x),
                        0.25f * ((img.at<float>(y - 1, x) + img.at<float>(y + 1, x)) +
                                 (img.at<float>(y, x - 1) + img.at<float>(y, x + 1))));
    }
  // Matched: rows split over threads give the rows of small frames cut from the same mosaic.
  demosaic(img, m, DemosaicMethod::kMatched, planes, 20.f);
  for (int y0 : {100, 258}) {
    std::vector<cv::Mat> part;
    demosaic(img.rowRange(y0 - 4, y0 + 6).clone(), m, DemosaicMethod::kMatched, part, 20.f);
    for (int b = 0; b < 3; ++b)
      for (int x = 0; x < img.cols; ++x)
        EXPECT_EQ(planes[b].at<float>(y0, x), part[b].at<float>(4, x)) << b << " " << x;
  }
}

// Matched planes of 16 MiB and more are stored past the cache: the same values as the rows of
// small frames cut from the same mosaic (stored the usual way), saturated, missing and unlit
// samples included, at the odd row offsets the stores' alignment depends on.
TEST(Demosaic, matched_large_frames_stored_past_the_cache_give_the_rows_of_small_ones) {
  const MosaicLayout m = MosaicLayout::bayer("GRBG");
  cv::Mat img(1040, 1402, CV_32F);
  cv::randu(img, 0, 200);  // a tenth below the no-light level of 20
  for (int k = 0; k < 3000; ++k) {
    img.at<float>((k * 7919) % img.rows, (k * 104729) % img.cols) =
        k % 2 ? std::numeric_limits<float>::infinity() : std::numeric_limits<float>::quiet_NaN();
  }
  ASSERT_GE(3.0 * 4 * static_cast<double>(img.total()), 16.0 * 1024 * 1024);
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kMatched, planes, 20.f);
  for (int y0 : {6, 517, 1032}) {  // rows starting 16-byte aligned and not
    std::vector<cv::Mat> part;
    const int start = (y0 - 4) & ~1;  // an even row: the cut keeps the pattern
    demosaic(img.rowRange(start, start + 11).clone(), m, DemosaicMethod::kMatched, part, 20.f);
    for (int b = 0; b < 3; ++b)
      for (int x = 0; x < img.cols; ++x) {
        const float want = part[b].at<float>(y0 - start, x), got = planes[b].at<float>(y0, x);
        if (std::isnan(want))
          EXPECT_TRUE(std::isnan(got)) << b << " " << y0 << "," << x;
        else
          EXPECT_EQ(std::memcmp(&got, &want, sizeof got), 0) << b << " " << y0 << "," << x;
      }
  }
}

// Blocks of columns whose kernels reach only samples without light are written as dim without
// running the kernels. A NaN sample every 64 columns of every row has "light" (it is a mark),
// so every block of the second frame takes the kernels' path: away from the NaNs' reach both
// frames must give the same bits. Hot rectangles with unlit samples among them on a cold
// background, a small frame with an odd width and one large enough to be split and streamed.
TEST(Demosaic, matched_blocks_without_light_give_what_the_kernels_give) {
  for (const cv::Size size : {cv::Size(203, 40), cv::Size(1402, 1040)}) {
    const MosaicLayout m = MosaicLayout::bayer("GBRG");
    cv::Mat img(size, CV_32F);
    cv::randu(img, 0, 5);  // below the no-light level of 5: the cold background
    cv::RNG rng(11);
    for (int i = 0; i < 12; ++i) {
      const int w = rng.uniform(1, 90), h = rng.uniform(1, 30);
      cv::Mat hot =
          img(cv::Rect(rng.uniform(0, size.width - w), rng.uniform(0, size.height - h), w, h));
      cv::randu(hot, 0, 200);  // lit, with unlit samples among them
    }
    img.at<float>(size.height / 2, size.width / 3) = kInf;
    cv::Mat every_block_lit = img.clone();
    const auto near_a_nan = [](int x) { return x % 64 >= 28 && x % 64 <= 32; };
    for (int y = 0; y < size.height; ++y)
      for (int x = 30; x < size.width; x += 64) every_block_lit.at<float>(y, x) = std::nanf("");
    std::vector<cv::Mat> skipped, computed;
    demosaic(img, m, DemosaicMethod::kMatched, skipped, 5.f);
    demosaic(every_block_lit, m, DemosaicMethod::kMatched, computed, 5.f);
    long zeros = 0, compared = 0;
    for (int b = 0; b < 3; ++b)
      for (int y = 0; y < size.height; ++y)
        for (int x = 0; x < size.width; ++x) {
          if (near_a_nan(x)) continue;
          const float want = computed[b].at<float>(y, x), got = skipped[b].at<float>(y, x);
          ++compared, zeros += want == 0.f;
          if (std::isnan(want))
            EXPECT_TRUE(std::isnan(got)) << b << " " << y << "," << x;
          else
            ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << b << " " << y << "," << x;
        }
    EXPECT_GT(zeros, compared / 2) << size;  // most of the frame is cold background
  }
}

// The fused path's strips are the whole frame's rows bit for bit, at the frame's top and bottom
// (mirrored) and inside it, with an odd width, but for the blocks flagged without light, which
// are left unwritten: the frame's values there are 0 (and so every nonzero value is flagged).
TEST(Demosaic, matched_strips_are_the_frames_rows) {
  const MosaicLayout m = MosaicLayout::bayer("BGGR");
  cv::Mat img(61, 331, CV_32F);
  cv::randu(img, 0, 5);  // the cold background, below the no-light level of 5
  cv::Mat hot = img(cv::Rect(150, 20, 40, 9));
  cv::randu(hot, 0, 200);
  img.at<float>(22, 160) = kInf;
  img.at<float>(25, 170) = std::nanf("");
  std::vector<cv::Mat> frame;
  demosaic(img, m, DemosaicMethod::kMatched, frame, 5.f);
  const int blocks = matched_bayer_blocks(img.cols);
  ASSERT_EQ(blocks, (img.cols + kMatchedBlockColumns - 1) / kMatchedBlockColumns);
  std::vector<cv::Mat> strip;
  std::vector<std::uint8_t> lit;
  int unlit = 0;
  for (const auto& [y0, y1] : {std::pair{0, 7}, {7, 23}, {22, 30}, {30, 60}, {60, 61}, {0, 61}}) {
    for (cv::Mat& plane : strip) plane.setTo(-7);  // what the last strip left is not read
    demosaic_matched_bayer_rows(img, m, 5.f, y0, y1, strip, lit);
    ASSERT_EQ(strip.size(), 3u);
    ASSERT_EQ(lit.size(), static_cast<std::size_t>((y1 - y0) * blocks));
    for (int b = 0; b < 3; ++b)
      for (int y = y0; y < y1; ++y)
        for (int x = 0; x < img.cols; ++x) {
          const float want = frame[b].at<float>(y, x), got = strip[b].at<float>(y - y0, x);
          const bool block_lit = lit[(y - y0) * blocks + x / kMatchedBlockColumns] != 0;
          unlit += !block_lit;
          if (!block_lit) {
            EXPECT_EQ(want, 0.f) << b << " " << y << "," << x;
            continue;
          }
          if (std::isnan(want))
            EXPECT_TRUE(std::isnan(got)) << b << " " << y << "," << x;
          else
            ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << b << " " << y << "," << x;
        }
  }
  EXPECT_GT(unlit, 0);
  EXPECT_THROW(demosaic_matched_bayer_rows(img, m, 5.f, 5, 62, strip, lit), InputError);
  std::vector<int> map(25);
  std::iota(map.begin(), map.end(), 0);
  const MosaicLayout snapshot = MosaicLayout::snapshot(5, 5, map);
  EXPECT_THROW(demosaic_matched_bayer_rows(img, snapshot, 5.f, 0, 5, strip, lit), InputError);
}

// Strips taken one after another from one MatchedBayerRows (the rows its kernels reach carried
// from strip to strip) are the frame's rows bit for bit, as are strips after a jump back or
// ahead (the rows then read afresh); each block's flag follows its rule.
TEST(Demosaic, matched_strips_in_sequence_are_the_frames_rows) {
  const MosaicLayout m = MosaicLayout::bayer("GRBG");
  cv::Mat img(70, 203, CV_32F);
  cv::randu(img, 0, 5);  // below the no-light level
  cv::Mat hot = img(cv::Rect(20, 3, 150, 60));
  cv::randu(hot, 0, 250);
  img.at<float>(30, 60) = kInf;
  img.at<float>(66, 202) = 100;  // light at the right edge (its padding) ...
  img.at<float>(69, 1) = 100;    // ... and at the left one
  img.at<float>(68, 62) = 100;   // in the first pair of the second block (of padded columns)
  std::vector<cv::Mat> frame;
  demosaic(img, m, DemosaicMethod::kMatched, frame, 5.f);
  const int blocks = matched_bayer_blocks(img.cols);
  // A block is lit where a sample in the rows and columns its kernels can reach has light: two
  // rows each way, from two columns left of the block to the end of the next block (mirrored
  // without repeating the edge).
  auto lit_by_rule = [&](int y, int block) {
    for (int yy = y - 2; yy <= y + 2; ++yy)
      for (int x = block * kMatchedBlockColumns - 2; x < (block + 2) * kMatchedBlockColumns - 2;
           ++x) {
        if (x > img.cols + 1) break;
        const float v = img.at<float>(cv::borderInterpolate(yy, img.rows, cv::BORDER_REFLECT_101),
                                      cv::borderInterpolate(x, img.cols, cv::BORDER_REFLECT_101));
        if (!(v < 5.f)) return true;
      }
    return false;
  };
  MatchedBayerRows rows(img, m, 5.f);
  std::vector<cv::Mat> strip;
  std::vector<std::uint8_t> lit;
  int compared = 0;
  for (const auto& [y0, y1] : {std::pair{0, 16},
                               {16, 32},
                               {32, 33},
                               {33, 50},
                               {10, 26},
                               {26, 40},
                               {60, 70},
                               {50, 60},
                               {60, 70}}) {
    for (cv::Mat& plane : strip) plane.setTo(-7);
    rows.rows(y0, y1, strip, lit);
    for (int y = y0; y < y1; ++y)
      for (int k = 0; k < blocks; ++k)
        EXPECT_EQ(lit[(y - y0) * blocks + k] != 0, lit_by_rule(y, k)) << y << " " << k;
    for (int b = 0; b < 3; ++b)
      for (int y = y0; y < y1; ++y)
        for (int x = 0; x < img.cols; ++x) {
          if (lit[(y - y0) * blocks + x / kMatchedBlockColumns] == 0) continue;
          const float want = frame[b].at<float>(y, x), got = strip[b].at<float>(y - y0, x);
          ++compared;
          if (std::isnan(want))
            EXPECT_TRUE(std::isnan(got)) << b << " " << y << "," << x;
          else
            ASSERT_EQ(std::memcmp(&got, &want, sizeof got), 0) << b << " " << y << "," << x;
        }
  }
  EXPECT_GT(compared, 3 * 150 * 60);
  EXPECT_THROW(rows.rows(60, 71, strip, lit), InputError);
}

// The fused pass (each block of rows checked as it is demosaicked, on the threads) marks what
// the separate one marks: bit for bit, on a frame large enough to be split, with an odd width,
// plates with sharp edges, saturated samples and a dim background left out by the skip level.
TEST(Demosaic, marking_mixed_pixels_while_demosaicking_gives_the_separate_passes_result) {
  cv::Mat img(530, 611, CV_32F);
  cv::randn(img, 0, 1.5);
  cv::RNG rng(7);
  for (int i = 0; i < 40; ++i) {
    const int x = rng.uniform(0, 560), y = rng.uniform(0, 480), w = rng.uniform(3, 50);
    const cv::Mat block = img(cv::Rect(x, y, w, rng.uniform(3, 50)));
    block += cv::Scalar(rng.uniform(10.0, 200.0));  // hot objects, some overlapping
  }
  for (int i = 0; i < 200; ++i) img.at<float>(rng.uniform(0, 530), rng.uniform(0, 611)) = kInf;
  FootprintCheck check;
  check.noise = {{0.03, 0.23}, {0.06, 0.43}, {0.12, 1.2}};
  check.skip_below_dn = 20;
  for (const char* pattern : {"RGGB", "GBRG"})
    for (DemosaicMethod method :
         {DemosaicMethod::kBilinear, DemosaicMethod::kMatched, DemosaicMethod::kBinCells}) {
      const MosaicLayout m = MosaicLayout::bayer(pattern);
      std::vector<cv::Mat> separate, fused;
      demosaic(img, m, method, separate, 5.5f);
      const std::size_t marked = mark_mixed_pixels(img, m, method, check, separate);
      EXPECT_GT(marked, 100u) << pattern;
      EXPECT_EQ(demosaic_marking_mixed(img, m, method, check, fused, 5.5f), marked) << pattern;
      for (int b = 0; b < 3; ++b) {
        cv::Mat differ;
        // NaN == NaN is false: compare the marks, then the values elsewhere.
        cv::compare(separate[b] != separate[b], fused[b] != fused[b], differ, cv::CMP_NE);
        EXPECT_EQ(cv::countNonZero(differ), 0) << pattern << " band " << b;
        cv::patchNaNs(separate[b], -1);
        cv::patchNaNs(fused[b], -1);
        cv::compare(separate[b], fused[b], differ, cv::CMP_NE);
        EXPECT_EQ(cv::countNonZero(differ), 0) << pattern << " band " << b;
      }
    }
}

// A mosaic whose band b reads 100 b + q(x, y), with q quadratic: each band's kernel mean is
// q + its first moments . grad q + (Mxx qxx + Myy qyy) / 2 + Mxy qxy.
cv::Mat bowl(const MosaicLayout& m, int w, int h) {
  cv::Mat img(h, w, CV_32F);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img.at<float>(y, x) = 100.f * m.band_at(x, y) + 0.5f * (x - 6.f) * (x - 6.f) +
                            0.25f * (y - 5.f) * (y - 5.f) + 0.1f * (x - 6.f) * (y - 5.f) + x;
  return img;
}

TEST(Demosaic, matched_gives_every_band_the_same_offset_on_a_curved_signal) {
  for (const char* p : {"RGGB", "BGGR", "GRBG", "GBRG"}) {
    const MosaicLayout m = MosaicLayout::bayer(p);
    std::vector<cv::Mat> planes;
    demosaic(bowl(m, 12, 10), m, DemosaicMethod::kMatched, planes);
    ASSERT_EQ(planes.size(), 3u);
    ASSERT_EQ(planes[0].size(), cv::Size(12, 10));
    for (int b = 0; b < 3; ++b)
      for (int y = 2; y < 8; ++y)
        for (int x = 2; x < 10; ++x) {
          // Moments 1 along x and y, none across or first-order: + (0.5 * 2 + 0.25 * 2) / 2.
          const float q = 0.5f * (x - 6.f) * (x - 6.f) + 0.25f * (y - 5.f) * (y - 5.f) +
                          0.1f * (x - 6.f) * (y - 5.f) + x;
          EXPECT_NEAR(planes[b].at<float>(y, x), 100.f * b + q + 0.75f, 1e-3)
              << p << " band " << b << " at " << x << "," << y;
        }
  }
}

TEST(Demosaic, matched_keeps_the_pattern_at_the_borders) {
  // One level per band: every kernel reads its band's level, borders included (mirrored).
  for (const char* p : {"RGGB", "GBRG"}) {
    const MosaicLayout m = MosaicLayout::bayer(p);
    cv::Mat img(7, 9, CV_32F);  // odd sizes: the last row and column have the other parity
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) img.at<float>(y, x) = 10.f + 7.f * m.band_at(x, y);
    std::vector<cv::Mat> planes;
    demosaic(img, m, DemosaicMethod::kMatched, planes);
    for (int b = 0; b < 3; ++b)
      for (int y = 0; y < img.rows; ++y)
        for (int x = 0; x < img.cols; ++x)
          EXPECT_FLOAT_EQ(planes[b].at<float>(y, x), 10.f + 7.f * b) << p << " " << x << "," << y;
  }
}

TEST(Demosaic, matched_marks_saturation_nan_and_samples_without_light) {
  const MosaicLayout m = MosaicLayout::bayer("RGGB");
  cv::Mat img(10, 10, CV_32F, cv::Scalar(50));
  img.at<float>(4, 4) = kInf;           // an R pixel
  img.at<float>(4, 7) = std::nanf("");  // a G pixel
  img.at<float>(8, 1) = 0.5f;           // a G pixel without light
  std::vector<cv::Mat> planes;
  demosaic(img, m, DemosaicMethod::kMatched, planes, 2.f);
  EXPECT_EQ(planes[0].at<float>(4, 4), kInf);  // R at itself
  EXPECT_EQ(planes[0].at<float>(6, 4), kInf);  // R at the R pixel 2 below (its axial kernel)
  EXPECT_EQ(planes[1].at<float>(4, 4), 50.f);  // G never draws on an R sample
  EXPECT_TRUE(std::isnan(planes[1].at<float>(4, 7)));
  EXPECT_TRUE(std::isnan(planes[1].at<float>(5, 8)));  // G at a diagonal of the NaN G
  EXPECT_EQ(planes[1].at<float>(8, 1), 0.f);   // dim: a band drawn from a sample without light
  EXPECT_EQ(planes[1].at<float>(8, 2), 0.f);   // G at the R pixel next to it
  EXPECT_EQ(planes[0].at<float>(8, 1), 50.f);  // R and B do not draw on it
  EXPECT_EQ(planes[2].at<float>(8, 1), 50.f);
  // Without the level the same sample is averaged in.
  demosaic(img, m, DemosaicMethod::kMatched, planes);
  EXPECT_GT(planes[1].at<float>(8, 2), 30.f);
  // A kernel with both a saturated sample and one without light: no reading.
  img.at<float>(6, 6) = kInf;
  img.at<float>(6, 8) = 0.f;
  demosaic(img, m, DemosaicMethod::kMatched, planes, 2.f);
  EXPECT_TRUE(std::isnan(planes[0].at<float>(6, 7)));  // R at G (6,7): both R neighbours
}

TEST(Demosaic, matched_footprint_is_the_kernel_samples_of_the_band) {
  const MosaicLayout m = MosaicLayout::bayer("RGGB");
  for (int py = 0; py < 2; ++py)
    for (int px = 0; px < 2; ++px)
      for (int b = 0; b < 3; ++b) {
        // A mosaic with one sample changed changes band b at the pixel exactly when the sample
        // is in the footprint (and of band b).
        const auto footprint = matched_footprint(m, b, px, py);
        for (int dy = -2; dy <= 2; ++dy)
          for (int dx = -2; dx <= 2; ++dx) {
            cv::Mat img(10, 10, CV_32F, cv::Scalar(40));
            img.at<float>(4 + py + dy, 4 + px + dx) = 80.f;
            std::vector<cv::Mat> planes;
            demosaic(img, m, DemosaicMethod::kMatched, planes);
            const bool in =
                std::find(footprint.begin(), footprint.end(), cv::Point(dx, dy)) != footprint.end();
            EXPECT_EQ(planes[b].at<float>(4 + py, 4 + px) != 40.f, in)
                << b << " at parity " << px << "," << py << " sample " << dx << "," << dy;
            if (in) {
              EXPECT_EQ(m.band_at(4 + px + dx, 4 + py + dy), b);
            }
          }
      }
}

TEST(Demosaic, matched_reads_every_snapshot_band_at_the_cell_centre) {
  // The same linear ramp under every band: binned, each band reads it where it sits in the
  // cell; matched, every band reads it at the cell's centre (zero first moment), marks spread
  // over the 3x3 cells around.
  std::vector<int> identity(25);
  std::iota(identity.begin(), identity.end(), 0);
  const MosaicLayout m = MosaicLayout::snapshot(5, 5, identity);
  cv::Mat img(30, 35, CV_32F);
  for (int y = 0; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) img.at<float>(y, x) = 30.f + 0.5f * x + 0.25f * y;
  std::vector<cv::Mat> binned, matched;
  demosaic(img, m, DemosaicMethod::kBinCells, binned);
  demosaic(img, m, DemosaicMethod::kMatched, matched);
  ASSERT_EQ(matched.size(), 25u);
  ASSERT_EQ(matched[0].size(), cv::Size(7, 6));
  for (int b = 0; b < 25; ++b)
    for (int cy = 1; cy < 5; ++cy)
      for (int cx = 1; cx < 6; ++cx) {
        EXPECT_FLOAT_EQ(binned[b].at<float>(cy, cx),
                        30.f + 0.5f * (5 * cx + b % 5) + 0.25f * (5 * cy + b / 5));
        EXPECT_NEAR(matched[b].at<float>(cy, cx), 30.f + 0.5f * (5 * cx + 2) + 0.25f * (5 * cy + 2),
                    1e-4)
            << "band " << b << " cell " << cx << "," << cy;
      }
  img.at<float>(12, 13) = kInf;  // band 2 * 5 + 3 of cell (2, 2)
  img.at<float>(22, 5) = 1.f;    // band 2 * 5 + 0 of cell (1, 4), without light
  demosaic(img, m, DemosaicMethod::kMatched, matched, 5.f);
  for (int cy = 0; cy < 6; ++cy)
    for (int cx = 0; cx < 7; ++cx) {
      const bool near_inf = std::abs(cx - 2) <= 1 && std::abs(cy - 2) <= 1;
      EXPECT_EQ(matched[13].at<float>(cy, cx) == kInf, near_inf) << cx << "," << cy;
      const bool near_dark = std::abs(cx - 1) <= 1 && std::abs(cy - 4) <= 1;
      EXPECT_EQ(matched[10].at<float>(cy, cx) == 0.f, near_dark) << cx << "," << cy;
      EXPECT_TRUE(std::isfinite(matched[12].at<float>(cy, cx)));  // other bands untouched
    }
}

}  // namespace
}  // namespace pyrocam
