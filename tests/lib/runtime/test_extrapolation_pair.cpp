// Above the calibration a colour model reads from the band ratio the calibration constrains best
// (extrapolation_pair.h): which pair, and the likelihood fit's reading with it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "pyrocam/core/locus.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/extrapolation_pair.h"
#include "runtime/estimator_test_support.h"

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
  // A reference that is the mean of several bands: the pair's ratio is not one the network
  // reads, so no reader takes it.
  CameraModel mean_reference = colour;
  mean_reference.profile.normalisation.reference = {0, 1, 2};
  EXPECT_FALSE(extrapolation_pair(mean_reference, locus, 1100).active());
  const ExtrapolationPair pair = extrapolation_pair(colour, locus, 1100);
  EXPECT_EQ(pair.numerator_ratio, 0);     // R: the first numerator
  EXPECT_EQ(pair.denominator_ratio, -1);  // G: the reference
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

// The reading is a continuous function of the three-band reading and the pair's ratio, even
// across the ratio's turning point (near 890 degC on this camera, above a top of 700 degC) and
// for ratios the locus never has: a lookup table of it interpolates. (Read instead at the
// crossing nearest the three-band reading, it jumped by hundreds of degrees where the nearest
// crossing changed branch or vanished.)
TEST(ExtrapolationPair, reads_continuously_across_branches) {
  const CameraModel camera = datasheet_camera("rgb-reference");
  const Locus locus = make_locus(camera, 500, 3500, 1);
  const ExtrapolationPair pair = extrapolation_pair(camera, locus, 700);
  ASSERT_TRUE(pair.active());
  const auto [lo, hi] = std::minmax_element(pair.log_ratio.begin(), pair.log_ratio.end());
  // Steps small enough that the steepest slope (where the pair reads hundreds of degrees from
  // the three bands and its weight changes) moves the reading by well under the bound.
  const double dl = (*hi - *lo) / 200000, dt = 0.005;
  double largest_step_l = 0, largest_step_t = 0;
  for (double t = 650; t < 3550; t += 7.3)
    for (double l = *lo - 0.2; l < *hi + 0.2; l += (*hi - *lo) / 300) {
      const double r = pair.read(t, l);
      ASSERT_TRUE(std::isfinite(r));
      largest_step_l = std::max(largest_step_l, std::abs(pair.read(t, l + dl) - r));
      largest_step_t = std::max(largest_step_t, std::abs(pair.read(t + dt, l) - r));
    }
  EXPECT_LT(largest_step_l, 1.0);
  EXPECT_LT(largest_step_t, 1.0);
  std::printf("largest change: %.3f degC for a ratio %.2g apart, %.3f for %.3f degC\n",
              largest_step_l, dl, largest_step_t, dt);
}

// The network learns the readings of every band; above the calibration its reading, and so its
// lookup table's, passes to the pair's as the likelihood fit's does.
TEST(ExtrapolationPair, the_network_and_its_table_read_the_pair_above_the_calibration) {
  const std::shared_ptr<const ThermalModel> calibrated = test::test_model("test-model-rgb.json");
  ASSERT_TRUE(std::isfinite(calibrated->calibrated_up_to_c));
  auto plain = std::make_shared<ThermalModel>(*calibrated);
  plain->calibrated_up_to_c = NAN;
  const auto every_band = make_estimator(plain, Method::kMlp);
  const auto network = make_estimator(calibrated, Method::kMlp);
  const auto table = make_estimator(calibrated, Method::kLut);
  const auto fit = make_estimator(calibrated, Method::kLikelihood);
  const double top = calibrated->calibrated_up_to_c;
  const auto signals = [&](double t) {
    Eigen::VectorXd s = calibrated->camera.rates(t);
    s *= 150.0 / s.maxCoeff();
    s[2] *= 1.05;  // the unit's blue band is 5 % brighter than its model says
    return s;
  };
  for (double t : {top + 400, top + 900, top + 1500}) {
    const Eigen::VectorXd s = signals(t);
    EXPECT_GT(std::abs(every_band->temperature_c(s.data()) - t), 5) << t;
    EXPECT_NEAR(network->temperature_c(s.data()), t, 0.5) << t;
    EXPECT_NEAR(fit->temperature_c(s.data()), network->temperature_c(s.data()), 0.5) << t;
    EXPECT_NEAR(table->temperature_c(s.data()), network->temperature_c(s.data()), 0.1) << t;
  }
  // Within the calibration the network reads as it was trained.
  for (double t : {top - 300, top}) {
    const Eigen::VectorXd s = signals(t);
    EXPECT_EQ(network->temperature_c(s.data()), every_band->temperature_c(s.data())) << t;
  }
}

}  // namespace
}  // namespace pyrocam
