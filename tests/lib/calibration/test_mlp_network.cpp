// The network as training sees it (calibration/mlp_network.h): forward and backward passes,
// chunked evaluation, parameters as one vector.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "calibration/mlp_network.h"

namespace pyrocam::mlp_training {
namespace {

// A 3-5-4-1 network in double precision with fixed pseudo-random weights and biases.
Network<double> small_network() {
  std::mt19937 engine(3);
  std::normal_distribution<double> normal;
  Network<double> net;
  const int widths[] = {3, 5, 4, 1};
  for (int l = 0; l < 3; ++l) {
    Eigen::MatrixXd w(widths[l + 1], widths[l]);
    for (Eigen::Index i = 0; i < w.size(); ++i) w.data()[i] = normal(engine);
    Eigen::VectorXd b(widths[l + 1]);
    for (Eigen::Index i = 0; i < b.size(); ++i) b[i] = 0.3 * normal(engine);
    net.weights.push_back(w);
    net.bias.push_back(b);
  }
  return net;
}

Eigen::MatrixXd sample_columns(Eigen::Index n) {
  std::mt19937 engine(5);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd x(3, n);
  for (Eigen::Index i = 0; i < x.size(); ++i) x.data()[i] = normal(engine);
  return x;
}

// mean(w e^2) by a forward pass.
double weighted_loss(const Network<double>& net, const Eigen::MatrixXd& x,
                     const Eigen::RowVectorXd& targets, const Eigen::RowVectorXd& weights) {
  auto acts = make_activations(net, x.cols());
  acts[0] = x;
  forward(net, acts, x.cols());
  const Eigen::ArrayXXd e = acts.back().array() - targets.array();
  return (e.square() * weights.array()).mean();
}

TEST(MlpNetwork, forward_applies_relu_to_hidden_layers_only) {
  const Network<double> net = small_network();
  const Eigen::MatrixXd x = sample_columns(7);
  auto acts = make_activations(net, 7);
  acts[0] = x;
  forward(net, acts, 7);
  ASSERT_EQ(acts.size(), 4u);
  Eigen::MatrixXd a = x;
  for (std::size_t l = 0; l < 3; ++l) {
    Eigen::MatrixXd z = (net.weights[l] * a).colwise() + net.bias[l];
    a = l < 2 ? Eigen::MatrixXd(z.cwiseMax(0.0)) : z;
    EXPECT_TRUE(acts[l + 1].isApprox(a, 1e-14)) << "layer " << l;
  }
  EXPECT_TRUE((acts[1].array() >= 0).all());
  EXPECT_TRUE((acts[3].array() < 0).any()) << "the linear output can go negative";
}

TEST(MlpNetwork, evaluate_in_chunks_matches_one_forward_pass) {
  const Network<double> net = small_network();
  const Eigen::MatrixXd x = sample_columns(10);
  auto chunk_acts = make_activations(net, 4);  // chunks of 4, 4 and 2
  const Eigen::RowVectorXd chunked = evaluate(net, x, chunk_acts);
  auto acts = make_activations(net, 10);
  acts[0] = x;
  forward(net, acts, 10);
  EXPECT_TRUE(chunked.isApprox(acts.back().row(0), 1e-14));
}

TEST(MlpNetwork, backward_gives_the_weighted_loss_and_its_gradient) {
  const Network<double> net = small_network();
  const Eigen::Index n = 6;
  const Eigen::MatrixXd x = sample_columns(n);
  const Eigen::RowVectorXd targets = Eigen::RowVectorXd::LinSpaced(n, -1, 1);
  const Eigen::RowVectorXd weights = Eigen::RowVectorXd::LinSpaced(n, 0.5, 2);
  auto acts = make_activations(net, n);
  auto deltas = make_activations(net, n);
  acts[0] = x;
  forward(net, acts, n);
  Network<double> grad = net;
  const double sse = backward(net, acts, deltas, targets, weights, n, grad);
  EXPECT_NEAR(sse / n, weighted_loss(net, x, targets, weights), 1e-12);

  Eigen::VectorXd theta, g;
  flatten(net, theta);
  flatten(grad, g);
  for (Eigen::Index i = 0; i < theta.size(); ++i) {
    Network<double> up = net, down = net;
    Eigen::VectorXd t = theta;
    const double h = 1e-6;
    t[i] += h;
    unflatten(t, up);
    t[i] -= 2 * h;
    unflatten(t, down);
    const double numeric =
        (weighted_loss(up, x, targets, weights) - weighted_loss(down, x, targets, weights)) /
        (2 * h);
    EXPECT_NEAR(g[i], numeric, 1e-6 * std::abs(numeric) + 1e-7) << "parameter " << i;
  }
}

TEST(MlpNetwork, flatten_and_unflatten_round_trip_layer_by_layer) {
  const Network<double> net = small_network();
  EXPECT_EQ(parameter_count(net), 3 * 5 + 5 + 5 * 4 + 4 + 4 * 1 + 1);
  Eigen::VectorXd theta;
  flatten(net, theta);
  ASSERT_EQ(theta.size(), parameter_count(net));
  EXPECT_EQ(theta[1], net.weights[0](1, 0)) << "weights column-major";
  EXPECT_EQ(theta[15], net.bias[0][0]) << "then the layer's biases";
  Network<float> single;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    single.weights.push_back(Eigen::MatrixXf::Zero(net.weights[l].rows(), net.weights[l].cols()));
    single.bias.push_back(Eigen::VectorXf::Zero(net.bias[l].size()));
  }
  unflatten(theta, single);
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    EXPECT_TRUE(single.weights[l].isApprox(net.weights[l].cast<float>()));
    EXPECT_TRUE(single.bias[l].isApprox(net.bias[l].cast<float>()));
  }
}

}  // namespace
}  // namespace pyrocam::mlp_training
