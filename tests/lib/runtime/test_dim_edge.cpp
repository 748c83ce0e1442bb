// The dim threshold as an edge: on a surface whose band sits near it, the pixels that read must
// not be those whose own noise lifted that band (their readings would lean one way).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <vector>

#include "plate_readings.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/dim_edge.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

// A 1200 degC plate on the simulated colour camera (its true QE, the likelihood fit), exposed
// so that blue, its dimmest band, sits at a given mean: from below the 20 DN threshold to a few
// of its noise's standard deviations (2 DN raw, 1.1 DN after matched demosaicking) above it.
// Before the check, 22 % of the plate read 48 degC low with blue at 19.2 DN and 76 % read 10 degC
// low at 20.8 DN. Now a plate reads on under 5 % of its pixels (1.6 % at 21 DN, 9 degC low on
// average) or on most, within 5 degC: the
// median of about 2 x 13000 readings of 35 degC spread, neighbours sharing samples (about 14
// readings a sample), has a standard error near 1 degC; the model's own bias is under 1 degC.
TEST(DimEdge, a_plate_at_the_dim_threshold_reads_on_none_or_without_lean) {
  TrueQeColourPlate p;
  constexpr double kTruthC = TrueQeColourPlate::kTruthC;
  const double reference_us = 20;
  const double blue_dn = p.camera.mean_signal_dn(kTruthC, reference_us)[2];
  double most_read = 0, least_read = 1;
  for (const double blue_target : {19.0, 20.0, 21.0, 22.0, 23.0, 24.0, 26.0}) {
    const double exposure = reference_us * blue_target / blue_dn;
    const PlateReadings plate = measure_plate(p.measurer, p.camera, p.truth, kTruthC, exposure);
    const double read = plate.read, median = plate.median;
    most_read = std::max(most_read, read);
    least_read = std::min(least_read, read);
    std::printf("blue %.0f DN: %.1f %% read, median error %.2f degC\n", blue_target, 100 * read,
                median);
    if (read >= 0.05) {
      EXPECT_LE(std::abs(median), 5.0) << "blue at " << blue_target << " DN";
    }
  }
  EXPECT_LT(least_read, 0.05) << "no exposure left the plate without readings: not at the edge";
  EXPECT_GT(most_read, 0.9) << "no exposure read the plate";
}

// The check's thresholds follow the noise model: 2 and 6 standard deviations of a band value
// after demosaicking above the dim threshold, wider with analogue gain.
TEST(DimEdge, thresholds_follow_the_noise_model) {
  const CameraProfile profile = load_profile_by_name("rgb-reference");
  const DemosaicNoise matched = demosaic_noise(profile.mosaic, DemosaicMethod::kMatched);
  const DimEdgeCheck check(profile, 1.0, matched), gained(profile, 4.0, matched);
  const double dim = profile.thresholds.inference_dim_dn;
  for (int b = 0; b < 3; ++b) {
    double factor = 0;
    for (int phase = 0; phase < 4; ++phase)
      factor = std::max(factor, matched.factor[static_cast<std::size_t>(phase * 3 + b)]);
    const double sd = std::sqrt(signal_variance_dn2(profile, b, dim) * factor);
    EXPECT_NEAR(check.accept_dn(b), dim + 2 * sd, 1e-4) << b;
    EXPECT_NEAR(check.checked_dn(b), dim + 6 * sd, 1e-4) << b;
    EXPECT_GT(gained.accept_dn(b), check.accept_dn(b)) << b;
  }
}

