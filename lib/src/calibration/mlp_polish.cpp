#include "calibration/mlp_polish.h"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace pyrocam::mlp_training {
namespace {

// The training curve gets a point every this many polish iterations (and at the last).
constexpr int kPolishReportInterval = 10;

// The polish's loss as a function of the hidden layers' parameters, the output layer fitted by
// least squares at every evaluation (variable projection).
class ProjectedLoss {
 public:
  ProjectedLoss(TrainingNetwork& net, const PolishProblem& problem)
      : net_(net),
        problem_(problem),
        n_(problem.inputs.cols()),
        layers_(net.layer_count()),
        acts_(make_activations(net, n_)),
        deltas_(make_activations(net, n_)),
        targets_(problem.targets.cast<float>()),
        weights_(problem.weights.cast<float>()),
        grad_(net),
        output_params(net.weights.back().size() + 1),
        output_at(parameter_count(net) - output_params) {
    acts_[0] = problem.inputs;
  }

  // Sets the output layer (in net and theta), returns the loss, its gradient into g.
  double operator()(Eigen::VectorXd& theta, Eigen::VectorXd& g) {
    TrainingNetwork& net = net_;
    const PolishProblem& problem = problem_;
    auto& acts = acts_;
    const std::size_t layers = layers_;
    const Eigen::Index n = n_;
    unflatten(theta, net);
    forward(net, acts, n, 0, layers - 1);
    fit_output_layer(net, acts[layers - 1], problem);
    theta.segment(output_at, output_params - 1) = net.weights.back().reshaped().cast<double>();
    theta[output_at + output_params - 1] = static_cast<double>(net.bias.back()[0]);
    forward(net, acts, n, layers - 1);
    const Eigen::Index reported = problem.reported;
    const Eigen::ArrayXd residual =
        (acts[layers].row(0).leftCols(reported) - targets_.leftCols(reported))
            .transpose()
            .cast<double>()
            .array();
    train_rmse = std::sqrt(
        (residual.square() * problem.slope_squared.leftCols(reported).transpose().array()).mean());
    const double sse = backward(net, acts, deltas_, targets_, weights_, n, grad_);
    double penalty = 0;
    if (problem.weight_decay > 0) {
      const auto decay = static_cast<float>(problem.weight_decay);
      for (std::size_t l = 0; l < layers; ++l) {
        penalty += problem.weight_decay * static_cast<double>(net.weights[l].squaredNorm());
        grad_.weights[l] += 2 * decay * net.weights[l];
      }
    }
    flatten(grad_, g);
    // The output layer is at its optimum: its gradient is zero but for rounding.
    g.segment(output_at, output_params).setZero();
    return sse / static_cast<double>(n) + penalty;
  }

 private:
  TrainingNetwork& net_;
  const PolishProblem& problem_;
  const Eigen::Index n_;
  const std::size_t layers_;
  std::vector<TrainingMatrix> acts_, deltas_;
  const Eigen::RowVectorXf targets_, weights_;
  TrainingNetwork grad_;

 public:
  // The output layer's parameters: the last output_params of the flattened vector.
  const Eigen::Index output_params, output_at;
  double train_rmse = 0;  // of the last evaluation, target units to first order
};

// The last steps and gradient changes L-BFGS keeps.
struct LbfgsHistory {
  static constexpr int kMemory = 30;
  std::vector<Eigen::VectorXd> s_history, y_history;
  std::vector<double> rho_history;
  std::vector<double> alpha = std::vector<double>(kMemory);
};

// The search direction -H g into direction (H from the history), or plain steepest descent
// with the history forgotten when that is no descent direction. Returns the slope g . direction.
double lbfgs_direction(LbfgsHistory& h, const Eigen::VectorXd& g, Eigen::VectorXd& direction) {
  auto& s_history = h.s_history;
  auto& y_history = h.y_history;
  auto& rho_history = h.rho_history;
  auto& alpha = h.alpha;
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
  return slope;
}

// Stores the step s and the gradient change y when they keep H positive definite, dropping the
// oldest pair beyond kMemory.
void remember_step(LbfgsHistory& h, Eigen::VectorXd s, Eigen::VectorXd y) {
  const double sy = s.dot(y);
  if (sy > 1e-12 * s.norm() * y.norm()) {  // keep H positive definite
    if (static_cast<int>(h.s_history.size()) == LbfgsHistory::kMemory) {
      h.s_history.erase(h.s_history.begin());
      h.y_history.erase(h.y_history.begin());
      h.rho_history.erase(h.rho_history.begin());
    }
    h.s_history.push_back(std::move(s));
    h.y_history.push_back(std::move(y));
    h.rho_history.push_back(1 / sy);
  }
}

}  // namespace

