// Over 600 lines: the network's inference, its JSON form and its training (validation, split,
// augmentation, Adam, L-BFGS polish) in one file; splitting training into stage files is planned
// with the architecture issue.
#include "pyrocam/runtime/mlp.h"

#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <utility>

#include "detail/portable_math.h"
#include "pyrocam/core/physics.h"
#include "detail/random.h"

namespace pyrocam {
namespace {

using json = nlohmann::json;

// Training runs in single precision: twice the speed of double where Eigen has only SSE2. Its
// rounding stops the polish near a training rmse of 0.02-0.03 degC on the locus, far below the
// half-degree target; the output layer's least squares run in double.
using TrainingScalar = float;

constexpr double kKelvinOffset = kZeroCelsius;

// Target (degC) -> the network's output quantity.
double to_network_units(MlpOutputTransform t, double y) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return 1.0 / (y + kKelvinOffset);
    case MlpOutputTransform::kLogKelvin:
      return portable::log(y + kKelvinOffset);
    case MlpOutputTransform::kNone:
      break;
  }
  return y;
}

// The inverse of to_network_units; NaN where v is outside its range.
double from_network_units(MlpOutputTransform t, double v) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return v > 0 ? 1.0 / v - kKelvinOffset : std::numeric_limits<double>::quiet_NaN();
    case MlpOutputTransform::kLogKelvin: {
      const double y = portable::exp(v) - kKelvinOffset;
      return std::isfinite(y) ? y : std::numeric_limits<double>::quiet_NaN();
    }
    case MlpOutputTransform::kNone:
      break;
  }
  return v;
}

// d from_network_units / d v.
double target_slope(MlpOutputTransform t, double v) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return -1.0 / (v * v);
    case MlpOutputTransform::kLogKelvin:
      return portable::exp(v);
    case MlpOutputTransform::kNone:
      break;
  }
  return 1.0;
}

const char* to_string(MlpInputTransform t) { return t == MlpInputTransform::kLog ? "log" : "none"; }

const char* to_string(MlpOutputTransform t) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return "inverse_kelvin";
    case MlpOutputTransform::kLogKelvin:
      return "log_kelvin";
    case MlpOutputTransform::kNone:
      break;
  }
  return "none";
}

// Samples per chunk in the batch inference path: activations of the widest layer stay in L2.
constexpr Eigen::Index kInferenceChunk = 256;
// The training curve gets a point every this many polish iterations (and at the last).
constexpr int kPolishReportInterval = 10;

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

// What the polish minimises: the weighted mean squared error of the network on the training set
// (standardised units) plus weight_decay times the sum of squared weights (biases free).
struct PolishProblem {
  Eigen::MatrixXf inputs;            // standardised, one column per sample
  Eigen::RowVectorXd targets;        // standardised network outputs
  Eigen::RowVectorXd weights;        // per sample; mean 1 over the reported samples
  Eigen::RowVectorXd slope_squared;  // (target units per standardised output)^2, for reports
  double weight_decay = 0;
  // The training rmse is reported over the first this many samples (the training rows; the
  // augmented samples follow them).
  Eigen::Index reported = 0;
};

// The output layer (weights and bias) that minimises the polish's loss given the last hidden
// layer's activations (one column per sample): ridge least squares in double precision.
void fit_output_layer(Network<float>& net, const Eigen::MatrixXf& hidden,
                      const PolishProblem& problem) {
  const Eigen::Index n = problem.targets.size(), features = hidden.rows();
  const Eigen::VectorXd root_w = problem.weights.transpose().cwiseSqrt();
  const Eigen::Index ridge_rows = problem.weight_decay > 0 ? features : 0;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + ridge_rows, features + 1);
  a.topLeftCorner(n, features) =
      root_w.asDiagonal() * hidden.leftCols(n).transpose().cast<double>();
  a.topRightCorner(n, 1) = root_w;
  if (ridge_rows > 0) {
    // mean(w e^2) + decay |W|^2 = (|sqrt(w) e|^2 + |sqrt(n decay) W|^2) / n
    a.bottomLeftCorner(features, features)
        .diagonal()
        .setConstant(std::sqrt(static_cast<double>(n) * problem.weight_decay));
  }
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + ridge_rows);
  b.head(n) = root_w.cwiseProduct(problem.targets.transpose());
  // Column pivoting copes with dead units (zero columns).
  const Eigen::VectorXd solution = a.colPivHouseholderQr().solve(b);
  net.weights.back().row(0) = solution.head(features).transpose().cast<float>();
  net.bias.back()[0] = static_cast<float>(solution[features]);
}

