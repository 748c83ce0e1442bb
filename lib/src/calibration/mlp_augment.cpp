#include "calibration/mlp_augment.h"

#include <string>
#include <utility>

#include "detail/portable_math.h"
#include "pyrocam/core/physics.h"

namespace pyrocam::mlp_training {
namespace {

constexpr double kKelvinOffset = kZeroCelsius;

}  // namespace

AugmentedSamples make_augmented(const MlpTrainingOptions& options, const TrainingData& data,
                                std::uint64_t seed) {
  using S = TrainingScalar;
  const double y_mean = data.y_mean, y_scale = data.y_scale;
  const double mean_slope_squared = data.mean_slope_squared;
  AugmentedSamples a;
  MlpSamples samples = options.augment(data.training_rows, seed);
  const Eigen::Index count = samples.inputs.rows();
  if (samples.targets.size() != count || (count > 0 && samples.inputs.cols() != data.input_size)) {
    throw MlpError("mlp: augmentation gave " + std::to_string(count) + " samples of " +
                   std::to_string(samples.inputs.cols()) + " inputs and " +
                   std::to_string(samples.targets.size()) + " targets; need " +
                   std::to_string(data.input_size) + " inputs and one target each");
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
  a.z = data.input.apply(v).transpose().cast<S>();
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
}

}  // namespace pyrocam::mlp_training
