// Region statistics of a temperature image: median, extremes, mean and valid fraction in a mask.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/runtime/region_stats.h"

namespace pyrocam {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

TEST(RegionStats, median_min_max_mean_and_valid_fraction_inside_a_mask) {
  const cv::Mat t = (cv::Mat_<float>(2, 4) << 1000, 1010, kNaN, 990, 2000, 5, 1020, kNaN);
  const cv::Mat mask = (cv::Mat_<std::uint8_t>(2, 4) << 1, 1, 1, 1, 0, 0, 1, 1);
  const RegionStats s = region_stats(t, mask);
  EXPECT_EQ(s.pixels, 6u);
  EXPECT_EQ(s.valid, 4u);
  EXPECT_DOUBLE_EQ(s.valid_fraction, 4.0 / 6.0);
  EXPECT_DOUBLE_EQ(s.min_c, 990);
  EXPECT_DOUBLE_EQ(s.max_c, 1020);
  EXPECT_DOUBLE_EQ(s.mean_c, 1005);
  EXPECT_DOUBLE_EQ(s.median_c, 1005);  // even count: mean of the middle two
  const RegionStats all = region_stats(t);
  EXPECT_EQ(all.pixels, 8u);
  EXPECT_DOUBLE_EQ(all.median_c, 1005);  // 5, 990, 1000, 1010, 1020, 2000
  EXPECT_DOUBLE_EQ(all.max_c, 2000);
  const RegionStats none = region_stats(cv::Mat(2, 2, CV_32F, cv::Scalar(kNaN)));
  EXPECT_EQ(none.valid, 0u);
  EXPECT_TRUE(std::isnan(none.median_c));
}

// The definition, window by window: the reference the fast search must match.
double naive_window_median(const cv::Mat& t, int w, const cv::Mat& mask, int cx, int cy) {
  std::vector<float> v;
  const int h = w / 2;
  for (int y = std::max(0, cy - h); y <= std::min(t.rows - 1, cy + h); ++y)
    for (int x = std::max(0, cx - h); x <= std::min(t.cols - 1, cx + h); ++x)
      if (std::isfinite(t.at<float>(y, x)) && (mask.empty() || mask.at<std::uint8_t>(y, x)))
        v.push_back(t.at<float>(y, x));
  if (2 * static_cast<int>(v.size()) < w * w) return kNaN;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (static_cast<double>(v[n / 2 - 1]) + v[n / 2]);
}

// The definition: windows wholly inside the image.
RegionPeak naive_peak(const cv::Mat& t, int w, const cv::Mat& mask = cv::Mat()) {
  RegionPeak best;
  for (int cy = w / 2; cy < t.rows - w / 2; ++cy)
    for (int cx = w / 2; cx < t.cols - w / 2; ++cx) {
      const double m = naive_window_median(t, w, mask, cx, cy);
      if (!std::isnan(m) && (!best.found() || m > best.c)) best = {m, cx, cy};
    }
  return best;
}

cv::Mat noisy_plate(int width, int height, float plate_c, float noise_c, unsigned seed) {
  cv::Mat t(height, width, CV_32F);
  cv::RNG rng(seed);
  rng.fill(t, cv::RNG::NORMAL, plate_c, noise_c);
  return t;
}

TEST(RegionPeak, wild_edge_pixels_do_not_make_the_peak) {
  cv::Mat t(80, 100, CV_32F, cv::Scalar(kNaN));
  noisy_plate(60, 40, 735, 2, 1).copyTo(t(cv::Rect(20, 20, 60, 40)));
  // Mixed pixels along the plate's edges: single wild readings, hot and cold.
  for (int x : {20, 33, 50, 79}) t.at<float>(20, x) = 2500;
  for (int y : {25, 40, 59}) t.at<float>(y, 79) = 2283;
  t.at<float>(59, 40) = 503;
  t.at<float>(19, 50) = 2500;  // a stray reading outside the plate
  const RegionStats s = region_stats(t);
  EXPECT_DOUBLE_EQ(s.max_c, 2500);
  const RegionPeak p = region_peak(t);
  ASSERT_TRUE(p.found());
  EXPECT_NEAR(p.c, 735, 3);
  EXPECT_GE(p.x, 20);
  EXPECT_LT(p.x, 80);
  EXPECT_GE(p.y, 20);
  EXPECT_LT(p.y, 60);
}

TEST(RegionPeak, finds_a_hot_spot_where_it_is) {
  cv::Mat t = noisy_plate(120, 90, 1000, 3, 2);
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x)
      t.at<float>(y, x) += 800.0f * std::exp(-((x - 37) * (x - 37) + (y - 61) * (y - 61)) / 32.0f);
  t.at<float>(5, 100) = 3000;  // an outlier hotter than the spot
  const RegionPeak p = region_peak(t, 5);
  ASSERT_TRUE(p.found());
  EXPECT_LE(std::abs(p.x - 37), 1);
  EXPECT_LE(std::abs(p.y - 61), 1);
  // The 13th-nearest of 25 pixels lies 2 px from the centre: 1000 + 800 exp(-4 / 32).
  EXPECT_NEAR(p.c, 1706, 15);
  const RegionPeak one = region_peak(t, 1);  // a 1-pixel window is the hottest pixel
  EXPECT_EQ(one.x, 100);
  EXPECT_EQ(one.y, 5);
  EXPECT_DOUBLE_EQ(one.c, 3000);
}