// Full-batch L-BFGS (two-loop recursion, Armijo backtracking) from the network as it is, in
// single precision. The output layer is refitted by least squares at every evaluation
// (variable projection), so that L-BFGS moves the hidden layers only, against a loss in which
// the output layer is always optimal: far better conditioned than moving all layers at once.
// Calls on_iteration(train_rmse) after every iteration, the network at the new point, the rmse
// in target units to first order. Returns the number of iterations done: fewer than asked when
// no step lowers the loss any more (the limit of single precision).
template <class OnIteration>
int polish_with_lbfgs(Network<float>& net, const PolishProblem& problem, int iterations,
                      OnIteration on_iteration) {
  constexpr int kMemory = 30;
  constexpr double kArmijo = 1e-4;
  const Eigen::Index n = problem.inputs.cols();
  const std::size_t layers = net.layer_count();
  auto acts = make_activations(net, n);
  auto deltas = make_activations(net, n);
  acts[0] = problem.inputs;
  const Eigen::RowVectorXf targets = problem.targets.cast<float>();
  const Eigen::RowVectorXf weights = problem.weights.cast<float>();
  Network<float> grad = net;
  const Eigen::Index output_params = net.weights.back().size() + 1;
  const Eigen::Index output_at = parameter_count(net) - output_params;
  double train_rmse = 0;
  // Sets the output layer (in net and theta), returns the loss, its gradient into g.
  auto loss_and_gradient = [&](Eigen::VectorXd& theta, Eigen::VectorXd& g) {
    unflatten(theta, net);
    forward(net, acts, n, 0, layers - 1);
    fit_output_layer(net, acts[layers - 1], problem);
    theta.segment(output_at, output_params - 1) = net.weights.back().reshaped().cast<double>();
    theta[output_at + output_params - 1] = static_cast<double>(net.bias.back()[0]);
    forward(net, acts, n, layers - 1);
    const Eigen::Index reported = problem.reported;
    const Eigen::ArrayXd residual =
        (acts[layers].row(0).leftCols(reported) - targets.leftCols(reported))
            .transpose()
            .cast<double>()
            .array();
    train_rmse = std::sqrt(
        (residual.square() * problem.slope_squared.leftCols(reported).transpose().array()).mean());
    const double sse = backward(net, acts, deltas, targets, weights, n, grad);
    double penalty = 0;
    if (problem.weight_decay > 0) {
      const auto decay = static_cast<float>(problem.weight_decay);
      for (std::size_t l = 0; l < layers; ++l) {
        penalty += problem.weight_decay * static_cast<double>(net.weights[l].squaredNorm());
        grad.weights[l] += 2 * decay * net.weights[l];
      }
    }
    flatten(grad, g);
    // The output layer is at its optimum: its gradient is zero but for rounding.
    g.segment(output_at, output_params).setZero();
    return sse / static_cast<double>(n) + penalty;
  };

  Eigen::VectorXd x, g, x_next, g_next, direction;
  flatten(net, x);
  double loss = loss_and_gradient(x, g);
  std::vector<Eigen::VectorXd> s_history, y_history;
  std::vector<double> rho_history;
  std::vector<double> alpha(kMemory);
  int done = 0;
  for (; done < iterations; ++done) {
    // Two-loop recursion: direction = -H g with H from the last kMemory steps.
    direction = -g;
    const int stored = static_cast<int>(s_history.size());
    for (int i = stored - 1; i >= 0; --i) {
      alpha[i] = rho_history[i] * s_history[i].dot(direction);
      direction -= alpha[i] * y_history[i];
    }
    if (stored > 0) {
      direction *= s_history.back().dot(y_history.back()) / y_history.back().squaredNorm();
    } else {
      direction *= 1e-3 / std::max(1e-300, g.lpNorm<Eigen::Infinity>());  // cautious first step
    }
    for (int i = 0; i < stored; ++i) {
      const double beta = rho_history[i] * y_history[i].dot(direction);
      direction += (alpha[i] - beta) * s_history[i];
    }
    double slope = g.dot(direction);
    if (!(slope < 0)) {  // not a descent direction: forget the history, go downhill
      s_history.clear(), y_history.clear(), rho_history.clear();
      direction = -g * (1e-3 / std::max(1e-300, g.lpNorm<Eigen::Infinity>()));
      slope = g.dot(direction);
    }
    double step = 1, next_loss = 0;
    bool accepted = false;
    for (int halving = 0; halving < 30 && !accepted; ++halving, step *= 0.5) {
      x_next = x + step * direction;
      next_loss = loss_and_gradient(x_next, g_next);
      accepted = next_loss <= loss + kArmijo * step * slope;
    }
    if (!accepted) break;
    Eigen::VectorXd s = x_next - x, y = g_next - g;
    s.segment(output_at, output_params).setZero();  // set by least squares, not by the step
    const double sy = s.dot(y);
    if (sy > 1e-12 * s.norm() * y.norm()) {  // keep H positive definite
      if (static_cast<int>(s_history.size()) == kMemory) {
        s_history.erase(s_history.begin());
        y_history.erase(y_history.begin());
        rho_history.erase(rho_history.begin());
      }
      s_history.push_back(std::move(s));
      y_history.push_back(std::move(y));
      rho_history.push_back(1 / sy);
    }
    x.swap(x_next);
    g.swap(g_next);
    loss = next_loss;
    on_iteration(train_rmse);
  }
  unflatten(x, net);
  return done;
}

double learning_rate_at(const MlpTrainingOptions& o, long step, long total_steps) {
  const long warmup = std::max(1L, std::lround(o.warmup_fraction * total_steps));
  if (step < warmup) return o.learning_rate * static_cast<double>(step + 1) / warmup;
  const long decay_steps = std::max(1L, total_steps - warmup);
  const double progress = std::min(1.0, static_cast<double>(step - warmup) / decay_steps);
  return o.final_learning_rate +
         0.5 * (o.learning_rate - o.final_learning_rate) * (1.0 + portable::cos(M_PI * progress));
}

void check_options(const MlpTrainingOptions& o) {
  if (o.hidden.size() + 1 > static_cast<std::size_t>(kMlpMaxLayers)) {
    throw MlpError("mlp: " + std::to_string(o.hidden.size()) + " hidden layers; at most " +
                   std::to_string(kMlpMaxLayers - 1));
  }
  for (int width : o.hidden) {
    if (width < 1 || width > kMlpMaxLayerWidth) {
      throw MlpError("mlp: hidden layer width " + std::to_string(width) + " outside 1.." +
                     std::to_string(kMlpMaxLayerWidth));
    }
  }
  if (o.epochs < 0) throw MlpError("mlp: epochs must be >= 0");
  if (o.polish_iterations < 0) throw MlpError("mlp: polish_iterations must be >= 0");
  if (o.polish_rounds < 1) throw MlpError("mlp: polish_rounds must be at least 1");
  if (!(o.polish_weight_decay >= 0)) throw MlpError("mlp: polish_weight_decay must be >= 0");
  if (o.batch_size < 1) throw MlpError("mlp: batch_size must be at least 1");
  if (!(o.learning_rate > 0) || !(o.final_learning_rate >= 0) ||
      !(o.final_learning_rate <= o.learning_rate)) {
    throw MlpError("mlp: need 0 <= final_learning_rate <= learning_rate, learning_rate > 0");
  }
  if (!(o.warmup_fraction >= 0 && o.warmup_fraction < 1)) {
    throw MlpError("mlp: warmup_fraction must be in [0, 1)");
  }
  if (!(o.l2_weight_decay >= 0)) throw MlpError("mlp: l2_weight_decay must be >= 0");
  if (!(o.test_fraction >= 0 && o.test_fraction < 1)) {
    throw MlpError("mlp: test_fraction must be in [0, 1)");
  }
}

// One Adam step on a parameter block (AdamW decay when decay > 0).
template <class Param, class Grad, class S>
void adam_step(Param& p, const Grad& g, Param& m, Param& v, S lr, S bias1, S bias2, S decay) {
  constexpr S kBeta1 = S(0.9), kBeta2 = S(0.999), kEpsilon = S(1e-8);
  m.array() = kBeta1 * m.array() + (1 - kBeta1) * g.array();
  v.array() = kBeta2 * v.array() + (1 - kBeta2) * g.array().square();
  if (decay > 0) p.array() *= 1 - lr * decay;
  p.array() -= lr * (m.array() / bias1) / ((v.array() / bias2).sqrt() + kEpsilon);
}

// A number in messages: "1e+06", "1e+308", "0.5".
std::string to_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// ---- JSON reading with messages that say where the problem is ----

const json& require(const json& j, const char* key, const std::string& where) {
  if (!j.is_object()) throw MlpError("mlp json: " + where + " is not an object");
  const auto it = j.find(key);
  if (it == j.end()) {
    throw MlpError("mlp json: missing key \"" + std::string(key) + "\" in " + where);
  }
  return *it;
}

