// Above the calibration a colour model reads from the band ratio the calibration constrains best
// (extrapolation_pair.h): which pair, and the likelihood fit's reading with it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>

#include "pyrocam/core/locus.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/extrapolation_pair.h"

namespace pyrocam {
namespace {

CameraModel datasheet_camera(const std::string& profile) {
  const CameraProfile p = load_profile_by_name(profile);
  return CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
}

TEST(ExtrapolationPair, is_the_two_bands_whose_light_the_furnace_saw) {
  const CameraModel camera = datasheet_camera("rgb-reference");
  const Locus locus = make_locus(camera, 500, 3500, 1);
  const ExtrapolationPair pair = extrapolation_pair(camera, locus, 1100);
  ASSERT_TRUE(pair.active());
  ASSERT_EQ(pair.overlap.size(), 3u);
  // Blue sees a 1100 degC furnace through its infrared leak and a 2500 degC pool through its
  // pass band: the least overlap of the three.
  EXPECT_EQ(pair.numerator, 0);
  EXPECT_EQ(pair.denominator, 1);
  EXPECT_LT(pair.overlap[2], pair.overlap[0]);
  EXPECT_LT(pair.overlap[2], pair.overlap[1]);
  for (double o : pair.overlap) EXPECT_TRUE(o > 0 && o <= 1 + 1e-9) << o;
  // Calibrated higher, the light differs less.
  const ExtrapolationPair higher = extrapolation_pair(camera, locus, 2000);
  ASSERT_TRUE(higher.active());
  for (int b = 0; b < 3; ++b) EXPECT_GT(higher.overlap[b], pair.overlap[b]);
}

TEST(ExtrapolationPair, weighs_the_pair_by_its_noise_and_the_blend) {
  const CameraModel camera = datasheet_camera("rgb-reference");
  const Locus locus = make_locus(camera, 500, 3500, 1);
  const ExtrapolationPair pair = extrapolation_pair(camera, locus, 700);
  ASSERT_TRUE(pair.active());
  const auto at = [](double t) { return static_cast<std::size_t>(t - 500); };
  for (double t : {600.0, 700.0}) EXPECT_EQ(pair.weight[at(t)], 0) << t;
  // A quarter through the blend, and near the turning point less still: in proportion to how
  // far the pair's noise ratio is below kPairNoNoiseRatio.
  const double r750 = pair.noise_ratio[at(750)];
  EXPECT_GT(r750, kPairFullNoiseRatio);
  EXPECT_NEAR(pair.weight[at(750)],
              0.25 * (kPairNoNoiseRatio - r750) / (kPairNoNoiseRatio - kPairFullNoiseRatio), 1e-12);
  // Its ratio turns over near 890 degC: far noisier than the three bands there, so no weight.
  EXPECT_GT(pair.noise_ratio[at(890)], kPairNoNoiseRatio);
  EXPECT_EQ(pair.weight[at(890)], 0);
  for (double t : {1300.0, 2000.0, 3000.0}) {
    EXPECT_GE(pair.noise_ratio[at(t)], 1 - 1e-9) << t;  // one ratio never beats two
    EXPECT_LE(pair.noise_ratio[at(t)], kPairFullNoiseRatio) << t;
    EXPECT_EQ(pair.weight[at(t)], 1) << t;
  }
  // It hands back to the three bands over the top 200 degC of the range (the locus' end, or
  // the top given).
  EXPECT_NEAR(pair.weight[at(3400)], 0.5, 1e-9);
  EXPECT_GT(pair.weight[at(3499)], 0);
  EXPECT_EQ(extrapolation_pair(camera, locus, 700, 3000).weight[at(3000)], 0);
  EXPECT_NEAR(extrapolation_pair(camera, locus, 700, 3000).weight[at(2900)], 0.5, 1e-9);
}

TEST(ExtrapolationPair, none_without_a_calibrated_top_inside_the_locus_or_three_bands_n) {
  const CameraModel colour = datasheet_camera("rgb-reference");
  const Locus locus = make_locus(colour, 500, 3500, 1);
  EXPECT_FALSE(extrapolation_pair(colour, locus, NAN).active());
  EXPECT_FALSE(extrapolation_pair(colour, locus, 3500).active());  // nothing above it
  EXPECT_FALSE(extrapolation_pair(colour, locus, 400).active());
  // The 5x5 camera's 25 bands are read together (their extrapolation holds without this).
  const CameraModel snapshot = datasheet_camera("nir5x5-reference");
  EXPECT_FALSE(extrapolation_pair(snapshot, make_locus(snapshot, 500, 3500, 5), 1100).active());
}

// A unit whose blue band is 5 % brighter than its model says: read from every band, the
// temperatures above the calibration are off; read from the pair above it, they are not.
TEST(ExtrapolationPair, the_likelihood_fit_reads_the_pair_above_the_calibration) {
  auto plain = std::make_shared<ThermalModel>();
  plain->camera = datasheet_camera("rgb-reference");
  plain->min_temperature_c = 500;
  plain->max_temperature_c = 3500;
  auto calibrated = std::make_shared<ThermalModel>(*plain);
  calibrated->calibrated_up_to_c = 1100;
  const auto every_band = make_estimator(plain, Method::kLikelihood);
  const auto fast = make_estimator(calibrated, Method::kLikelihood);
  const auto exhaustive = make_exhaustive_likelihood_estimator(calibrated);
  const auto signals = [&](double t) {
    Eigen::VectorXd s = plain->camera.rates(t);
    s *= 150.0 / s.maxCoeff();
    s[2] *= 1.05;
    return s;
  };
  for (double t : {1400.0, 2000.0, 2600.0}) {
    const Eigen::VectorXd s = signals(t);
    EXPECT_GT(std::abs(every_band->temperature_c(s.data()) - t), 5) << t;
    EXPECT_NEAR(fast->temperature_c(s.data()), t, 0.5) << t;
    EXPECT_NEAR(exhaustive->temperature_c(s.data()), fast->temperature_c(s.data()), 0.01) << t;
  }
  // In the calibrated range every band reads, as without a top.
  for (double t : {800.0, 1000.0}) {
    const Eigen::VectorXd s = signals(t);
    EXPECT_EQ(fast->temperature_c(s.data()), every_band->temperature_c(s.data())) << t;
  }
  // Half way through the blend (kExtrapolationBlendC above the top), half way between the two.
  const double t = 1100 + kExtrapolationBlendC / 2;
  const Eigen::VectorXd s = signals(t);
  const double all = every_band->temperature_c(s.data());
  const double w = (all - 1100) / kExtrapolationBlendC;  // the blend's weight at that reading
  EXPECT_NEAR(fast->temperature_c(s.data()), all + w * (t - all), 0.5);
  // Where the pair's ratio turns over (near 890 degC on this camera) it tells nothing: a model
  // calibrated up to 700 degC reads the three bands there, and the pair further up.
  auto low_top = std::make_shared<ThermalModel>(*plain);
  low_top->calibrated_up_to_c = 700;
  const auto low = make_estimator(low_top, Method::kLikelihood);
  for (double at : {880.0, 890.0, 900.0}) {
    const Eigen::VectorXd s_at = signals(at);
    EXPECT_EQ(low->temperature_c(s_at.data()), every_band->temperature_c(s_at.data())) << at;
  }
  const Eigen::VectorXd s_hot = signals(2000);
  EXPECT_NEAR(low->temperature_c(s_hot.data()), 2000, 0.5);
}

}  // namespace
}  // namespace pyrocam
