// The saturation level as an edge: on a surface whose band sits near it, the pixels that read
// must not be those whose own noise pulled that band down (their readings would lean one way).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "plate_readings.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/dim_edge.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/saturation_edge.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

// A 1200 degC plate on the simulated colour camera (its true QE, the likelihood fit), exposed
// so that red, its brightest band, sits from a few of a raw sample's standard deviations
// (about 2.3 DN) below the saturation level to above it. Without the check, the pixels whose
// red samples all stayed below the level read, selected by their own noise: 26 % of the plate
// with red 1 standard deviation below the level (median 1.6 degC low), 7.7 % at 0.5 (3.0 degC
// low), 1.3 % at the level (4.6 degC low; on 4 times these pixels). Now a plate whose red lies
// within 1 standard deviation of the level reads on under 5 % of its pixels (none: the ring's
// half means lie a standard deviation above the mark, with a noise of 0.3 of one), and where
// it reads on 5 % or more, within 5 degC: the median of about 2 x 13000 readings of 35 degC
// spread, neighbours sharing samples (about 14 readings a sample), has a standard error near
// 1 degC; the model's own bias is under 1 degC.
TEST(SaturationEdge, a_plate_at_the_saturation_level_reads_on_none_or_without_lean) {
  TrueQeColourPlate p;
  const CameraProfile& profile = p.profile;
  constexpr double kTruthC = TrueQeColourPlate::kTruthC;
  const double reference_us = 20;
  const double red_dn = p.camera.mean_signal_dn(kTruthC, reference_us)[0];
  const double level = profile.thresholds.inference_saturation_dn - profile.dark_offset_dn;
  const double sd = std::sqrt(signal_variance_dn2(profile, 0, level));
  double most_read = 0, least_read = 1;
  for (const double below_sd : {4.0, 3.0, 2.0, 1.0, 0.5, 0.0, -1.0}) {
    const double exposure = reference_us * (level - below_sd * sd) / red_dn;
    const PlateReadings plate = measure_plate(p.measurer, p.camera, p.truth, kTruthC, exposure);
    const double read = plate.read, median = plate.median;
    most_read = std::max(most_read, read);
    least_read = std::min(least_read, read);
    std::printf("red %.1f sd below the level: %.1f %% read, median error %.2f degC\n", below_sd,
                100 * read, median);
    if (read >= 0.05) {
      EXPECT_LE(std::abs(median), 5.0) << "red " << below_sd << " sd below the level";
    }
    if (below_sd <= 1.0) {
      EXPECT_LT(read, 0.05) << "red " << below_sd << " sd below the level: read where noise chose";
    }
  }
  EXPECT_LT(least_read, 0.05) << "no exposure left the plate without readings: not at the edge";
  EXPECT_GT(most_read, 0.9) << "no exposure read the plate";
}

// The check's levels follow the noise model at the saturation level less the dark offset: 2
// and 6 standard deviations of a raw sample below it, wider with analogue gain.
TEST(SaturationEdge, levels_follow_the_noise_model) {
  const CameraProfile profile = load_profile_by_name("nir5x5-reference");
  const SaturationEdgeCheck check(profile, 1.0, 220), gained(profile, 4.0, 220);
  const double level = 220 - profile.dark_offset_dn;
  ASSERT_EQ(check.bands(), profile.band_count());
  for (int b = 0; b < check.bands(); ++b) {
    const double sd = std::sqrt(signal_variance_dn2(profile, b, level));
    EXPECT_NEAR(check.mark_dn(b), level - 2 * sd, 1e-3) << b;
    EXPECT_NEAR(check.checked_dn(b), level - 6 * sd, 1e-3) << b;
    EXPECT_LT(gained.mark_dn(b), check.mark_dn(b)) << b;
  }
  EXPECT_THROW(SaturationEdgeCheck(profile, 1.0, NAN), InputError);
  const SaturationEdgeCheck off(profile, 1.0, INFINITY);  // nothing saturates: no check
  EXPECT_EQ(off.bands(), 0);
  EXPECT_EQ(off.checked_dn(0), INFINITY);
}

// On a row: a value near the level is marked where its ring reaches a saturated region or lies
// at the level, kept where the ring lies clearly below; values far below, and those above the
// level by more than the margin (a fused bracket's shorter exposure, scaled up), are left.
TEST(SaturationEdge, marks_by_the_ring_not_the_value) {
  const CameraProfile profile = load_profile_by_name("rgb-reference");
  const SaturationEdgeCheck check(profile, 1.0, 220);
  const float level = static_cast<float>(220 - profile.dark_offset_dn);
  const float near = (check.mark_dn(0) + check.checked_dn(0)) / 2;  // checked, not marked
  ASSERT_GT(check.mark_dn(0), check.checked_dn(0));
  constexpr int w = 64, h = 21, y = 10;
  std::vector<cv::Mat> planes(3);
  for (auto& p : planes) p = cv::Mat(h, w, CV_32F, cv::Scalar(level / 4));
  planes[0](cv::Rect(0, 0, 16, h)).setTo(INFINITY);  // saturated on the left
  planes[0](cv::Rect(40, 0, 24, h)).setTo(level);    // at the level on the right
  planes[0].at<float>(y, 17) = near;                 // ring reaches the saturated part
  planes[0].at<float>(y, 28) = near;                 // ring clear of both
  planes[0].at<float>(y, 50) = near;                 // inside the part at the level
  planes[0].at<float>(y, 30) = level + 100;          // a scaled-up shorter exposure's
  planes[1].at<float>(y, 28) = near;                 // green's ring is dim everywhere
  const DimEdgeCheck::Ring ring = DimEdgeCheck::plane_ring(profile.mosaic);
  const auto window = [&](int b, int first, int last, int row) {
    return plane_ring_mean(planes[static_cast<std::size_t>(b)], first, last, row, ring);
  };
  const float* rows[3] = {planes[0].ptr<float>(y), planes[1].ptr<float>(y),
                          planes[2].ptr<float>(y)};
  std::vector<std::vector<float>> scratch;
  check.apply(rows, w, 0, y, window, scratch, DimEdgeCheck::kSpan, false);
  EXPECT_EQ(rows[0][17], INFINITY);
  EXPECT_EQ(rows[0][28], near);
  EXPECT_EQ(rows[0][50], INFINITY);
  EXPECT_EQ(rows[0][41], INFINITY);  // at the level itself: its own ring is too
  EXPECT_EQ(rows[0][30], level + 100);
  EXPECT_EQ(rows[1][28], near);
  EXPECT_EQ(rows[2], planes[2].ptr<float>(y)) << "a band without a value to check is not copied";
  EXPECT_EQ(planes[0].at<float>(y, 17), near) << "the planes themselves are not written";
  // Where every band must read, a pixel with a band already saturated is not checked.
  planes[1].at<float>(y, 50) = INFINITY;
  const float* again[3] = {planes[0].ptr<float>(y), planes[1].ptr<float>(y),
                           planes[2].ptr<float>(y)};
  check.apply(again, w, 0, y, window, scratch, DimEdgeCheck::kSpan, true);
  EXPECT_EQ(again[0][50], near);
  EXPECT_EQ(again[0][17], INFINITY);
  // The ring mean counts a saturated value as asked: at the level here, +INF for the dim check.
  EXPECT_FLOAT_EQ(plane_ring_mean(planes[0], 16, 17, y, ring, level), level);
  EXPECT_EQ(plane_ring_mean(planes[0], 16, 17, y, ring), INFINITY);
}

}  // namespace
}  // namespace pyrocam