double read_number(const json& j, const std::string& where) {
  if (!j.is_number()) {
    throw MlpError("mlp json: " + where + " is not a number (" + std::string(j.type_name()) + ")");
  }
  const double value = j.get<double>();
  if (!std::isfinite(value)) throw MlpError("mlp json: " + where + " is not finite (NaN or inf)");
  return value;
}

Eigen::VectorXd read_vector(const json& j, const std::string& where) {
  if (!j.is_array()) throw MlpError("mlp json: " + where + " is not an array");
  Eigen::VectorXd v(static_cast<Eigen::Index>(j.size()));
  for (std::size_t i = 0; i < j.size(); ++i) {
    v[static_cast<Eigen::Index>(i)] = read_number(j[i], where + "[" + std::to_string(i) + "]");
  }
  return v;
}

Eigen::MatrixXd read_matrix(const json& j, const std::string& where) {
  if (!j.is_array() || j.empty())
    throw MlpError("mlp json: " + where + " is not a non-empty array of rows");
  const std::size_t cols = j[0].is_array() ? j[0].size() : 0;
  // Bounded before the matrix is allocated from the two sizes.
  const auto limit = static_cast<std::size_t>(kMlpMaxLayerWidth);
  if (j.size() > limit || cols > limit) {
    throw MlpError("mlp json: " + where + " is " + std::to_string(j.size()) + " x " +
                   std::to_string(cols) + "; a layer is at most " + std::to_string(limit) +
                   " wide");
  }
  Eigen::MatrixXd m(static_cast<Eigen::Index>(j.size()), static_cast<Eigen::Index>(cols));
  for (std::size_t r = 0; r < j.size(); ++r) {
    const std::string row_where = where + "[" + std::to_string(r) + "]";
    const Eigen::VectorXd row = read_vector(j[r], row_where);
    if (static_cast<std::size_t>(row.size()) != cols || cols == 0) {
      throw MlpError("mlp json: " + row_where + " has " + std::to_string(row.size()) +
                     " columns where row 0 has " + std::to_string(cols));
    }
    m.row(static_cast<Eigen::Index>(r)) = row.transpose();
  }
  return m;
}

json to_json_array(const Eigen::VectorXd& v) {
  return json(std::vector<double>(v.data(), v.data() + v.size()));
}

}  // namespace

// ---------------------------------------------------------------- Standardizer

Standardizer Standardizer::fit(const Eigen::MatrixXd& samples) {
  if (samples.rows() < 1) throw MlpError("mlp: cannot standardise zero samples");
  Standardizer s;
  s.mean = samples.colwise().mean().transpose();
  s.scale.resize(samples.cols());
  for (Eigen::Index c = 0; c < samples.cols(); ++c) {
    const double sd = std::sqrt((samples.col(c).array() - s.mean[c]).square().mean());
    s.scale[c] = sd > 1e-12 * std::max(1.0, std::abs(s.mean[c])) ? sd : 1.0;
  }
  return s;
}

Eigen::MatrixXd Standardizer::apply(const Eigen::MatrixXd& samples) const {
  return (samples.rowwise() - mean.transpose()).array().rowwise() / scale.transpose().array();
}

Eigen::MatrixXd Standardizer::invert(const Eigen::MatrixXd& standardized) const {
  return (standardized.array().rowwise() * scale.transpose().array()).matrix().rowwise() +
         mean.transpose();
}

// ---------------------------------------------------------------- training

