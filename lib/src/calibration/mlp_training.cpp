// train_mlp: the training's stages in order (mlp_training_data, mlp_init, mlp_adam, mlp_polish),
// then the model and its report.
#include "pyrocam/calibration/mlp_training.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <utility>

#include "calibration/mlp_adam.h"
#include "calibration/mlp_augment.h"
#include "calibration/mlp_init.h"
#include "calibration/mlp_network.h"
#include "calibration/mlp_polish.h"
#include "calibration/mlp_training_data.h"
#include "detail/random.h"

namespace pyrocam {
namespace {

using namespace mlp_training;

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

// The report of a trained model: the curve, and its errors on the training rows, the held-out
// rows and the last set of augmented samples.
void write_report(const Mlp& model, const TrainingData& data, const AugmentedSamples& augmented,
                  TrainingCurve curve, int epochs, int polish_done,
                  std::chrono::steady_clock::time_point started, MlpTrainingReport* report) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Eigen::Index train_count = data.train_count, test_count = data.test_count;
  report->pass = std::move(curve.pass);
  report->train_rmse = std::move(curve.train_rmse);
  report->test_rmse = std::move(curve.test_rmse);
  report->train_samples = static_cast<int>(train_count);
  report->test_samples = static_cast<int>(test_count);
  report->epochs = epochs;
  report->polish_iterations_done = polish_done;
  const Eigen::VectorXd train_error = model.predict(data.x_train) - data.y_train;
  report->final_train_rmse =
      std::sqrt(train_error.squaredNorm() / static_cast<double>(train_count));
  report->max_abs_train_error = train_error.cwiseAbs().maxCoeff();
  if (test_count > 0) {
    const Eigen::VectorXd test_error = model.predict(data.x_test) - data.y_test;
    report->final_test_rmse = std::sqrt(test_error.squaredNorm() / static_cast<double>(test_count));
    report->max_abs_test_error = test_error.cwiseAbs().maxCoeff();
  } else {
    report->final_test_rmse = report->max_abs_test_error = nan;
  }
  report->augmented_samples = static_cast<int>(augmented.size());
  if (augmented.size() > 0) {
    const Eigen::VectorXd error = model.predict(augmented.inputs) - augmented.targets;
    report->augmented_rmse = std::sqrt(error.squaredNorm() / static_cast<double>(augmented.size()));
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

}  // namespace

Mlp train_mlp(const Eigen::MatrixXd& X, const Eigen::VectorXd& y, const MlpTrainingOptions& options,
              MlpTrainingReport* report) {
  const auto started = std::chrono::steady_clock::now();
  check_options(options);
  Random random(options.seed);
  const TrainingData data = prepare_training_data(X, y, options, random);
  TrainingNetwork net =
      initial_network(static_cast<int>(data.input_size), options.hidden, data.z_train_s, random);
  TrainingCurve curve;
  AugmentedSamples augmented;  // the last set made: the report's
  train_with_adam(net, data, options, random, augmented, curve);
  const int polish_done = polish(net, data, options, random, augmented, curve);

  std::vector<MlpLayer> model_layers;
  for (std::size_t l = 0; l < net.layer_count(); ++l) {
    model_layers.push_back(
        {net.weights[l].template cast<double>(), net.bias[l].template cast<double>()});
  }
  Mlp model(options.input_transform, data.input, options.output_transform, data.y_mean,
            data.y_scale, std::move(model_layers));
  if (report) {
    write_report(model, data, augmented, std::move(curve), options.epochs, polish_done, started,
                 report);
  }
  return model;
}

}  // namespace pyrocam