PolishProblem make_polish_problem(const TrainingData& data, const MlpTrainingOptions& options,
                                  const AugmentedSamples& augmented) {
  const Eigen::Index train_count = data.train_count;
  PolishProblem problem{data.z_train_s,
                        data.t_train,
                        data.loss_weights,
                        data.slope_squared,
                        options.polish_weight_decay,
                        train_count};
  if (augmented.size() > 0) {
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
  return problem;
}

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

int polish_with_lbfgs(TrainingNetwork& net, const PolishProblem& problem, int iterations,
                      const std::function<void(double train_rmse)>& on_iteration) {
  constexpr double kArmijo = 1e-4;
  ProjectedLoss loss_and_gradient(net, problem);
  const Eigen::Index output_at = loss_and_gradient.output_at;
  const Eigen::Index output_params = loss_and_gradient.output_params;
  Eigen::VectorXd x, g, x_next, g_next, direction;
  flatten(net, x);
  double loss = loss_and_gradient(x, g);
  LbfgsHistory history;
  int done = 0;
  for (; done < iterations; ++done) {
    const double slope = lbfgs_direction(history, g, direction);
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
    remember_step(history, std::move(s), std::move(y));
    x.swap(x_next);
    g.swap(g_next);
    loss = next_loss;
    on_iteration(loss_and_gradient.train_rmse);
  }
  unflatten(x, net);
  return done;
}

bool reweight_towards_minimax(const TrainingNetwork& net, const TrainingData& data,
                              MlpOutputTransform output_transform,
                              std::vector<TrainingMatrix>& acts, PolishProblem& problem) {
  const Eigen::Index train_count = data.train_count;
  const Eigen::RowVectorXf predicted = evaluate(net, data.z_train_s, acts);
  Eigen::ArrayXd error(train_count);
  for (Eigen::Index i = 0; i < train_count; ++i) {
    const double v = static_cast<double>(predicted[i]) * data.y_scale + data.y_mean;
    error[i] = std::abs(from_network_units(output_transform, v) - data.y_train[i]);
  }
  const double floor = error.maxCoeff() / 20;
  if (!(floor > 0)) return false;  // exact fit (or NaN): nothing to reweight
  for (Eigen::Index i = 0; i < train_count; ++i) {
    problem.weights[i] *= std::max(error[i], floor);
  }
  problem.weights.head(train_count) /= problem.weights.head(train_count).mean();
  return true;
}

int polish(TrainingNetwork& net, const TrainingData& data, const MlpTrainingOptions& options,
           Random& random, AugmentedSamples& augmented, TrainingCurve& curve) {
  // The polish, in rounds; between rounds each sample's weight is multiplied by its absolute
  // error (Lawson's iteration: the weighted least-squares fit tends to the minimax fit).
  const bool augmenting = options.augment && options.polish_iterations > 0;
  if (augmenting) augmented = make_augmented(options, data, random.bits());
  PolishProblem problem =
      make_polish_problem(data, options, augmenting ? augmented : AugmentedSamples{});
  auto eval_acts = make_activations(net, kEvaluationChunk);
  int polish_done = 0;
  const int pass_before_polish = options.epochs;
  auto record_polish_point = [&](double train) {
    const double test = test_set_rmse(net, eval_acts, data, options.output_transform);
    if (!std::isfinite(train)) throw MlpError("mlp: the polish diverged");
    curve.add(pass_before_polish + polish_done, train, test, options);
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
    if (round + 1 < options.polish_rounds &&
        !reweight_towards_minimax(net, data, options.output_transform, eval_acts, problem)) {
      break;
    }
  }
  if (polish_done % kPolishReportInterval != 0) record_polish_point(last_train);  // the last
  return polish_done;
}

}  // namespace pyrocam::mlp_training