Mlp Mlp::train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
               const MlpTrainingOptions& options, MlpTrainingReport* report) {
  using S = TrainingScalar;
  using Matrix = Network<S>::Matrix;
  using Row = Eigen::Matrix<S, 1, Eigen::Dynamic>;
  const auto started = std::chrono::steady_clock::now();
  check_options(options);
  if (X.rows() != y.size()) {
    throw MlpError("mlp: " + std::to_string(X.rows()) + " input rows but " +
                   std::to_string(y.size()) + " targets");
  }
  if (X.cols() < 1 || X.cols() > kMlpMaxLayerWidth) {
    throw MlpError("mlp: input size " + std::to_string(X.cols()) + " outside 1.." +
                   std::to_string(kMlpMaxLayerWidth));
  }
  if (!X.allFinite() || !y.allFinite()) throw MlpError("mlp: training data has NaN or inf");
  Eigen::MatrixXd transformed = X;
  if (options.input_transform == MlpInputTransform::kLog) {
    for (Eigen::Index c = 0; c < X.cols(); ++c) {
      for (Eigen::Index r = 0; r < X.rows(); ++r) {
        if (!(X(r, c) > 0)) {
          throw MlpError("mlp: the log input transform needs inputs > 0; sample " +
                         std::to_string(r) + " input " + std::to_string(c) + " is " +
                         std::to_string(X(r, c)));
        }
        transformed(r, c) = portable::log(X(r, c));
      }
    }
  }
  Eigen::VectorXd y_network(y.size());
  for (Eigen::Index r = 0; r < y.size(); ++r) {
    if (options.output_transform != MlpOutputTransform::kNone && !(y[r] > -kKelvinOffset)) {
      throw MlpError("mlp: the output transform \"" +
                     std::string(to_string(options.output_transform)) +
                     "\" needs targets above absolute zero (-273.15 degC); target " +
                     std::to_string(r) + " is " + std::to_string(y[r]));
    }
    y_network[r] = to_network_units(options.output_transform, y[r]);
  }
  const Eigen::Index samples = X.rows();
  const auto test_count =
      static_cast<Eigen::Index>(std::lround(options.test_fraction * static_cast<double>(samples)));
  const Eigen::Index train_count = samples - test_count;
  if (train_count < 1) throw MlpError("mlp: no training samples left after the test split");

  Random random(options.seed);
  std::vector<Eigen::Index> order(static_cast<std::size_t>(samples));
  for (Eigen::Index i = 0; i < samples; ++i) order[static_cast<std::size_t>(i)] = i;
  if (options.stratified_split && test_count > 0 && test_count <= samples - 2) {
    // Held-out samples evenly spaced in target order from a random phase, never the first or
    // the last: the ends are trained on, held-out samples lie between training ones.
    std::vector<Eigen::Index> by_target = order;
    std::stable_sort(by_target.begin(), by_target.end(),
                     [&y](Eigen::Index a, Eigen::Index b) { return y[a] < y[b]; });
    const double spacing =
        static_cast<double>(samples - 2) / static_cast<double>(test_count);  // >= 1
    const double phase = random.uniform();
    std::vector<char> held_out(static_cast<std::size_t>(samples), 0);
    for (Eigen::Index k = 0; k < test_count; ++k) {
      const auto rank = 1 + static_cast<std::size_t>((static_cast<double>(k) + phase) * spacing);
      held_out[std::min(rank, by_target.size() - 2)] = 1;
    }
    std::size_t next_test = 0, next_train = static_cast<std::size_t>(test_count);
    for (std::size_t i = 0; i < by_target.size(); ++i) {
      order[held_out[i] ? next_test++ : next_train++] = by_target[i];
    }
  } else {
    random.shuffle(order);
  }
  // Raw inputs and targets for the final report, transformed ones for training.
  Eigen::MatrixXd x_train(train_count, X.cols()), x_test(test_count, X.cols());
  Eigen::MatrixXd v_train(train_count, X.cols()), v_test(test_count, X.cols());
  Eigen::VectorXd y_train(train_count), y_test(test_count), w_train(train_count);
  for (Eigen::Index i = 0; i < samples; ++i) {
    const Eigen::Index src = order[static_cast<std::size_t>(i)];
    if (i < test_count) {
      x_test.row(i) = X.row(src);
      v_test.row(i) = transformed.row(src);
      y_test[i] = y[src];
    } else {
      x_train.row(i - test_count) = X.row(src);
      v_train.row(i - test_count) = transformed.row(src);
      y_train[i - test_count] = y[src];
      w_train[i - test_count] = y_network[src];
    }
  }
  // Standardise on the training rows only, so that the test set stays unseen.
  const Standardizer input = Standardizer::fit(v_train);
  const Standardizer output = Standardizer::fit(w_train);
  const double y_mean = output.mean[0], y_scale = output.scale[0];
  // Samples as columns: each layer is then one matrix product per batch.
  const Eigen::MatrixXd z_train = input.apply(v_train).transpose();
  const Eigen::RowVectorXd t_train = ((w_train.array() - y_mean) / y_scale).matrix().transpose();
  const Matrix z_train_s = z_train.cast<S>();
  const Matrix z_test_s = input.apply(v_test).transpose().cast<S>();
  const Row t_train_s = t_train.cast<S>();
  // (d target / d standardised output)^2 per training sample: what turns a squared error of the
  // network into one in target units. The loss weights are these over their mean (or 1).
  Eigen::RowVectorXd slope_squared(train_count);
  for (Eigen::Index i = 0; i < train_count; ++i) {
    const double slope = target_slope(options.output_transform, w_train[i]) * y_scale;
    slope_squared[i] = slope * slope;
  }
  const double mean_slope_squared = slope_squared.mean();
  const Eigen::RowVectorXd loss_weights =
      options.loss_in_target_units ? Eigen::RowVectorXd(slope_squared / mean_slope_squared)
                                   : Eigen::RowVectorXd::Ones(train_count);
  // Per-sample factors from a weighted squared error (w e^2) to one in target units^2.
  const Eigen::RowVectorXd to_target_units =
      options.loss_in_target_units ? Eigen::RowVectorXd::Constant(train_count, mean_slope_squared)
                                   : slope_squared;
  const Row loss_weights_s = loss_weights.cast<S>();

  // Augmented samples, prepared as the training rows are: standardised inputs (columns) and
  // targets, loss weights, and the factors to target units.
  struct Augmented {
    Eigen::MatrixXd inputs;  // raw, one row each
    Eigen::VectorXd targets;
    Matrix z;
    Row t;
    Row weights;
    Eigen::RowVectorXd t_double, weights_double, slope_squared;
    Eigen::Index size() const { return targets.size(); }
  };
  const std::vector<Eigen::Index> training_rows(order.begin() + test_count, order.end());
  const bool augmenting = static_cast<bool>(options.augment);
  auto make_augmented = [&](std::uint64_t augment_seed) {
    Augmented a;
    MlpSamples samples = options.augment(training_rows, augment_seed);
    const Eigen::Index count = samples.inputs.rows();
    if (samples.targets.size() != count || (count > 0 && samples.inputs.cols() != X.cols())) {
      throw MlpError("mlp: augmentation gave " + std::to_string(count) + " samples of " +
                     std::to_string(samples.inputs.cols()) + " inputs and " +
                     std::to_string(samples.targets.size()) + " targets; need " +
                     std::to_string(X.cols()) + " inputs and one target each");
    }
    if (!samples.inputs.allFinite() || !samples.targets.allFinite()) {
      throw MlpError("mlp: augmented samples have NaN or inf");
    }
    Eigen::MatrixXd v = samples.inputs;
    if (options.input_transform == MlpInputTransform::kLog) {
      if (!(samples.inputs.array() > 0).all()) {
        throw MlpError(
            "mlp: the log input transform needs inputs > 0; an augmented sample has "
            "an input <= 0");
      }
      v = samples.inputs.unaryExpr([](double x) { return portable::log(x); });
    }
    a.z = input.apply(v).transpose().cast<S>();
    a.t_double.resize(count), a.weights_double.resize(count), a.slope_squared.resize(count);
    for (Eigen::Index i = 0; i < count; ++i) {
      const double target = samples.targets[i];
      if (options.output_transform != MlpOutputTransform::kNone && !(target > -kKelvinOffset)) {
        throw MlpError("mlp: augmented target " + std::to_string(target) +
                       " degC is below absolute zero");
      }
      const double network = to_network_units(options.output_transform, target);
      a.t_double[i] = (network - y_mean) / y_scale;
      const double slope = target_slope(options.output_transform, network) * y_scale;
      a.slope_squared[i] = slope * slope;
      a.weights_double[i] =
          options.augmented_weight *
          (options.loss_in_target_units ? a.slope_squared[i] / mean_slope_squared : 1.0);
    }
    a.t = a.t_double.cast<S>();
    a.weights = a.weights_double.cast<S>();
    a.inputs = std::move(samples.inputs);
    a.targets = std::move(samples.targets);
    return a;
  };
  Augmented augmented;  // the last set made: the report's

  // He initialisation for ReLU layers, variance 1/fan_in for the linear output.
  Network<S> net;
  std::vector<int> widths{static_cast<int>(X.cols())};
  widths.insert(widths.end(), options.hidden.begin(), options.hidden.end());
  widths.push_back(1);
  for (std::size_t l = 0; l + 1 < widths.size(); ++l) {
    const bool is_output = l + 2 == widths.size();
    const double sd = std::sqrt((is_output ? 1.0 : 2.0) / widths[l]);
    Matrix w(widths[l + 1], widths[l]);
    // Row by row, the order the JSON lists them.
    for (Eigen::Index r = 0; r < w.rows(); ++r) {
      for (Eigen::Index c = 0; c < w.cols(); ++c) w(r, c) = static_cast<S>(sd * random.normal());
    }
    net.weights.push_back(std::move(w));
    net.bias.push_back(Network<S>::Vector::Zero(widths[l + 1]));
  }
  const std::size_t layers = net.layer_count();
  // Data-dependent hidden biases: each hidden unit's kink passes through a random training
  // sample, so that the kinks spread along the data instead of all crossing the origin, and no
  // unit starts dead. The output bias stays 0 (the target mean).
  {
    Matrix a = z_train_s;
    for (std::size_t l = 0; l + 1 < layers; ++l) {
      Matrix z = net.weights[l] * a;
      for (Eigen::Index i = 0; i < z.rows(); ++i) {
        const auto sample =
            static_cast<Eigen::Index>(random.below(static_cast<std::size_t>(train_count)));
        net.bias[l][i] = -z(i, sample);
      }
      z.colwise() += net.bias[l];
      a = z.cwiseMax(S(0));
    }
  }

  Network<S> grad = net, adam_m = net, adam_v = net;
  for (std::size_t l = 0; l < layers; ++l) {
    adam_m.weights[l].setZero(), adam_m.bias[l].setZero();
    adam_v.weights[l].setZero(), adam_v.bias[l].setZero();
  }
  const Eigen::Index batch = std::min<Eigen::Index>(options.batch_size, train_count);
  auto acts = make_activations(net, batch);
  auto deltas = make_activations(net, batch);  // d loss / d pre-activation, same shapes
  auto eval_acts = make_activations(net, kInferenceChunk);
  Row batch_targets(batch), batch_weights(batch);

  // The first epoch's augmented samples fix the schedule's length (later epochs have about as
  // many; the schedule holds its final rate should they have more).
  if (augmenting && options.epochs > 0) augmented = make_augmented(random.bits());
  const long steps_per_epoch =
      static_cast<long>((train_count + augmented.size() + batch - 1) / batch);
  const long total_steps = steps_per_epoch * options.epochs;
  long step = 0;
  // Indices below train_count are training rows, the rest augmented samples.
  std::vector<Eigen::Index> train_order(static_cast<std::size_t>(train_count));
  for (Eigen::Index i = 0; i < train_count; ++i) train_order[static_cast<std::size_t>(i)] = i;
  std::vector<int> pass;
  std::vector<double> train_rmse, test_rmse;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const MlpOutputTransform output_transform = options.output_transform;
  auto test_set_rmse = [&](const auto& network, auto& activations, const auto& z_test) {
    if (test_count == 0) return nan;
    const auto predicted = evaluate(network, z_test, activations);
    double squared_error_sum = 0;
    for (Eigen::Index i = 0; i < test_count; ++i) {
      const double v = static_cast<double>(predicted[i]) * y_scale + y_mean;
      const double error = from_network_units(output_transform, v) - y_test[i];
      squared_error_sum += error * error;
    }
    return std::sqrt(squared_error_sum / static_cast<double>(test_count));
  };

  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    if (augmenting) {
      if (epoch > 0) augmented = make_augmented(random.bits());
      train_order.resize(static_cast<std::size_t>(train_count + augmented.size()));
      for (std::size_t i = 0; i < train_order.size(); ++i) {
        train_order[i] = static_cast<Eigen::Index>(i);
      }
    }
    random.shuffle(train_order);
    const auto epoch_count = static_cast<Eigen::Index>(train_order.size());
    double squared_error_sum = 0;  // in target units, to first order, of the training rows
    for (Eigen::Index start = 0; start < epoch_count; start += batch, ++step) {
      const Eigen::Index n = std::min(batch, epoch_count - start);
      double factor_sum = 0;
      for (Eigen::Index k = 0; k < n; ++k) {
        const Eigen::Index src = train_order[static_cast<std::size_t>(start + k)];
        if (src < train_count) {
          acts[0].col(k) = z_train_s.col(src);
          batch_targets[k] = t_train_s[src];
          batch_weights[k] = loss_weights_s[src];
          factor_sum += to_target_units[src];
        } else {
          const Eigen::Index a = src - train_count;
          acts[0].col(k) = augmented.z.col(a);
          batch_targets[k] = augmented.t[a];
          batch_weights[k] = augmented.weights[a];
        }
      }
      forward(net, acts, n);
      if (augmenting) {
        for (Eigen::Index k = 0; k < n; ++k) {
          const Eigen::Index src = train_order[static_cast<std::size_t>(start + k)];
          if (src >= train_count) continue;
          const double error = static_cast<double>(acts[layers](0, k) - batch_targets[k]);
          squared_error_sum += error * error * slope_squared[src];
        }
      }
      const double weighted_sum =
          backward(net, acts, deltas, batch_targets, batch_weights, n, grad);
      // Exact when the factor is the same for all samples (weighted loss), approximate else.
      if (!augmenting) squared_error_sum += weighted_sum * factor_sum / static_cast<double>(n);
      const S lr = static_cast<S>(learning_rate_at(options, step, total_steps));
      const S bias1 = static_cast<S>(1 - portable::pow(0.9, static_cast<double>(step + 1)));
      const S bias2 = static_cast<S>(1 - portable::pow(0.999, static_cast<double>(step + 1)));
      const S decay = static_cast<S>(options.l2_weight_decay);
      for (std::size_t l = 0; l < layers; ++l) {
        adam_step(net.weights[l], grad.weights[l], adam_m.weights[l], adam_v.weights[l], lr, bias1,
                  bias2, decay);
        adam_step(net.bias[l], grad.bias[l], adam_m.bias[l], adam_v.bias[l], lr, bias1, bias2,
                  S(0));
      }
    }
    const double epoch_train_rmse = std::sqrt(squared_error_sum / static_cast<double>(train_count));
    if (!std::isfinite(epoch_train_rmse)) {
      throw MlpError("mlp: training diverged at epoch " + std::to_string(epoch + 1) +
                     "; lower learning_rate");
    }
    const double epoch_test_rmse = test_set_rmse(net, eval_acts, z_test_s);
    pass.push_back(epoch + 1);
    train_rmse.push_back(epoch_train_rmse);
    test_rmse.push_back(epoch_test_rmse);
    if (options.progress) options.progress(epoch + 1, epoch_train_rmse, epoch_test_rmse);
  }

  // The polish, in rounds; between rounds each sample's weight is multiplied by its absolute
  // error (Lawson's iteration: the weighted least-squares fit tends to the minimax fit), with a
  // floor of a twentieth of the largest error so that no sample drops out.
  PolishProblem problem{
      z_train_s, t_train, loss_weights, slope_squared, options.polish_weight_decay, train_count};
  if (augmenting && options.polish_iterations > 0) {
    augmented = make_augmented(random.bits());
    const Eigen::Index total = train_count + augmented.size();
    problem.inputs.conservativeResize(Eigen::NoChange, total);
    problem.inputs.rightCols(augmented.size()) = augmented.z;
    problem.targets.conservativeResize(total);
    problem.targets.tail(augmented.size()) = augmented.t_double;
    problem.weights.conservativeResize(total);
    problem.weights.tail(augmented.size()) = augmented.weights_double;
    problem.slope_squared.conservativeResize(total);
    problem.slope_squared.tail(augmented.size()) = augmented.slope_squared;
  }
  int polish_done = 0;
  const int pass_before_polish = options.epochs;
  auto record_polish_point = [&](double train) {
    const double test = test_set_rmse(net, eval_acts, z_test_s);
    if (!std::isfinite(train)) throw MlpError("mlp: the polish diverged");
    pass.push_back(pass_before_polish + polish_done);
    train_rmse.push_back(train);
    test_rmse.push_back(test);
    if (options.progress) options.progress(pass.back(), train, test);
  };
  double last_train = 0;
  for (int round = 0; round < options.polish_rounds && options.polish_iterations > 0; ++round) {
    const int budget = options.polish_iterations * (round + 1) / options.polish_rounds -
                       options.polish_iterations * round / options.polish_rounds;
    polish_with_lbfgs(net, problem, budget, [&](double train) {
      ++polish_done;
      last_train = train;
      if (polish_done % kPolishReportInterval == 0) record_polish_point(train);
    });
    if (round + 1 < options.polish_rounds) {
      const Eigen::RowVectorXf predicted = evaluate(net, z_train_s, eval_acts);
      Eigen::ArrayXd error(train_count);
      for (Eigen::Index i = 0; i < train_count; ++i) {
        const double v = static_cast<double>(predicted[i]) * y_scale + y_mean;
        error[i] = std::abs(from_network_units(output_transform, v) - y_train[i]);
      }
      const double floor = error.maxCoeff() / 20;
      if (!(floor > 0)) break;  // exact fit (or NaN): nothing to reweight
      for (Eigen::Index i = 0; i < train_count; ++i) {
        problem.weights[i] *= std::max(error[i], floor);
      }
      problem.weights.head(train_count) /= problem.weights.head(train_count).mean();
    }
  }
  if (polish_done % kPolishReportInterval != 0) record_polish_point(last_train);  // the last

  std::vector<MlpLayer> model_layers;
  for (std::size_t l = 0; l < layers; ++l) {
    model_layers.push_back(
        {net.weights[l].template cast<double>(), net.bias[l].template cast<double>()});
  }
  Mlp model(options.input_transform, input, options.output_transform, y_mean, y_scale,
            std::move(model_layers));

  if (report) {
    report->pass = std::move(pass);
    report->train_rmse = std::move(train_rmse);
    report->test_rmse = std::move(test_rmse);
    report->train_samples = static_cast<int>(train_count);
    report->test_samples = static_cast<int>(test_count);
    report->epochs = options.epochs;
    report->polish_iterations_done = polish_done;
    const Eigen::VectorXd train_error = model.predict(x_train) - y_train;
    report->final_train_rmse =
        std::sqrt(train_error.squaredNorm() / static_cast<double>(train_count));
    report->max_abs_train_error = train_error.cwiseAbs().maxCoeff();
    if (test_count > 0) {
      const Eigen::VectorXd test_error = model.predict(x_test) - y_test;
      report->final_test_rmse =
          std::sqrt(test_error.squaredNorm() / static_cast<double>(test_count));
      report->max_abs_test_error = test_error.cwiseAbs().maxCoeff();
    } else {
      report->final_test_rmse = report->max_abs_test_error = nan;
    }
    report->augmented_samples = static_cast<int>(augmented.size());
    if (augmented.size() > 0) {
      const Eigen::VectorXd error = model.predict(augmented.inputs) - augmented.targets;
      report->augmented_rmse =
          std::sqrt(error.squaredNorm() / static_cast<double>(augmented.size()));
      std::vector<double> abs_error(error.data(), error.data() + error.size());
      for (double& e : abs_error) e = std::abs(e);
      const auto middle = abs_error.begin() + static_cast<std::ptrdiff_t>(abs_error.size() / 2);
      std::nth_element(abs_error.begin(), middle, abs_error.end());
      report->augmented_median_abs_error = *middle;
    } else {
      report->augmented_rmse = report->augmented_median_abs_error = nan;
    }
    report->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  return model;
}