// Windows cut by the image's edge hold fewer readings: with two hot columns at the edge, a
// window centred on the edge (15 pixels, 10 hot) had a hot median where no window inside the
// image has (10 hot of 25). The peak comes from windows wholly inside.
TEST(RegionPeak, windows_cut_by_the_edge_do_not_count) {
  cv::Mat t(20, 20, CV_32F, cv::Scalar(1000));
  t(cv::Rect(0, 0, 2, 20)) = 1100;
  const RegionPeak p = region_peak(t, 5);
  ASSERT_TRUE(p.found());
  EXPECT_DOUBLE_EQ(p.c, 1000);
  EXPECT_GE(p.x, 2);
  EXPECT_GE(p.y, 2);
  EXPECT_LE(p.y, 17);
}

TEST(RegionPeak, windows_with_under_half_their_pixels_valid_do_not_count) {
  cv::Mat t(40, 40, CV_32F, cv::Scalar(kNaN));
  t(cv::Rect(2, 2, 3, 3)) = 2000;    // 9 readings: under half of 25 in any window
  t(cv::Rect(20, 10, 4, 4)) = 1200;  // 16 readings: windows over most of it count
  RegionPeak p = region_peak(t);
  EXPECT_DOUBLE_EQ(p.c, 1200);
  EXPECT_GE(p.x, 20);
  EXPECT_LE(p.x, 23);
  p = region_peak(t, 3);  // 3 x 3: the small block counts now
  EXPECT_DOUBLE_EQ(p.c, 2000);
  EXPECT_LE(std::abs(p.x - 3), 1);  // 2000 in any window holding 5 of the 9
  EXPECT_LE(std::abs(p.y - 3), 1);
  // A mask leaving the block under half of its window: no peak.
  cv::Mat mask(t.size(), CV_8U, cv::Scalar(0));
  mask(cv::Rect(20, 10, 2, 4)) = 1;
  p = region_peak(t, 5, mask);
  EXPECT_FALSE(p.found());
  EXPECT_TRUE(std::isnan(p.c));
  EXPECT_FALSE(region_peak(cv::Mat(9, 9, CV_32F, cv::Scalar(kNaN))).found());
}

TEST(RegionPeak, window_must_be_odd_positive_and_fit_in_the_image) {
  const cv::Mat t(20, 30, CV_32F, cv::Scalar(900));
  EXPECT_THROW(region_peak(t, 4), InputError);
  EXPECT_THROW(region_peak(t, 0), InputError);
  EXPECT_THROW(region_peak(t, -3), InputError);
  EXPECT_THROW(region_peak(t, 21), InputError);  // taller than the image
  EXPECT_THROW(region_peak(cv::Mat(300, 300, CV_32F, cv::Scalar(900)), 257), InputError);
  EXPECT_THROW(region_peak(cv::Mat(20, 30, CV_64F, cv::Scalar(900))), InputError);
  EXPECT_THROW(region_peak(t, 5, cv::Mat(20, 29, CV_8U, cv::Scalar(1))), InputError);
  const RegionPeak p = region_peak(t, 19);
  EXPECT_DOUBLE_EQ(p.c, 900);
}