// The ring's halves: at an edge, the half inside the body decides; the pixels of the span it
// goes around never count.
TEST(DimEdge, the_rings_largest_half_sees_inside_a_body) {
  const DimEdgeCheck::Ring ring{5, 6};
  cv::Mat alone(31, 31, CV_32F, cv::Scalar(0));
  alone.at<float>(15, 15) = 1000;  // the pixel's own value is not in its ring
  EXPECT_FLOAT_EQ(plane_ring_mean(alone, 15, 15, 15, ring), 0);
  cv::Mat plane(31, 31, CV_32F, cv::Scalar(0));
  plane(cv::Rect(15, 0, 16, 31)).setTo(30);                       // lit from column 15 on
  EXPECT_FLOAT_EQ(plane_ring_mean(plane, 16, 16, 15, ring), 30);  // inside, by the edge: its right
  EXPECT_FLOAT_EQ(plane_ring_mean(plane, 5, 5, 15, ring), 0);     // its ring ends before the edge
  // A value without a reading counts as no light; a saturated one is brighter than any.
  cv::Mat even(31, 31, CV_32F, cv::Scalar(30));
  even(cv::Rect(0, 0, 31, 31)).setTo(NAN);
  EXPECT_FLOAT_EQ(plane_ring_mean(even, 16, 16, 15, ring), 0);
  even.at<float>(15, 21) = INFINITY;  // in the right half
  EXPECT_EQ(plane_ring_mean(even, 16, 16, 15, ring), INFINITY);
  // A span's ring goes around all its pixels: none of their values is in it.
  cv::Mat span(31, 31, CV_32F, cv::Scalar(0));
  span(cv::Rect(12, 15, 8, 1)).setTo(1000);  // columns 12 .. 19 of row 15
  EXPECT_FLOAT_EQ(plane_ring_mean(span, 12, 19, 15, ring), 0);
  EXPECT_GT(plane_ring_mean(span, 12, 14, 15, ring), 0);  // columns 19, 20: 5 and 6 away
  cv::Mat mosaic(31, 31, CV_32F, cv::Scalar(0));
  const MosaicLayout rggb = MosaicLayout::bayer("RGGB");
  for (int y = 0; y < 31; ++y)
    for (int x = 0; x < 31; ++x) mosaic.at<float>(y, x) = static_cast<float>(rggb.band_at(x, y));
  // Each band's ring mean is that band's own samples only.
  for (int b = 0; b < 3; ++b)
    EXPECT_FLOAT_EQ(mosaic_ring_mean(mosaic, rggb, b, 15, 15, 15, {3, 6}), static_cast<float>(b))
        << b;
}

// Four spans' ring means side by side are each span's own, bit for bit: on planes and mosaics of
// noisy values with NaN, +INF and foreign ones, at every place (the image's edges included, where
// the rings are clipped and the spans are read one by one), with a saturated value counted as
// +INF and as a level.
TEST(DimEdge, four_spans_ring_means_are_each_spans_own) {
  cv::Mat image(37, 45, CV_32F);
  cv::RNG rng(7);
  rng.fill(image, cv::RNG::UNIFORM, 0, 200);
  for (int k = 0; k < 60; ++k) {
    const int x = rng.uniform(0, image.cols), y = rng.uniform(0, image.rows);
    image.at<float>(y, x) = k % 3 == 0 ? NAN : k % 3 == 1 ? INFINITY : 900.0f;  // 900: foreign
  }
  const auto same = [](double a, double b) {
    return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0;
  };
  const MosaicLayout rggb = MosaicLayout::bayer("RGGB");
  std::vector<int> cells(25);
  for (int b = 0; b < 25; ++b) cells[static_cast<std::size_t>(b)] = b;
  const MosaicLayout five = MosaicLayout::snapshot(5, 5, cells);
  int compared = 0, differ = 0, foreign = 0;
  for (const double saturated : {static_cast<double>(INFINITY), 187.3})
    for (int y = 0; y < image.rows; ++y)
      for (int first = 0; first < image.cols; first += 2) {
        double means[4];
        for (const DimEdgeCheck::Ring ring : {DimEdgeCheck::Ring{5, 6}, DimEdgeCheck::Ring{3, 3}}) {
          plane_ring_means_four(image, first, 2, y, ring, means, saturated, 500);
          for (int k = 0; k < 4 && first + 2 * k < image.cols; ++k, ++compared) {
            const int at = first + 2 * k;
            const double one = plane_ring_mean(image, at, at + 1, y, ring, saturated, 500);
            differ += !same(means[k], one);
            foreign += std::isnan(one);
          }
        }
        for (const auto& [layout, band] :
             {std::pair{rggb, 0}, std::pair{rggb, 1}, std::pair{rggb, 2}, std::pair{five, 7}}) {
          mosaic_ring_means_four(image, layout, band, first, 2, y, DimEdgeCheck::kMosaicRing, means,
                                 saturated, 500);
          for (int k = 0; k < 4 && first + 2 * k < image.cols; ++k, ++compared) {
            const int at = first + 2 * k;
            const double one = mosaic_ring_mean(image, layout, band, at, at + 1, y,
                                                DimEdgeCheck::kMosaicRing, saturated, 500);
            differ += !same(means[k], one);
          }
        }
      }
  EXPECT_EQ(differ, 0) << "of " << compared;
  EXPECT_GT(foreign, 0);  // rings with a foreign value were among them
}

}  // namespace
}  // namespace pyrocam