// ---------------------------------------------------------------- model

Mlp::Mlp(MlpInputTransform input_transform, Standardizer input, MlpOutputTransform output_transform,
         double output_mean, double output_scale, std::vector<MlpLayer> layers)
    : input_transform_(input_transform),
      input_(std::move(input)),
      output_transform_(output_transform),
      output_mean_(output_mean),
      output_scale_(output_scale),
      layers_(std::move(layers)) {
  check_and_prepare();
}

void Mlp::check_and_prepare() {
  if (layers_.empty()) throw MlpError("mlp: no layers");
  const Eigen::Index inputs = input_.mean.size();
  if (inputs < 1 || input_.scale.size() != inputs) {
    throw MlpError("mlp: input_mean has " + std::to_string(inputs) + " values, input_scale " +
                   std::to_string(input_.scale.size()) + "; need the same, at least 1");
  }
  if (!input_.mean.allFinite() || !(input_.scale.array() > 0).all() || !input_.scale.allFinite()) {
    throw MlpError("mlp: input_mean must be finite and input_scale finite and > 0");
  }
  if (!std::isfinite(output_mean_) || !(output_scale_ > 0) || !std::isfinite(output_scale_)) {
    throw MlpError("mlp: output_mean must be finite and output_scale finite and > 0");
  }
  const auto too_large = [](double v) { return !(std::abs(v) <= kMlpMaxAbsParameter); };
  if (input_.mean.unaryExpr(too_large).any() || input_.scale.unaryExpr(too_large).any() ||
      too_large(output_mean_) || too_large(output_scale_)) {
    throw MlpError("mlp: input_mean, input_scale, output_mean and output_scale must lie within +-" +
                   to_text(kMlpMaxAbsParameter));
  }
  if (layers_.size() > static_cast<std::size_t>(kMlpMaxLayers)) {
    throw MlpError("mlp: " + std::to_string(layers_.size()) + " layers; at most " +
                   std::to_string(kMlpMaxLayers) + " supported");
  }
  Eigen::Index width = inputs;
  max_width_ = static_cast<int>(inputs);
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    const auto& layer = layers_[l];
    const std::string name = "layers[" + std::to_string(l) + "]";
    if (layer.weights.cols() != width) {
      throw MlpError("mlp: " + name + ".weights has " + std::to_string(layer.weights.cols()) +
                     " columns, expected " + std::to_string(width) +
                     (l == 0 ? " (input size)" : " (outputs of the layer before)"));
    }
    if (layer.bias.size() != layer.weights.rows()) {
      throw MlpError("mlp: " + name + ".bias has " + std::to_string(layer.bias.size()) +
                     " values for " + std::to_string(layer.weights.rows()) + " weight rows");
    }
    if (!layer.weights.allFinite() || !layer.bias.allFinite()) {
      throw MlpError("mlp: " + name + " has a NaN or infinite weight or bias");
    }
    const double largest =
        std::max(layer.weights.cwiseAbs().maxCoeff(), layer.bias.cwiseAbs().maxCoeff());
    if (largest > kMlpMaxAbsParameter) {
      throw MlpError("mlp: " + name + " has a weight or bias of " + to_text(largest) +
                     "; trained networks stay within +-" + to_text(kMlpMaxAbsParameter));
    }
    width = layer.weights.rows();
    if (width < 1) throw MlpError("mlp: " + name + " has no outputs");
    max_width_ = std::max(max_width_, static_cast<int>(width));
  }
  if (width != 1) {
    throw MlpError("mlp: the last layer has " + std::to_string(width) + " outputs; need 1");
  }
  if (max_width_ > kMlpMaxLayerWidth) {
    throw MlpError("mlp: a layer is " + std::to_string(max_width_) + " wide; at most " +
                   std::to_string(kMlpMaxLayerWidth) + " supported");
  }
  inverse_input_scale_ = input_.scale.cwiseInverse();
  weights_f_.clear();
  bias_f_.clear();
  for (const auto& layer : layers_) {
    weights_f_.push_back(layer.weights.cast<float>());
    bias_f_.push_back(layer.bias.cast<float>());
  }
}

