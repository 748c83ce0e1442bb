// Training's polish stage (calibration/mlp_polish.h): the output layer by least squares, L-BFGS
// with variable projection, Lawson reweighting, and the stage as a whole.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "calibration/mlp_init.h"
#include "calibration/mlp_polish.h"
#include "mlp_test_support.h"

namespace pyrocam::mlp_training {
namespace {

using test::profile_locus;

// The colour locus every 20 degC, prepared, and a freshly initialised small network.
struct PolishSetup {
  MlpTrainingOptions options = test::small_options();
  TrainingData data;
  TrainingNetwork net;

  PolishSetup() {
    static const Locus locus = profile_locus("rgb-reference", 500, 3500, 20);
    Random random(options.seed);
    data = prepare_training_data(locus.ratios, locus.temperature_c, options, random);
    net = initial_network(2, options.hidden, data.z_train_s, random);
  }
};

// The last hidden layer's activations of the problem's inputs.
Eigen::MatrixXf last_hidden(const TrainingNetwork& net, const PolishProblem& problem) {
  auto acts = make_activations(net, problem.inputs.cols());
  acts[0] = problem.inputs;
  forward(net, acts, problem.inputs.cols(), 0, net.layer_count() - 1);
  return acts[net.layer_count() - 1];
}

// mean(w e^2) of the network on the problem, standardised units.
double weighted_mse(const TrainingNetwork& net, const PolishProblem& problem) {
  auto acts = make_activations(net, kEvaluationChunk);
  const Eigen::RowVectorXd out = evaluate(net, problem.inputs, acts).cast<double>();
  return ((out - problem.targets).array().square() * problem.weights.array()).mean();
}

TEST(MlpPolish, output_layer_solves_the_weighted_least_squares) {
  PolishSetup s;
  PolishProblem problem = make_polish_problem(s.data, s.options, AugmentedSamples{});
  problem.weight_decay = 0;
  problem.weights = Eigen::RowVectorXd::LinSpaced(problem.targets.size(), 0.5, 1.5);
  const Eigen::MatrixXf hidden = last_hidden(s.net, problem);
  fit_output_layer(s.net, hidden, problem);
  // Normal equations of the same problem: [H; 1]' W [H; 1] beta = [H; 1]' W t.
  const Eigen::Index n = problem.targets.size(), features = hidden.rows();
  Eigen::MatrixXd a(n, features + 1);
  a.leftCols(features) = hidden.transpose().cast<double>();
  a.col(features).setOnes();
  const Eigen::MatrixXd aw = a.transpose() * problem.weights.transpose().asDiagonal();
  const double before = weighted_mse(s.net, problem);
  // Perturbing the solution in any direction raises the loss: it is the minimum.
  for (Eigen::Index k = 0; k <= features; ++k) {
    TrainingNetwork moved = s.net;
    if (k < features) {
      moved.weights.back()(0, k) += 1e-2f;
    } else {
      moved.bias.back()[0] += 1e-2f;
    }
    EXPECT_GT(weighted_mse(moved, problem), before) << "parameter " << k;
  }
  // The residual is orthogonal to the columns, weighted (up to single-precision rounding).
  Eigen::VectorXd beta(features + 1);
  beta.head(features) = s.net.weights.back().row(0).transpose().cast<double>();
  beta[features] = s.net.bias.back()[0];
  const Eigen::VectorXd residual = a * beta - problem.targets.transpose();
  EXPECT_LT((aw * residual).cwiseAbs().maxCoeff(), 1e-4 * (aw * a).cwiseAbs().maxCoeff());
}

TEST(MlpPolish, lbfgs_lowers_the_loss_and_reports_every_iteration) {
  PolishSetup s;
  const PolishProblem problem = make_polish_problem(s.data, s.options, AugmentedSamples{});
  TrainingNetwork start = s.net;
  fit_output_layer(start, last_hidden(start, problem), problem);
  const double initial = weighted_mse(start, problem);
  std::vector<double> reported;
  const int done =
      polish_with_lbfgs(s.net, problem, 40, [&](double rmse) { reported.push_back(rmse); });
  EXPECT_EQ(done, 40);
  ASSERT_EQ(reported.size(), 40u);
  EXPECT_LT(weighted_mse(s.net, problem), 0.1 * initial);
  EXPECT_LT(reported.back(), 0.5 * reported.front());
  for (double rmse : reported) EXPECT_TRUE(std::isfinite(rmse));
}

TEST(MlpPolish, reweighting_multiplies_weights_by_the_errors_with_a_floor) {
  PolishSetup s;
  PolishProblem problem = make_polish_problem(s.data, s.options, AugmentedSamples{});
  auto acts = make_activations(s.net, kEvaluationChunk);
  ASSERT_TRUE(reweight_towards_minimax(s.net, s.data, s.options.output_transform, acts, problem));
  EXPECT_NEAR(problem.weights.mean(), 1, 1e-12);
  // Errors of the network, target units, as reweighting computes them.
  const Eigen::RowVectorXf out = evaluate(s.net, s.data.z_train_s, acts);
  Eigen::ArrayXd error(s.data.train_count);
  for (Eigen::Index i = 0; i < error.size(); ++i) {
    const double v = static_cast<double>(out[i]) * s.data.y_scale + s.data.y_mean;
    error[i] = std::abs(from_network_units(s.options.output_transform, v) - s.data.y_train[i]);
  }
  const Eigen::ArrayXd expected =
      s.data.loss_weights.transpose().array() * error.max(error.maxCoeff() / 20);
  EXPECT_TRUE(problem.weights.transpose().array().isApprox(expected / expected.mean(), 1e-12));
  EXPECT_FALSE(problem.weights.isApprox(s.data.loss_weights, 1e-3)) << "weights moved";
}

TEST(MlpPolish, problem_appends_augmented_samples_after_the_training_rows) {
  PolishSetup s;
  AugmentedSamples a;
  a.z = TrainingMatrix::Ones(2, 3);
  a.targets = Eigen::VectorXd::Constant(3, 900);
  a.t_double = Eigen::RowVectorXd::Constant(3, 0.25);
  a.weights_double = Eigen::RowVectorXd::Constant(3, 0.3);
  a.slope_squared = Eigen::RowVectorXd::Constant(3, 7);
  const PolishProblem p = make_polish_problem(s.data, s.options, a);
  const Eigen::Index n = s.data.train_count;
  EXPECT_EQ(p.reported, n);
  ASSERT_EQ(p.inputs.cols(), n + 3);
  EXPECT_EQ(p.inputs.col(n + 1), a.z.col(1));
  EXPECT_EQ(p.inputs.leftCols(n), s.data.z_train_s);
  EXPECT_EQ(p.targets[n + 2], 0.25);
  EXPECT_EQ(p.weights[n], 0.3);
  EXPECT_EQ(p.slope_squared[n], 7);
  EXPECT_EQ(p.weight_decay, s.options.polish_weight_decay);
}

TEST(MlpPolish, stage_runs_its_rounds_and_adds_a_point_every_ten_iterations) {
  PolishSetup s;
  s.options.polish_iterations = 35;
  int calls = 0;
  s.options.augment = [&](const std::vector<Eigen::Index>& rows, std::uint64_t) {
    ++calls;
    MlpSamples m;
    m.inputs = Eigen::MatrixXd::Constant(static_cast<Eigen::Index>(rows.size()), 2, 1.0);
    m.targets = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(rows.size()), 1500);
    return m;
  };
  Random random(3);
  AugmentedSamples augmented;
  TrainingCurve curve;
  const int done = polish(s.net, s.data, s.options, random, augmented, curve);
  EXPECT_EQ(done, 35);
  EXPECT_EQ(calls, 1) << "one set of augmented samples for the whole polish";
  EXPECT_EQ(augmented.size(), s.data.train_count);
  EXPECT_EQ(curve.pass, (std::vector<int>{14, 24, 34, 39})) << "after the 4 epochs of Adam";
  EXPECT_LT(curve.test_rmse.back(), curve.test_rmse.front());
}

}  // namespace
}  // namespace pyrocam::mlp_training
