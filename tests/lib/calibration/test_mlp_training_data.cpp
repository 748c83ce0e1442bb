// Training's first stage (calibration/mlp_training_data.h): the checks and transforms, the split,
// the standardisation on the training rows, the held-out rmse and the curve.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include "calibration/mlp_training_data.h"
#include "mlp_test_support.h"

namespace pyrocam::mlp_training {
namespace {

using test::expect_mlp_error;
using test::profile_locus;

TEST(MlpTrainingData, transforms_inputs_to_logs_and_targets_to_network_units) {
  const Locus locus = profile_locus("rgb-reference", 500, 3500, 500);
  MlpTrainingOptions options;  // log in, 1/T out
  const TransformedSamples s = transform_samples(locus.ratios, locus.temperature_c, options);
  EXPECT_NEAR(s.inputs(2, 1), std::log(locus.ratios(2, 1)), 1e-12);
  EXPECT_NEAR(s.targets[0], 1 / (500 + 273.15), 1e-15);
  options.input_transform = MlpInputTransform::kNone;
  options.output_transform = MlpOutputTransform::kNone;
  const TransformedSamples raw = transform_samples(locus.ratios, locus.temperature_c, options);
  EXPECT_EQ(raw.inputs, locus.ratios);
  EXPECT_EQ(raw.targets, locus.temperature_c);
  expect_mlp_error(
      [&] { transform_samples(Eigen::MatrixXd::Ones(3, 0), Eigen::VectorXd::Ones(3), options); },
      {"input size 0"});
}

TEST(MlpTrainingData, stratified_split_holds_out_evenly_spaced_rows_never_the_ends) {
  const Eigen::Index samples = 101, test_count = 30;
  // Targets in scrambled order: the split must follow target order, not row order.
  Eigen::VectorXd y(samples);
  for (Eigen::Index i = 0; i < samples; ++i) y[i] = static_cast<double>((i * 37) % samples);
  Random random(4);
  const std::vector<Eigen::Index> order = split_order(y, test_count, true, random);
  std::vector<Eigen::Index> sorted = order;
  std::sort(sorted.begin(), sorted.end());
  std::vector<Eigen::Index> all(static_cast<std::size_t>(samples));
  std::iota(all.begin(), all.end(), 0);
  ASSERT_EQ(sorted, all) << "a permutation";
  std::vector<double> held_out;
  for (Eigen::Index k = 0; k < test_count; ++k) held_out.push_back(y[order[k]]);
  std::sort(held_out.begin(), held_out.end());
  EXPECT_GT(held_out.front(), 0) << "the coldest row is trained on";
  EXPECT_LT(held_out.back(), samples - 1) << "the hottest row is trained on";
  for (std::size_t k = 1; k < held_out.size(); ++k) {
    const double gap = held_out[k] - held_out[k - 1];
    EXPECT_GE(gap, 3);  // (101 - 2) / 30 = 3.3 apart
    EXPECT_LE(gap, 4);
  }
  Random other(5);
  EXPECT_NE(split_order(y, test_count, true, other), order) << "the phase is drawn";
  Random shuffled(4);
  const std::vector<Eigen::Index> random_split = split_order(y, test_count, false, shuffled);
  EXPECT_NE(random_split, order);
  EXPECT_TRUE(std::is_permutation(random_split.begin(), random_split.end(), all.begin()));
}

TEST(MlpTrainingData, standardises_on_the_training_rows_and_weights_the_loss_in_degrees) {
  const Locus locus = profile_locus("rgb-reference", 500, 3500, 20);
  MlpTrainingOptions options;
  Random random(1);
  const TrainingData d = prepare_training_data(locus.ratios, locus.temperature_c, options, random);
  EXPECT_EQ(d.train_count + d.test_count, locus.size());
  EXPECT_EQ(d.test_count, std::lround(0.3 * static_cast<double>(locus.size())));
  EXPECT_EQ(d.input_size, 2);
  EXPECT_EQ(static_cast<Eigen::Index>(d.training_rows.size()), d.train_count);
  EXPECT_EQ(d.z_train_s.rows(), 2);
  EXPECT_EQ(d.z_train_s.cols(), d.train_count);
  EXPECT_EQ(d.z_test_s.cols(), d.test_count);
  for (Eigen::Index r = 0; r < 2; ++r) {
    const Eigen::VectorXd z = d.z_train_s.row(r).cast<double>().transpose();
    EXPECT_NEAR(z.mean(), 0, 1e-6);
    EXPECT_NEAR(std::sqrt(z.squaredNorm() / static_cast<double>(z.size())), 1, 1e-5);
  }
  EXPECT_NEAR(d.t_train.mean(), 0, 1e-12);
  for (Eigen::Index i = 0; i < d.train_count; ++i) {
    EXPECT_EQ(d.y_train[i], locus.temperature_c[d.training_rows[static_cast<std::size_t>(i)]]);
  }
  // 1/T out: an error of the network weighs T^4 times as much at the hot end.
  EXPECT_NEAR(d.loss_weights.mean(), 1, 1e-12);
  Eigen::Index hottest = 0, coldest = 0;
  d.y_train.maxCoeff(&hottest);
  d.y_train.minCoeff(&coldest);
  EXPECT_NEAR(d.loss_weights[hottest] / d.loss_weights[coldest],
              std::pow((3500 + 273.15) / (500 + 273.15), 4), 1e-6);
  EXPECT_TRUE((d.loss_weights.array() * d.to_target_units.array())
                  .isApprox(d.slope_squared.array(), 1e-12));

  options.test_fraction = 0.99;
  Random again(1);
  const Eigen::MatrixXd two_rows = locus.ratios.topRows(2);
  expect_mlp_error(
      [&] { prepare_training_data(two_rows, locus.temperature_c.head(2), options, again); },
      {"no training samples"});
}

TEST(MlpTrainingData, test_set_rmse_is_in_degrees_and_nan_without_a_test_set) {
  const Locus locus = profile_locus("rgb-reference", 500, 3500, 50);
  MlpTrainingOptions options;
  options.output_transform = MlpOutputTransform::kNone;
  Random random(1);
  const TrainingData d = prepare_training_data(locus.ratios, locus.temperature_c, options, random);
  // A network whose output is 0 everywhere: it reads the training mean, y_mean.
  TrainingNetwork zero;
  zero.weights.push_back(TrainingMatrix::Zero(1, 2));
  zero.bias.push_back(TrainingNetwork::Vector::Zero(1));
  auto acts = make_activations(zero, kEvaluationChunk);
  const double expected =
      std::sqrt((d.y_test.array() - d.y_mean).square().sum() / static_cast<double>(d.test_count));
  EXPECT_NEAR(test_set_rmse(zero, acts, d, MlpOutputTransform::kNone), expected, 1e-9);
  EXPECT_GT(expected, 100);

  options.test_fraction = 0;
  Random again(1);
  const TrainingData all = prepare_training_data(locus.ratios, locus.temperature_c, options, again);
  EXPECT_TRUE(std::isnan(test_set_rmse(zero, acts, all, MlpOutputTransform::kNone)));
}

TEST(MlpTrainingData, curve_points_go_to_the_progress_callback) {
  MlpTrainingOptions options;
  std::vector<int> seen;
  options.progress = [&](int pass, double train, double test) {
    seen.push_back(pass);
    EXPECT_EQ(train, 0.5);
    EXPECT_EQ(test, 0.25);
  };
  TrainingCurve curve;
  curve.add(3, 0.5, 0.25, options);
  curve.add(7, 0.5, 0.25, options);
  EXPECT_EQ(curve.pass, (std::vector<int>{3, 7}));
  EXPECT_EQ(seen, curve.pass);
  EXPECT_EQ(curve.train_rmse, (std::vector<double>{0.5, 0.5}));
  EXPECT_EQ(curve.test_rmse.size(), 2u);
}

}  // namespace
}  // namespace pyrocam::mlp_training