std::vector<int> Mlp::hidden_sizes() const {
  std::vector<int> sizes;
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    sizes.push_back(static_cast<int>(layers_[l].weights.rows()));
  }
  return sizes;
}

template <class T>
bool Mlp::standardise_input(const double* x, T* z) const {
  bool valid = true;
  for (Eigen::Index j = 0; j < input_.mean.size(); ++j) {
    const double v = input_transform_ == MlpInputTransform::kLog ? portable::log(x[j]) : x[j];
    const double standardised = (v - input_.mean[j]) * inverse_input_scale_[j];
    valid = valid && std::isfinite(standardised);  // log of <= 0 gives -inf or NaN
    z[j] = static_cast<T>(standardised);
  }
  return valid;
}

double Mlp::output_from_network(double z) const {
  return from_network_units(output_transform_, z * output_scale_ + output_mean_);
}

double Mlp::predict(const double* x) const {
  if (layers_.empty()) return std::numeric_limits<double>::quiet_NaN();
  alignas(64) float buffer_a[kMlpMaxLayerWidth];
  alignas(64) float buffer_b[kMlpMaxLayerWidth];
  float* in = buffer_a;
  float* out = buffer_b;
  if (!standardise_input(x, in)) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t layers = weights_f_.size();
  for (std::size_t l = 0; l + 1 < layers; ++l) {
    const Eigen::MatrixXf& w = weights_f_[l];
    Eigen::Map<Eigen::VectorXf> o(out, w.rows());
    o = bias_f_[l];
    // Column by column so that the inputs ReLU zeroed (about half) cost nothing.
    for (Eigen::Index j = 0; j < w.cols(); ++j) {
      if (in[j] != 0.0f) o.noalias() += in[j] * w.col(j);
    }
    o = o.cwiseMax(0.0f);
    std::swap(in, out);
  }
  const Eigen::MatrixXf& w_out = weights_f_.back();
  const float z =
      w_out.row(0).dot(Eigen::Map<const Eigen::VectorXf>(in, w_out.cols())) + bias_f_.back()[0];
  return output_from_network(static_cast<double>(z));
}