TEST(RegionPeak, matches_the_window_by_window_definition) {
  cv::RNG rng(7);
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 1 + 2 * (trial % 4);
    cv::Mat t = noisy_plate(37 + trial, 23 + trial % 5, 1000, trial % 2 ? 50 : 0.5f, trial);
    for (int i = 0; i < t.rows * t.cols * 3 / 10; ++i)  // holes and wild pixels
      t.at<float>(rng.uniform(0, t.rows), rng.uniform(0, t.cols)) = i % 7 ? kNaN : 2500;
    cv::Mat mask;
    if (trial % 3 == 0) {
      mask = cv::Mat(t.size(), CV_8U, cv::Scalar(1));
      mask(cv::Rect(0, 0, t.cols / 2, t.rows)) = 0;
    }
    const RegionPeak want = naive_peak(t, w, mask), got = region_peak(t, w, mask);
    ASSERT_EQ(got.found(), want.found()) << trial;
    if (!want.found()) continue;
    EXPECT_DOUBLE_EQ(got.c, want.c) << trial;
    // Ties may pick another window of the same median.
    EXPECT_DOUBLE_EQ(naive_window_median(t, w, mask, got.x, got.y), want.c) << trial;
  }
  // A large noisy plate: many windows could beat the first guesses (the sampling rounds).
  const cv::Mat plate = noisy_plate(400, 300, 735, 5, 11);
  EXPECT_DOUBLE_EQ(region_peak(plate).c, naive_peak(plate, 5).c);
}

// Cost on a camera-sized frame: run with --gtest_also_run_disabled_tests.
// Where light saturated a band: +INF in any plane, or NaN within 2 pixels of one (not -INF,
// demosaicking's mark of a sample without light), or within the kernels' reach of such a mosaic
// sample; counted only where the pixel has no reading.
TEST(Saturation, marks_unread_band_values_and_counts_pixels_without_a_reading_there) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  cv::Mat red(3, 4, CV_32F, cv::Scalar(100)), green = red.clone();
  red.at<float>(0, 1) = kInf;
  green.at<float>(2, 3) = kNaN;
  green.at<float>(1, 0) = -kInf;
  const cv::Mat mask = saturated_band_mask({red, green});
  EXPECT_EQ(cv::countNonZero(mask), 2);
  EXPECT_EQ(mask.at<std::uint8_t>(0, 1), 1);
  EXPECT_EQ(mask.at<std::uint8_t>(2, 3), 1);
  EXPECT_EQ(mask.at<std::uint8_t>(1, 0), 0);
  cv::Mat t(3, 4, CV_32F, cv::Scalar(1500));
  t.at<float>(0, 1) = kNaN;                       // saturated, no reading: counts
  t.at<float>(1, 1) = kNaN;                       // no reading, nothing saturated: does not
  EXPECT_EQ(count_without_reading(t, mask), 1u);  // (2, 3) has a reading: does not
  // A NaN more than 2 pixels from any saturated one (a mixed pixel at an edge) is no saturation;
  // without any +INF, no NaN is.
  cv::Mat wide_red(6, 9, CV_32F, cv::Scalar(100)), wide_green = wide_red.clone();
  wide_red.at<float>(0, 0) = kInf;
  wide_green.at<float>(2, 2) = kNaN;  // within reach
  wide_green.at<float>(5, 8) = kNaN;  // beyond it
  const cv::Mat wide = saturated_band_mask({wide_red, wide_green});
  EXPECT_EQ(cv::countNonZero(wide), 2);
  EXPECT_EQ(wide.at<std::uint8_t>(2, 2), 1);
  EXPECT_EQ(wide.at<std::uint8_t>(5, 8), 0);
  wide_red.at<float>(0, 0) = 100;
  EXPECT_EQ(cv::countNonZero(saturated_band_mask({wide_red, wide_green})), 0);
  EXPECT_THROW(saturated_band_mask({}), InputError);
  EXPECT_THROW(saturated_band_mask({red, cv::Mat(2, 4, CV_32F)}), InputError);
  EXPECT_THROW(count_without_reading(t, cv::Mat(2, 4, CV_8U)), InputError);

  cv::Mat mosaic(8, 9, CV_32F, cv::Scalar(50));
  mosaic.at<float>(5, 3) = kInf;
  mosaic.at<float>(0, 8) = kNaN;
  const cv::Mat reach = saturated_sample_mask(mosaic, 2);
  EXPECT_EQ(cv::countNonZero(reach), 25 + 3 * 3);  // the corner's square clipped to 3x3
  EXPECT_EQ(reach.at<std::uint8_t>(3, 1), 1);
  EXPECT_EQ(reach.at<std::uint8_t>(7, 5), 1);
  EXPECT_EQ(reach.at<std::uint8_t>(2, 3), 0);
  EXPECT_EQ(cv::countNonZero(saturated_sample_mask(mosaic, 0)), 2);
  EXPECT_THROW(saturated_sample_mask(mosaic, -1), InputError);
}

