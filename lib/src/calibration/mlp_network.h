// The network as training sees it: weights and biases in a chosen scalar type, forward and
// backward passes over columns of samples, and its parameters as one vector (for L-BFGS).
// Header-only: templates over the scalar; training uses TrainingScalar.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <limits>
#include <vector>

namespace pyrocam::mlp_training {

// Training runs in single precision: twice the speed of double where Eigen has only SSE2. Its
// rounding stops the polish near a training rmse of 0.02-0.03 degC on the locus, far below the
// half-degree target; the output layer's least squares run in double.
using TrainingScalar = float;

// Samples per chunk in evaluate()'s passes (as the batch inference path's chunks): activations of
// the widest layer stay in L2.
constexpr Eigen::Index kEvaluationChunk = 256;

template <class S>
struct Network {
  using Matrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
  using Vector = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  std::vector<Matrix> weights;  // outputs x inputs
  std::vector<Vector> bias;
  std::size_t layer_count() const { return weights.size(); }
};

// Forward pass of columns of inputs into preallocated per-layer activations (acts[0] is the
// input block); returns the output row. Hidden layers ReLU, output linear.
template <class S>
void forward(const Network<S>& net, std::vector<typename Network<S>::Matrix>& acts,
             Eigen::Index cols, std::size_t first_layer = 0,
             std::size_t end_layer = std::numeric_limits<std::size_t>::max()) {
  const std::size_t layers = net.layer_count();
  for (std::size_t l = first_layer; l < std::min(layers, end_layer); ++l) {
    auto out = acts[l + 1].leftCols(cols);
    out.noalias() = net.weights[l] * acts[l].leftCols(cols);
    out.colwise() += net.bias[l];
    if (l + 1 < layers) out = out.cwiseMax(S(0));
  }
}

template <class S>
std::vector<typename Network<S>::Matrix> make_activations(const Network<S>& net,
                                                          Eigen::Index cols) {
  std::vector<typename Network<S>::Matrix> acts;
  acts.emplace_back(net.weights.front().cols(), cols);
  for (const auto& w : net.weights) acts.emplace_back(w.rows(), cols);
  return acts;
}

// Predictions (standardised units) for the columns of inputs.
template <class S>
Eigen::Matrix<S, 1, Eigen::Dynamic> evaluate(const Network<S>& net,
                                             const typename Network<S>::Matrix& inputs,
                                             std::vector<typename Network<S>::Matrix>& acts) {
  const Eigen::Index chunk = acts[0].cols();
  Eigen::Matrix<S, 1, Eigen::Dynamic> out(inputs.cols());
  for (Eigen::Index start = 0; start < inputs.cols(); start += chunk) {
    const Eigen::Index n = std::min(chunk, inputs.cols() - start);
    acts[0].leftCols(n) = inputs.middleCols(start, n);
    forward(net, acts, n);
    out.segment(start, n) = acts.back().row(0).leftCols(n);
  }
  return out;
}

// Backward pass after forward(): the gradient of the weighted mean squared error
// mean(w e^2) over the n columns into grad (same shapes as net); deltas has the activations'
// shapes. Returns the weighted sum of squared errors, sum(w e^2).
template <class S>
double backward(const Network<S>& net, const std::vector<typename Network<S>::Matrix>& acts,
                std::vector<typename Network<S>::Matrix>& deltas,
                const Eigen::Matrix<S, 1, Eigen::Dynamic>& targets,
                const Eigen::Matrix<S, 1, Eigen::Dynamic>& weights, Eigen::Index n,
                Network<S>& grad) {
  const std::size_t layers = net.layer_count();
  auto top = deltas[layers].leftCols(n);
  top = acts[layers].leftCols(n) - targets.leftCols(n);
  const double squared_error_sum =
      static_cast<double>((top.array().square() * weights.leftCols(n).array()).sum());
  // d mean(w e^2) / d output
  top.array() *= weights.leftCols(n).array() * (S(2) / static_cast<S>(n));
  for (std::size_t l = layers; l-- > 0;) {
    const auto delta = deltas[l + 1].leftCols(n);
    grad.weights[l].noalias() = delta * acts[l].leftCols(n).transpose();
    grad.bias[l] = delta.rowwise().sum();
    if (l > 0) {
      auto below = deltas[l].leftCols(n);
      below.noalias() = net.weights[l].transpose() * delta;
      // ReLU passes the gradient where its output was positive.
      below.array() *= (acts[l].leftCols(n).array() > S(0)).template cast<S>();
    }
  }
  return squared_error_sum;
}

template <class S>
Eigen::Index parameter_count(const Network<S>& net) {
  Eigen::Index count = 0;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    count += net.weights[l].size() + net.bias[l].size();
  }
  return count;
}

// All parameters in one vector (double whatever the network's scalar), layer by layer: weights
// column-major, then biases.
template <class S>
void flatten(const Network<S>& net, Eigen::VectorXd& theta) {
  theta.resize(parameter_count(net));
  Eigen::Index at = 0;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    theta.segment(at, net.weights[l].size()) = net.weights[l].reshaped().template cast<double>();
    at += net.weights[l].size();
    theta.segment(at, net.bias[l].size()) = net.bias[l].template cast<double>();
    at += net.bias[l].size();
  }
}

template <class S>
void unflatten(const Eigen::VectorXd& theta, Network<S>& net) {
  Eigen::Index at = 0;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    net.weights[l].reshaped() = theta.segment(at, net.weights[l].size()).template cast<S>();
    at += net.weights[l].size();
    net.bias[l] = theta.segment(at, net.bias[l].size()).template cast<S>();
    at += net.bias[l].size();
  }
}

// The network, its matrices and its rows (one value per sample) as training has them.
using TrainingNetwork = Network<TrainingScalar>;
using TrainingMatrix = TrainingNetwork::Matrix;
using TrainingRow = Eigen::Matrix<TrainingScalar, 1, Eigen::Dynamic>;

}  // namespace pyrocam::mlp_training