template <class Fetch>
void Mlp::predict_chunked(Eigen::Index count, Fetch fetch, double* out) const {
  if (layers_.empty()) {
    std::fill(out, out + count, std::numeric_limits<double>::quiet_NaN());
    return;
  }
  const Eigen::Index inputs = input_.mean.size();
  const Eigen::Index chunk = std::min(count, kInferenceChunk);
  Eigen::MatrixXf a(max_width_, chunk), b(max_width_, chunk);
  std::vector<double> sample(static_cast<std::size_t>(inputs));
  std::vector<char> valid(static_cast<std::size_t>(chunk));
  for (Eigen::Index start = 0; start < count; start += chunk) {
    const Eigen::Index n = std::min(chunk, count - start);
    for (Eigen::Index k = 0; k < n; ++k) {
      for (Eigen::Index j = 0; j < inputs; ++j)
        sample[static_cast<std::size_t>(j)] = fetch(start + k, j);
      valid[static_cast<std::size_t>(k)] = standardise_input(sample.data(), &a(0, k));
      if (!valid[static_cast<std::size_t>(k)]) a.col(k).head(inputs).setZero();
    }
    Eigen::Index width = inputs;
    for (std::size_t l = 0; l < weights_f_.size(); ++l) {
      const Eigen::MatrixXf& w = weights_f_[l];
      auto next = b.topLeftCorner(w.rows(), n);
      next.noalias() = w * a.topLeftCorner(width, n);
      next.colwise() += bias_f_[l];
      if (l + 1 < weights_f_.size()) next = next.cwiseMax(0.0f);
      width = w.rows();
      a.swap(b);
    }
    for (Eigen::Index k = 0; k < n; ++k) {
      out[start + k] = valid[static_cast<std::size_t>(k)]
                           ? output_from_network(static_cast<double>(a(0, k)))
                           : std::numeric_limits<double>::quiet_NaN();
    }
  }
}

Eigen::VectorXd Mlp::predict(const Eigen::MatrixXd& X) const {
  if (X.cols() != input_.mean.size()) {
    throw MlpError("mlp: predict got " + std::to_string(X.cols()) +
                   " inputs per sample, model has " + std::to_string(input_.mean.size()));
  }
  Eigen::VectorXd out(X.rows());
  predict_chunked(
      X.rows(), [&X](Eigen::Index i, Eigen::Index j) { return X(i, j); }, out.data());
  return out;
}

void Mlp::predict_rows(const double* rows, Eigen::Index count, double* out) const {
  const Eigen::Index inputs = input_.mean.size();
  predict_chunked(
      count, [rows, inputs](Eigen::Index i, Eigen::Index j) { return rows[i * inputs + j]; }, out);
}

