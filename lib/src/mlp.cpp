#include "pyrocam/mlp.h"

#include <Eigen/QR>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <chrono>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <utility>

namespace pyrocam {
namespace {

using json = nlohmann::json;

// Adam runs in single precision: twice the speed of double where Eigen has only SSE2, and its
// mini-batch noise (~1 degC) dwarfs float rounding. The L-BFGS polish that must resolve
// 0.5 degC (1.7e-4 of the span) runs in double.
#ifdef EXP_DOUBLE
using AdamScalar = double;
#else
using AdamScalar = float;
#endif

// Samples per chunk in the batch inference path: activations of the widest layer stay in L2.
constexpr Eigen::Index kInferenceChunk = 256;

// The standard library's distributions are implementation-defined; these are not, so a seed
// means the same model with any standard library.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double normal() {  // Box-Muller, one value per pair
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  // Uniform in [0, n); modulo bias is below 2^-40 for any n we shuffle.
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(engine_() % n); }
  template <class T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[below(i)]);
  }

 private:
  std::mt19937_64 engine_;
};

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
             Eigen::Index cols) {
  const std::size_t layers = net.layer_count();
  for (std::size_t l = 0; l < layers; ++l) {
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

// Backward pass after forward(): the gradient of the mean squared error over the n columns into
// grad (same shapes as net); deltas has the activations' shapes. Returns the sum of squared
// errors.
template <class S>
double backward(const Network<S>& net, const std::vector<typename Network<S>::Matrix>& acts,
                std::vector<typename Network<S>::Matrix>& deltas,
                const Eigen::Matrix<S, 1, Eigen::Dynamic>& targets, Eigen::Index n,
                Network<S>& grad) {
  const std::size_t layers = net.layer_count();
  auto top = deltas[layers].leftCols(n);
  top = acts[layers].leftCols(n) - targets.leftCols(n);
  const double squared_error_sum = static_cast<double>(top.squaredNorm());
  top *= S(2) / static_cast<S>(n);  // d mean(e^2) / d output
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

void flatten(const Network<double>& net, Eigen::VectorXd& theta) {
  theta.resize(parameter_count(net));
  Eigen::Index at = 0;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    theta.segment(at, net.weights[l].size()) = net.weights[l].reshaped();
    at += net.weights[l].size();
    theta.segment(at, net.bias[l].size()) = net.bias[l];
    at += net.bias[l].size();
  }
}

void unflatten(const Eigen::VectorXd& theta, Network<double>& net) {
  Eigen::Index at = 0;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    net.weights[l].reshaped() = theta.segment(at, net.weights[l].size());
    at += net.weights[l].size();
    net.bias[l] = theta.segment(at, net.bias[l].size());
    at += net.bias[l].size();
  }
}

// Full-batch L-BFGS (two-loop recursion, Armijo backtracking) on the training set's mean squared
// error, from Adam's result. Mini-batch Adam stalls at a noise floor of about 1 degC on a
// noise-free locus; a few hundred quasi-Newton steps take it well below. Returns the number of
// iterations done (fewer when no step decreases the loss any more).
int polish_with_lbfgs(Network<double>& net, const Eigen::MatrixXd& inputs,
                      const Eigen::RowVectorXd& targets, int iterations) {
  constexpr int kMemory = 10;
  constexpr double kArmijo = 1e-4;
  const Eigen::Index n = inputs.cols();
  auto acts = make_activations(net, n);
  auto deltas = make_activations(net, n);
  acts[0] = inputs;
  Network<double> grad = net;
  Eigen::VectorXd grad_flat;
  auto loss_and_gradient = [&](const Eigen::VectorXd& theta, Eigen::VectorXd& g) {
    unflatten(theta, net);
    forward(net, acts, n);
    const double sse = backward(net, acts, deltas, targets, n, grad);
    flatten(grad, g);
    return sse / static_cast<double>(n);
  };

  if (std::getenv("LSQ")) {
    forward(net, acts, n);
    const std::size_t L = net.layer_count();
    Eigen::MatrixXd A(n, acts[L - 1].rows() + 1);
    A.leftCols(acts[L - 1].rows()) = acts[L - 1].transpose();
    A.col(A.cols() - 1).setOnes();
    Eigen::VectorXd sol = A.colPivHouseholderQr().solve(targets.transpose());
    net.weights[L - 1].row(0) = sol.head(sol.size() - 1).transpose();
    net.bias[L - 1][0] = sol[sol.size() - 1];
    forward(net, acts, n);
    std::fprintf(stderr, "after lsq loss %.4e\n", (acts[L].row(0) - targets).squaredNorm() / n);
  }
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
    if (std::getenv("DBG") && done % 10 == 0) std::fprintf(stderr, "it %d loss %.4e step %g hist %zu\n", done, loss, step * 2, s_history.size());
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
         0.5 * (o.learning_rate - o.final_learning_rate) * (1.0 + std::cos(M_PI * progress));
}

void check_options(const MlpTrainingOptions& o) {
  for (int width : o.hidden) {
    if (width < 1 || width > kMlpMaxLayerWidth) {
      throw MlpError("mlp: hidden layer width " + std::to_string(width) + " outside 1.." +
                     std::to_string(kMlpMaxLayerWidth));
    }
  }
  if (o.epochs < 1) throw MlpError("mlp: epochs must be at least 1");
  if (o.polish_iterations < 0) throw MlpError("mlp: polish_iterations must be >= 0");
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
    throw MlpError("mlp json: " + where + " is not a number (" + std::string(j.type_name()) +
                   ")");
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
  if (!j.is_array() || j.empty()) throw MlpError("mlp json: " + where + " is not a non-empty array of rows");
  const std::size_t cols = j[0].is_array() ? j[0].size() : 0;
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

json to_json_array(const Eigen::VectorXd& v) { return json(std::vector<double>(v.data(), v.data() + v.size())); }

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
  using S = AdamScalar;
  using Matrix = Network<S>::Matrix;
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
        transformed(r, c) = std::log(X(r, c));
      }
    }
  }
  const Eigen::Index samples = X.rows();
  const auto test_count =
      static_cast<Eigen::Index>(std::lround(options.test_fraction * static_cast<double>(samples)));
  const Eigen::Index train_count = samples - test_count;
  if (train_count < 1) throw MlpError("mlp: no training samples left after the test split");

  Random random(options.seed);
  std::vector<Eigen::Index> order(static_cast<std::size_t>(samples));
  for (Eigen::Index i = 0; i < samples; ++i) order[static_cast<std::size_t>(i)] = i;
  random.shuffle(order);
  // Raw inputs for the final report, transformed ones for training.
  Eigen::MatrixXd x_train(train_count, X.cols()), x_test(test_count, X.cols());
  Eigen::MatrixXd v_train(train_count, X.cols()), v_test(test_count, X.cols());
  Eigen::VectorXd y_train(train_count), y_test(test_count);
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
    }
  }
  // Standardise on the training rows only, so that the test set stays unseen.
  const Standardizer input = Standardizer::fit(v_train);
  const Standardizer output = Standardizer::fit(y_train);
  const double y_mean = output.mean[0], y_scale = output.scale[0];
  // Samples as columns: each layer is then one matrix product per batch.
  const Eigen::MatrixXd z_train = input.apply(v_train).transpose();
  const Eigen::RowVectorXd t_train = ((y_train.array() - y_mean) / y_scale).matrix().transpose();
  const Matrix z_train_s = z_train.cast<S>();
  const Matrix z_test_s = input.apply(v_test).transpose().cast<S>();
  const Eigen::Matrix<S, 1, Eigen::Dynamic> t_train_s = t_train.cast<S>();

  // He initialisation for ReLU layers, variance 1/fan_in for the linear output; zero biases.
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
  if (!std::getenv("NOKINK")) {
    // Data-dependent biases: each hidden unit's kink passes through a random training sample, so
    // that the kinks spread along the data instead of all crossing the origin, and no unit starts
    // dead.
    Matrix a = z_train_s;
    for (std::size_t l = 0; l + 1 < layers; ++l) {
      Matrix z = net.weights[l] * a;
      for (Eigen::Index i = 0; i < z.rows(); ++i) {
        net.bias[l][i] = -z(i, static_cast<Eigen::Index>(random.below(static_cast<std::size_t>(train_count))));
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
  Eigen::Matrix<S, 1, Eigen::Dynamic> batch_targets(batch);

  const long steps_per_epoch = static_cast<long>((train_count + batch - 1) / batch);
  const long total_steps = steps_per_epoch * options.epochs;
  long step = 0;
  std::vector<Eigen::Index> train_order(static_cast<std::size_t>(train_count));
  for (Eigen::Index i = 0; i < train_count; ++i) train_order[static_cast<std::size_t>(i)] = i;
  std::vector<double> train_rmse, test_rmse;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto test_set_rmse = [&](const auto& network, auto& activations, const auto& z_test) {
    if (test_count == 0) return nan;
    const auto predicted = evaluate(network, z_test, activations);
    const Eigen::VectorXd error =
        (predicted.transpose().template cast<double>().array() * y_scale + y_mean).matrix() -
        y_test;
    return std::sqrt(error.squaredNorm() / static_cast<double>(test_count));
  };

  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    random.shuffle(train_order);
    double squared_error_sum = 0;
    for (Eigen::Index start = 0; start < train_count; start += batch, ++step) {
      const Eigen::Index n = std::min(batch, train_count - start);
      for (Eigen::Index k = 0; k < n; ++k) {
        const Eigen::Index src = train_order[static_cast<std::size_t>(start + k)];
        acts[0].col(k) = z_train_s.col(src);
        batch_targets[k] = t_train_s[src];
      }
      forward(net, acts, n);
      squared_error_sum += backward(net, acts, deltas, batch_targets, n, grad);
      const S lr = static_cast<S>(learning_rate_at(options, step, total_steps));
      const S bias1 = static_cast<S>(1 - std::pow(0.9, static_cast<double>(step + 1)));
      const S bias2 = static_cast<S>(1 - std::pow(0.999, static_cast<double>(step + 1)));
      const S decay = static_cast<S>(options.l2_weight_decay);
      for (std::size_t l = 0; l < layers; ++l) {
        adam_step(net.weights[l], grad.weights[l], adam_m.weights[l], adam_v.weights[l], lr, bias1,
                  bias2, decay);
        adam_step(net.bias[l], grad.bias[l], adam_m.bias[l], adam_v.bias[l], lr, bias1, bias2,
                  S(0));
      }
    }
    const double epoch_train_rmse =
        std::sqrt(squared_error_sum / static_cast<double>(train_count)) * y_scale;
    if (!std::isfinite(epoch_train_rmse)) {
      throw MlpError("mlp: training diverged at epoch " + std::to_string(epoch + 1) +
                     "; lower learning_rate");
    }
    const double epoch_test_rmse = test_set_rmse(net, eval_acts, z_test_s);
    train_rmse.push_back(epoch_train_rmse);
    test_rmse.push_back(epoch_test_rmse);
    if (options.progress) options.progress(epoch + 1, epoch_train_rmse, epoch_test_rmse);
  }

  Network<double> net_double;
  for (std::size_t l = 0; l < layers; ++l) {
    net_double.weights.push_back(net.weights[l].template cast<double>());
    net_double.bias.push_back(net.bias[l].template cast<double>());
  }
  int polish_done = 0;
  if (options.polish_iterations > 0) {
    polish_done = polish_with_lbfgs(net_double, z_train, t_train, options.polish_iterations);
  }

  std::vector<MlpLayer> model_layers;
  for (std::size_t l = 0; l < layers; ++l) {
    model_layers.push_back({std::move(net_double.weights[l]), std::move(net_double.bias[l])});
  }
  Mlp model(options.input_transform, input, y_mean, y_scale, std::move(model_layers));

  if (report) {
    report->train_rmse = std::move(train_rmse);
    report->test_rmse = std::move(test_rmse);
    report->train_samples = static_cast<int>(train_count);
    report->test_samples = static_cast<int>(test_count);
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
    report->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  }
  return model;
}

// ---------------------------------------------------------------- model

Mlp::Mlp(MlpInputTransform input_transform, Standardizer input, double output_mean,
         double output_scale, std::vector<MlpLayer> layers)
    : input_transform_(input_transform),
      input_(std::move(input)),
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
  if (!input_.mean.allFinite() || !(input_.scale.array() > 0).all() ||
      !input_.scale.allFinite()) {
    throw MlpError("mlp: input_mean must be finite and input_scale finite and > 0");
  }
  if (!std::isfinite(output_mean_) || !(output_scale_ > 0) || !std::isfinite(output_scale_)) {
    throw MlpError("mlp: output_mean must be finite and output_scale finite and > 0");
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
    const double v = input_transform_ == MlpInputTransform::kLog ? std::log(x[j]) : x[j];
    const double standardised = (v - input_.mean[j]) * inverse_input_scale_[j];
    valid = valid && std::isfinite(standardised);  // log of <= 0 gives -inf or NaN
    z[j] = static_cast<T>(standardised);
  }
  return valid;
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
  const float z = w_out.row(0).dot(Eigen::Map<const Eigen::VectorXf>(in, w_out.cols())) +
                  bias_f_.back()[0];
  return static_cast<double>(z) * output_scale_ + output_mean_;
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
      for (Eigen::Index j = 0; j < inputs; ++j) sample[static_cast<std::size_t>(j)] = fetch(start + k, j);
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
                           ? static_cast<double>(a(0, k)) * output_scale_ + output_mean_
                           : std::numeric_limits<double>::quiet_NaN();
    }
  }
}

