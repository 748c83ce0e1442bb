#include "calibration/mlp_adam.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>

#include "detail/portable_math.h"

namespace pyrocam::mlp_training {
namespace {

// What Adam keeps between steps: its moments, the gradient and the batch's buffers.
struct AdamState {
  TrainingNetwork grad, m, v;
  std::vector<TrainingMatrix> acts;
  std::vector<TrainingMatrix> deltas;  // d loss / d pre-activation, same shapes
  TrainingRow batch_targets, batch_weights;
  long step = 0, total_steps = 0;

  AdamState(const TrainingNetwork& net, Eigen::Index batch)
      : grad(net),
        m(net),
        v(net),
        acts(make_activations(net, batch)),
        deltas(make_activations(net, batch)),
        batch_targets(batch),
        batch_weights(batch) {
    for (std::size_t l = 0; l < net.layer_count(); ++l) {
      m.weights[l].setZero(), m.bias[l].setZero();
      v.weights[l].setZero(), v.bias[l].setZero();
    }
  }
};

// Loads the n samples of train_order from start into the batch (indices below train_count are
// training rows, the rest augmented samples); returns the sum of their factors to target units
// (training rows only).
double load_batch(AdamState& s, const TrainingData& data, const AugmentedSamples& augmented,
                  const std::vector<Eigen::Index>& train_order, Eigen::Index start,
                  Eigen::Index n) {
  const Eigen::Index train_count = data.train_count;
  double factor_sum = 0;
  for (Eigen::Index k = 0; k < n; ++k) {
    const Eigen::Index src = train_order[static_cast<std::size_t>(start + k)];
    if (src < train_count) {
      s.acts[0].col(k) = data.z_train_s.col(src);
      s.batch_targets[k] = data.t_train_s[src];
      s.batch_weights[k] = data.loss_weights_s[src];
      factor_sum += data.to_target_units[src];
    } else {
      const Eigen::Index a = src - train_count;
      s.acts[0].col(k) = augmented.z.col(a);
      s.batch_targets[k] = augmented.t[a];
      s.batch_weights[k] = augmented.weights[a];
    }
  }
  return factor_sum;
}

// One Adam step of every layer with the gradient in s.grad, at s.step of the schedule.
void adam_update(TrainingNetwork& net, AdamState& s, const MlpTrainingOptions& options) {
  using S = TrainingScalar;
  const long step = s.step;
  const S lr = static_cast<S>(learning_rate_at(options, step, s.total_steps));
  const S bias1 = static_cast<S>(1 - portable::pow(0.9, static_cast<double>(step + 1)));
  const S bias2 = static_cast<S>(1 - portable::pow(0.999, static_cast<double>(step + 1)));
  const S decay = static_cast<S>(options.l2_weight_decay);
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    adam_step(net.weights[l], s.grad.weights[l], s.m.weights[l], s.v.weights[l], lr, bias1, bias2,
              decay);
    adam_step(net.bias[l], s.grad.bias[l], s.m.bias[l], s.v.bias[l], lr, bias1, bias2, S(0));
  }
}

// One pass over train_order in mini-batches of batch samples. Returns the sum of squared errors
// of the training rows in target units, to first order.
double adam_epoch(TrainingNetwork& net, AdamState& s, const TrainingData& data,
                  const AugmentedSamples& augmented, const std::vector<Eigen::Index>& train_order,
                  bool augmenting, Eigen::Index batch, const MlpTrainingOptions& options) {
  const Eigen::Index train_count = data.train_count;
  const std::size_t layers = net.layer_count();
  const auto epoch_count = static_cast<Eigen::Index>(train_order.size());
  double squared_error_sum = 0;  // in target units, to first order, of the training rows
  for (Eigen::Index start = 0; start < epoch_count; start += batch, ++s.step) {
    const Eigen::Index n = std::min(batch, epoch_count - start);
    const double factor_sum = load_batch(s, data, augmented, train_order, start, n);
    forward(net, s.acts, n);
    if (augmenting) {
      for (Eigen::Index k = 0; k < n; ++k) {
        const Eigen::Index src = train_order[static_cast<std::size_t>(start + k)];
        if (src >= train_count) continue;
        const double error = static_cast<double>(s.acts[layers](0, k) - s.batch_targets[k]);
        squared_error_sum += error * error * data.slope_squared[src];
      }
    }
    const double weighted_sum =
        backward(net, s.acts, s.deltas, s.batch_targets, s.batch_weights, n, s.grad);
    // Exact when the factor is the same for all samples (weighted loss), approximate else.
    if (!augmenting) squared_error_sum += weighted_sum * factor_sum / static_cast<double>(n);
    adam_update(net, s, options);
  }
  return squared_error_sum;
}

}  // namespace

double learning_rate_at(const MlpTrainingOptions& o, long step, long total_steps) {
  const long warmup = std::max(1L, std::lround(o.warmup_fraction * total_steps));
  if (step < warmup) return o.learning_rate * static_cast<double>(step + 1) / warmup;
  const long decay_steps = std::max(1L, total_steps - warmup);
  const double progress = std::min(1.0, static_cast<double>(step - warmup) / decay_steps);
  return o.final_learning_rate +
         0.5 * (o.learning_rate - o.final_learning_rate) * (1.0 + portable::cos(M_PI * progress));
}

void train_with_adam(TrainingNetwork& net, const TrainingData& data,
                     const MlpTrainingOptions& options, Random& random, AugmentedSamples& augmented,
                     TrainingCurve& curve) {
  const Eigen::Index train_count = data.train_count;
  const bool augmenting = static_cast<bool>(options.augment);
  const Eigen::Index batch = std::min<Eigen::Index>(options.batch_size, train_count);
  AdamState state(net, batch);
  auto eval_acts = make_activations(net, kEvaluationChunk);

  // The first epoch's augmented samples fix the schedule's length (later epochs have about as
  // many; the schedule holds its final rate should they have more).
  if (augmenting && options.epochs > 0) augmented = make_augmented(options, data, random.bits());
  const long steps_per_epoch =
      static_cast<long>((train_count + augmented.size() + batch - 1) / batch);
  state.total_steps = steps_per_epoch * options.epochs;
  // Indices below train_count are training rows, the rest augmented samples.
  std::vector<Eigen::Index> train_order(static_cast<std::size_t>(train_count));
  for (Eigen::Index i = 0; i < train_count; ++i) train_order[static_cast<std::size_t>(i)] = i;

  for (int epoch = 0; epoch < options.epochs; ++epoch) {
    if (augmenting) {
      if (epoch > 0) augmented = make_augmented(options, data, random.bits());
      train_order.resize(static_cast<std::size_t>(train_count + augmented.size()));
      for (std::size_t i = 0; i < train_order.size(); ++i) {
        train_order[i] = static_cast<Eigen::Index>(i);
      }
    }
    random.shuffle(train_order);
    const double squared_error_sum =
        adam_epoch(net, state, data, augmented, train_order, augmenting, batch, options);
    const double epoch_train_rmse = std::sqrt(squared_error_sum / static_cast<double>(train_count));
    if (!std::isfinite(epoch_train_rmse)) {
      throw MlpError("mlp: training diverged at epoch " + std::to_string(epoch + 1) +
                     "; lower learning_rate");
    }
    const double epoch_test_rmse = test_set_rmse(net, eval_acts, data, options.output_transform);
    curve.add(epoch + 1, epoch_train_rmse, epoch_test_rmse, options);
  }
}

}  // namespace pyrocam::mlp_training