double Mlp::predict_with_gradient(const double* x, double* grad_out) const {
  const Eigen::Index inputs = input_.mean.size();
  if (layers_.empty()) {
    std::fill(grad_out, grad_out + inputs, std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::quiet_NaN();
  }
  // Every hidden activation is kept for the backward pass; sized once per thread.
  thread_local std::vector<double> scratch;
  std::size_t needed = static_cast<std::size_t>(inputs) + 2 * static_cast<std::size_t>(max_width_);
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    needed += static_cast<std::size_t>(layers_[l].weights.rows());
  }
  if (scratch.size() < needed) scratch.resize(needed);

  double* z0 = scratch.data();
  if (!standardise_input(x, z0)) {
    std::fill(grad_out, grad_out + inputs, std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::quiet_NaN();
  }
  double* cursor = z0 + inputs;
  const double* in = z0;
  const std::size_t layers = layers_.size();
  for (std::size_t l = 0; l + 1 < layers; ++l) {
    const auto& layer = layers_[l];
    Eigen::Map<Eigen::VectorXd> o(cursor, layer.weights.rows());
    o.noalias() = layer.weights * Eigen::Map<const Eigen::VectorXd>(in, layer.weights.cols());
    o = (o + layer.bias).cwiseMax(0.0);
    in = cursor;
    cursor += layer.weights.rows();
  }
  const auto& last = layers_.back();
  const double z =
      last.weights.row(0).dot(Eigen::Map<const Eigen::VectorXd>(in, last.weights.cols())) +
      last.bias[0];

  // Backward: g = d z / d (activations of layer l), starting from the output row.
  double* g = cursor;
  double* g_below = cursor + max_width_;
  Eigen::Map<Eigen::VectorXd>(g, last.weights.cols()) = last.weights.row(0).transpose();
  const double* act_end = cursor;
  for (std::size_t l = layers - 1; l-- > 0;) {
    const auto& layer = layers_[l];
    const Eigen::Index outputs = layer.weights.rows();
    const double* act = act_end - outputs;
    Eigen::Map<Eigen::VectorXd> grad(g, outputs);
    grad.array() *= (Eigen::Map<const Eigen::ArrayXd>(act, outputs) > 0.0).cast<double>();
    Eigen::Map<Eigen::VectorXd>(g_below, layer.weights.cols()).noalias() =
        layer.weights.transpose() * grad;
    std::swap(g, g_below);
    act_end = act;
  }
  const double v = z * output_scale_ + output_mean_;
  const double output_slope = target_slope(output_transform_, v) * output_scale_;
  for (Eigen::Index j = 0; j < inputs; ++j) {
    // d log(x) / dx = 1 / x
    const double input_slope = input_transform_ == MlpInputTransform::kLog ? 1.0 / x[j] : 1.0;
    grad_out[j] = g[j] * output_slope * inverse_input_scale_[j] * input_slope;
  }
  const double y = from_network_units(output_transform_, v);
  if (std::isnan(y)) std::fill(grad_out, grad_out + inputs, y);
  return y;
}

// ---------------------------------------------------------------- JSON

json Mlp::to_json() const {
  if (layers_.empty()) throw MlpError("mlp: cannot write an empty model");
  json layers = json::array();
  for (const auto& layer : layers_) {
    json rows = json::array();
    for (Eigen::Index r = 0; r < layer.weights.rows(); ++r) {
      const Eigen::VectorXd row = layer.weights.row(r).transpose();
      rows.push_back(to_json_array(row));
    }
    layers.push_back({{"weights", std::move(rows)}, {"bias", to_json_array(layer.bias)}});
  }
  return {{"format", "pyrocam-mlp"},
          {"version", kMlpFormatVersion},
          {"activation", "relu"},
          {"input_transform", to_string(input_transform_)},
          {"input_mean", to_json_array(input_.mean)},
          {"input_scale", to_json_array(input_.scale)},
          {"output_transform", to_string(output_transform_)},
          {"output_mean", output_mean_},
          {"output_scale", output_scale_},
          {"layers", std::move(layers)}};
}

Mlp Mlp::from_json(const json& j) {
  const std::string top = "the MLP object";
  const json& format = require(j, "format", top);
  if (!format.is_string() || format.get<std::string>() != "pyrocam-mlp") {
    throw MlpError("mlp json: \"format\" is " + format.dump() + ", expected \"pyrocam-mlp\"");
  }
  const json& version = require(j, "version", top);
  if (!version.is_number_integer() || version.get<int>() < 1 ||
      version.get<int>() > kMlpFormatVersion) {
    throw MlpError("mlp json: unsupported \"version\" " + version.dump() +
                   ", this build reads 1 to " + std::to_string(kMlpFormatVersion));
  }
  const int format_version = version.get<int>();
  if (j.contains("activation") && j["activation"] != "relu") {
    throw MlpError("mlp json: unsupported \"activation\" " + j["activation"].dump() +
                   ", expected \"relu\"");
  }
  // Version 1 had no transforms: both were "none".
  MlpInputTransform input_transform = MlpInputTransform::kNone;
  MlpOutputTransform output_transform = MlpOutputTransform::kNone;
  if (format_version >= 2) {
    const json& in = require(j, "input_transform", top);
    if (in == to_string(MlpInputTransform::kLog)) {
      input_transform = MlpInputTransform::kLog;
    } else if (in != to_string(MlpInputTransform::kNone)) {
      throw MlpError("mlp json: unsupported \"input_transform\" " + in.dump() +
                     ", expected \"none\" or \"log\"");
    }
    const json& out = require(j, "output_transform", top);
    bool known = false;
    for (const auto t : {MlpOutputTransform::kNone, MlpOutputTransform::kInverseKelvin,
                         MlpOutputTransform::kLogKelvin}) {
      if (out == to_string(t)) output_transform = t, known = true;
    }
    if (!known) {
      throw MlpError("mlp json: unsupported \"output_transform\" " + out.dump() +
                     ", expected \"none\", \"inverse_kelvin\" or \"log_kelvin\"");
    }
  } else if (j.contains("input_transform") || j.contains("output_transform")) {
    throw MlpError("mlp json: version 1 has no transforms, yet the file names one");
  }
  Standardizer input;
  input.mean = read_vector(require(j, "input_mean", top), "input_mean");
  input.scale = read_vector(require(j, "input_scale", top), "input_scale");
  const double output_mean = read_number(require(j, "output_mean", top), "output_mean");
  const double output_scale = read_number(require(j, "output_scale", top), "output_scale");
  const json& layers_json = require(j, "layers", top);
  if (!layers_json.is_array() || layers_json.empty()) {
    throw MlpError("mlp json: \"layers\" must be a non-empty array");
  }
  if (layers_json.size() > static_cast<std::size_t>(kMlpMaxLayers)) {
    throw MlpError("mlp json: \"layers\" holds " + std::to_string(layers_json.size()) +
                   " layers; at most " + std::to_string(kMlpMaxLayers) + " supported");
  }
  std::vector<MlpLayer> layers;
  for (std::size_t l = 0; l < layers_json.size(); ++l) {
    const std::string name = "layers[" + std::to_string(l) + "]";
    MlpLayer layer;
    layer.weights = read_matrix(require(layers_json[l], "weights", name), name + ".weights");
    layer.bias = read_vector(require(layers_json[l], "bias", name), name + ".bias");
    layers.push_back(std::move(layer));
  }
  try {
    return Mlp(input_transform, std::move(input), output_transform, output_mean, output_scale,
               std::move(layers));
  } catch (const MlpError& e) {
    // Same message, marked as coming from the file.
    std::string message = e.what();
    if (message.rfind("mlp: ", 0) == 0) message = "mlp json: " + message.substr(5);
    throw MlpError(message);
  }
}

}  // namespace pyrocam