Eigen::VectorXd Mlp::predict(const Eigen::MatrixXd& X) const {
  if (X.cols() != input_.mean.size()) {
    throw MlpError("mlp: predict got " + std::to_string(X.cols()) + " inputs per sample, model has " +
                   std::to_string(input_.mean.size()));
  }
  Eigen::VectorXd out(X.rows());
  predict_chunked(
      X.rows(), [&X](Eigen::Index i, Eigen::Index j) { return X(i, j); }, out.data());
  return out;
}

void Mlp::predict_rows(const double* rows, Eigen::Index count, double* out) const {
  const Eigen::Index inputs = input_.mean.size();
  predict_chunked(
      count, [rows, inputs](Eigen::Index i, Eigen::Index j) { return rows[i * inputs + j]; },
      out);
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
  for (Eigen::Index j = 0; j < inputs; ++j) {
    // d log(x) / dx = 1 / x
    const double transform_slope = input_transform_ == MlpInputTransform::kLog ? 1.0 / x[j] : 1.0;
    grad_out[j] = g[j] * output_scale_ * inverse_input_scale_[j] * transform_slope;
  }
  return z * output_scale_ + output_mean_;
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
          {"input_transform", input_transform_ == MlpInputTransform::kLog ? "log" : "none"},
          {"input_mean", to_json_array(input_.mean)},
          {"input_scale", to_json_array(input_.scale)},
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
  if (!version.is_number_integer() || version.get<int>() != kMlpFormatVersion) {
    throw MlpError("mlp json: unsupported \"version\" " + version.dump() + ", expected " +
                   std::to_string(kMlpFormatVersion));
  }
  if (j.contains("activation") && j["activation"] != "relu") {
    throw MlpError("mlp json: unsupported \"activation\" " + j["activation"].dump() +
                   ", expected \"relu\"");
  }
  const json& transform = require(j, "input_transform", top);
  MlpInputTransform input_transform = MlpInputTransform::kNone;
  if (transform == "log") {
    input_transform = MlpInputTransform::kLog;
  } else if (transform != "none") {
    throw MlpError("mlp json: unsupported \"input_transform\" " + transform.dump() +
                   ", expected \"log\" or \"none\"");
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
  std::vector<MlpLayer> layers;
  for (std::size_t l = 0; l < layers_json.size(); ++l) {
    const std::string name = "layers[" + std::to_string(l) + "]";
    MlpLayer layer;
    layer.weights = read_matrix(require(layers_json[l], "weights", name), name + ".weights");
    layer.bias = read_vector(require(layers_json[l], "bias", name), name + ".bias");
    layers.push_back(std::move(layer));
  }
  try {
    return Mlp(input_transform, std::move(input), output_mean, output_scale, std::move(layers));
  } catch (const MlpError& e) {
    // Same message, marked as coming from the file.
    std::string message = e.what();
    if (message.rfind("mlp: ", 0) == 0) message = "mlp json: " + message.substr(5);
    throw MlpError(message);
  }
}

}  // namespace pyrocam
