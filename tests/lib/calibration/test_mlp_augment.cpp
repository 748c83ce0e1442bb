// Training's augmentation stage (calibration/mlp_augment.h): augmented samples prepared with the
// training rows' standardisation and weights, and the checks on what augment gives.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "calibration/mlp_augment.h"
#include "mlp_test_support.h"

namespace pyrocam::mlp_training {
namespace {

using test::expect_mlp_error;
using test::profile_locus;

struct Fixture {
  Locus locus = profile_locus("rgb-reference", 500, 3500, 50);
  MlpTrainingOptions options;
  TrainingData data;
  std::vector<std::vector<Eigen::Index>> calls;
  std::vector<std::uint64_t> seeds;

  Fixture() {
    Random random(1);
    data = prepare_training_data(locus.ratios, locus.temperature_c, options, random);
    // Each row copied twice, 100 degC hotter.
    options.augment = [this](const std::vector<Eigen::Index>& rows, std::uint64_t seed) {
      calls.push_back(rows);
      seeds.push_back(seed);
      MlpSamples s;
      const auto n = static_cast<Eigen::Index>(rows.size());
      s.inputs.resize(2 * n, 2);
      s.targets.resize(2 * n);
      for (Eigen::Index i = 0; i < 2 * n; ++i) {
        s.inputs.row(i) = locus.ratios.row(rows[static_cast<std::size_t>(i % n)]);
        s.targets[i] = locus.temperature_c[rows[static_cast<std::size_t>(i % n)]] + 100;
      }
      return s;
    };
  }
};

TEST(MlpAugment, prepares_samples_as_the_training_rows_are) {
  Fixture f;
  const AugmentedSamples a = make_augmented(f.options, f.data, 42);
  ASSERT_EQ(f.calls.size(), 1u);
  EXPECT_EQ(f.calls[0], f.data.training_rows) << "called with the training rows only";
  EXPECT_EQ(f.seeds[0], 42u);
  ASSERT_EQ(a.size(), 2 * f.data.train_count);
  EXPECT_EQ(a.z.rows(), 2);
  EXPECT_EQ(a.z.cols(), a.size());
  // Same inputs as training row 0: same standardised column.
  EXPECT_TRUE(a.z.col(0).isApprox(f.data.z_train_s.col(0), 1e-6));
  EXPECT_TRUE(a.z.col(f.data.train_count).isApprox(f.data.z_train_s.col(0), 1e-6));
  // The target 100 degC hotter, standardised as the network's 1/T targets are.
  const double network = 1 / (f.data.y_train[0] + 100 + 273.15);
  EXPECT_NEAR(a.t_double[0], (network - f.data.y_mean) / f.data.y_scale, 1e-12);
  EXPECT_FLOAT_EQ(a.t[0], static_cast<float>(a.t_double[0]));
  // Weights: augmented_weight times the loss weight a training row at that target would get.
  const double slope = f.data.y_scale / (network * network);  // d T / d (1/T) = -T^2
  EXPECT_NEAR(a.slope_squared[0], slope * slope, 1e-9 * slope * slope);
  EXPECT_NEAR(a.weights_double[0],
              f.options.augmented_weight * a.slope_squared[0] / f.data.mean_slope_squared, 1e-12);
  EXPECT_EQ(a.inputs.rows(), a.size());
  EXPECT_EQ(a.targets[0], f.data.y_train[0] + 100);

  f.options.loss_in_target_units = false;
  const AugmentedSamples unweighted = make_augmented(f.options, f.data, 43);
  EXPECT_TRUE((unweighted.weights_double.array() == f.options.augmented_weight).all());
}

TEST(MlpAugment, rejects_wrong_shapes_bad_numbers_and_the_transforms_domain_n) {
  Fixture f;
  const auto give = [&](Eigen::MatrixXd inputs, Eigen::VectorXd targets) {
    f.options.augment = [=](const std::vector<Eigen::Index>&, std::uint64_t) {
      return MlpSamples{inputs, targets};
    };
  };
  give(Eigen::MatrixXd::Ones(2, 3), Eigen::VectorXd::Constant(2, 900));
  expect_mlp_error([&] { make_augmented(f.options, f.data, 1); },
                   {"augmentation gave 2 samples of 3 inputs", "need 2 inputs"});
  give(Eigen::MatrixXd::Ones(2, 2), Eigen::VectorXd::Constant(3, 900));
  expect_mlp_error([&] { make_augmented(f.options, f.data, 1); }, {"3 targets"});
  give(Eigen::MatrixXd::Ones(1, 2), Eigen::VectorXd::Constant(1, std::nan("")));
  expect_mlp_error([&] { make_augmented(f.options, f.data, 1); }, {"NaN"});
  give(-Eigen::MatrixXd::Ones(1, 2), Eigen::VectorXd::Constant(1, 900));
  expect_mlp_error([&] { make_augmented(f.options, f.data, 1); }, {"log input transform"});
  give(Eigen::MatrixXd::Ones(1, 2), Eigen::VectorXd::Constant(1, -300));
  expect_mlp_error([&] { make_augmented(f.options, f.data, 1); }, {"below absolute zero"});
  give(Eigen::MatrixXd(0, 0), Eigen::VectorXd(0));
  EXPECT_EQ(make_augmented(f.options, f.data, 1).size(), 0) << "no samples is allowed";
}

}  // namespace
}  // namespace pyrocam::mlp_training