TEST(RegionPeak, DISABLED_timing_2048x2048) {
  cv::Mat t = noisy_plate(2048, 2048, 735, 5, 3);
  for (int i = 0; i < 4000; ++i) t.at<float>((i * 7919) % 2048, (i * 104729) % 2048) = 2500;
  cv::circle(t, cv::Point(1200, 900), 20, cv::Scalar(1800), -1);
  for (int run = 0; run < 3; ++run) {
    const auto start = std::chrono::steady_clock::now();
    const RegionPeak p = region_peak(t);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::printf("region_peak 2048x2048, window 5: %.1f ms (peak %.1f at %d,%d)\n", ms, p.c, p.x,
                p.y);
    EXPECT_NEAR(p.c, 1800, 1);
  }
  const cv::Mat plate = noisy_plate(2048, 2048, 735, 5, 4);
  const auto start = std::chrono::steady_clock::now();
  const RegionPeak p = region_peak(plate);
  std::printf(
      "region_peak 2048x2048 noisy plate: %.1f ms (peak %.1f)\n",
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count(),
      p.c);
}

// The median's noise: independent readings as the median of independent normal values, one
// reading as itself, readings that share their noise in between, and a region's share falling
// as one over its readings once it is much larger than the footprint.
TEST(RegionStats, median_noise_share_counts_what_the_readings_share) {
  cv::Mat used = cv::Mat::zeros(200, 200, CV_8U);
  EXPECT_TRUE(std::isnan(median_noise_share(used, 13.9)));
  used.at<std::uint8_t>(50, 50) = 1;
  EXPECT_DOUBLE_EQ(median_noise_share(used, 13.9), 1);
  // Two neighbours: their mean, of noise they partly share.
  used.at<std::uint8_t>(50, 51) = 1;
  const double pair = median_noise_share(used, 13.9);
  EXPECT_GT(pair, 0.5);
  EXPECT_LT(pair, 1);
  // Far apart: independent.
  used.at<std::uint8_t>(50, 51) = 0;
  used.at<std::uint8_t>(50, 150) = used.at<std::uint8_t>(150, 50) = 1;
  EXPECT_NEAR(median_noise_share(used, 13.9), M_PI / 2 / 3, 1e-6);
  // Unshared noise: the median of independent readings.
  used.setTo(0);
  used(cv::Rect(20, 20, 160, 160)) = 1;
  EXPECT_NEAR(median_noise_share(used, 1), M_PI / 2 / (160 * 160), 1e-12);
  // Shared: more than independent readings, less than a footprint's area of them as one.
  const double large = median_noise_share(used, 13.9);
  EXPECT_GT(large, M_PI / 2 / (160 * 160));
  EXPECT_LT(large, M_PI / 2 * 13.9 / (160 * 160));
  // Much larger than the footprint: the share per reading hardly depends on the size.
  cv::Mat smaller = cv::Mat::zeros(200, 200, CV_8U);
  smaller(cv::Rect(40, 40, 120, 120)) = 1;
  EXPECT_NEAR(median_noise_share(smaller, 13.9) * 120 * 120, large * 160 * 160,
              0.05 * large * 160 * 160);
  EXPECT_THROW(median_noise_share(used, 0.5), InputError);
  EXPECT_THROW(median_noise_share(cv::Mat::zeros(4, 4, CV_32F), 2), InputError);
}

}  // namespace
}  // namespace pyrocam
