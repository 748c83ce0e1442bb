#include "calibration/mlp_training_data.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "detail/portable_math.h"
#include "pyrocam/core/physics.h"

namespace pyrocam::mlp_training {
namespace {

constexpr double kKelvinOffset = kZeroCelsius;

}  // namespace

TransformedSamples transform_samples(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                     const MlpTrainingOptions& options) {
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
  return {std::move(transformed), std::move(y_network)};
}

std::vector<Eigen::Index> split_order(const Eigen::VectorXd& y, Eigen::Index test_count,
                                      bool stratified, Random& random) {
  const Eigen::Index samples = y.size();
  std::vector<Eigen::Index> order(static_cast<std::size_t>(samples));
  for (Eigen::Index i = 0; i < samples; ++i) order[static_cast<std::size_t>(i)] = i;
  if (stratified && test_count > 0 && test_count <= samples - 2) {
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
  return order;
}

TrainingData prepare_training_data(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                   const MlpTrainingOptions& options, Random& random) {
  using S = TrainingScalar;
  const TransformedSamples transformed_samples = transform_samples(X, y, options);
  const Eigen::MatrixXd& transformed = transformed_samples.inputs;
  const Eigen::VectorXd& y_network = transformed_samples.targets;
  const Eigen::Index samples = X.rows();
  const auto test_count =
      static_cast<Eigen::Index>(std::lround(options.test_fraction * static_cast<double>(samples)));
  const Eigen::Index train_count = samples - test_count;
  if (train_count < 1) throw MlpError("mlp: no training samples left after the test split");
  const std::vector<Eigen::Index> order =
      split_order(y, test_count, options.stratified_split, random);

  TrainingData d;
  d.input_size = X.cols();
  d.train_count = train_count;
  d.test_count = test_count;
  d.training_rows.assign(order.begin() + test_count, order.end());
  // Raw inputs and targets for the final report, transformed ones for training.
  d.x_train.resize(train_count, X.cols()), d.x_test.resize(test_count, X.cols());
  Eigen::MatrixXd v_train(train_count, X.cols()), v_test(test_count, X.cols());
  d.y_train.resize(train_count), d.y_test.resize(test_count);
  Eigen::VectorXd w_train(train_count);
  for (Eigen::Index i = 0; i < samples; ++i) {
    const Eigen::Index src = order[static_cast<std::size_t>(i)];
    if (i < test_count) {
      d.x_test.row(i) = X.row(src);
      v_test.row(i) = transformed.row(src);
      d.y_test[i] = y[src];
    } else {
      d.x_train.row(i - test_count) = X.row(src);
      v_train.row(i - test_count) = transformed.row(src);
      d.y_train[i - test_count] = y[src];
      w_train[i - test_count] = y_network[src];
    }
  }
  d.input = Standardizer::fit(v_train);
  const Standardizer output = Standardizer::fit(w_train);
  const double y_mean = d.y_mean = output.mean[0], y_scale = d.y_scale = output.scale[0];
  const Eigen::MatrixXd z_train = d.input.apply(v_train).transpose();
  d.t_train = ((w_train.array() - y_mean) / y_scale).matrix().transpose();
  d.z_train_s = z_train.cast<S>();
  d.z_test_s = d.input.apply(v_test).transpose().cast<S>();
  d.t_train_s = d.t_train.cast<S>();
  d.slope_squared.resize(train_count);
  for (Eigen::Index i = 0; i < train_count; ++i) {
    const double slope = target_slope(options.output_transform, w_train[i]) * y_scale;
    d.slope_squared[i] = slope * slope;
  }
  const double mean_slope_squared = d.mean_slope_squared = d.slope_squared.mean();
  d.loss_weights = options.loss_in_target_units
                       ? Eigen::RowVectorXd(d.slope_squared / mean_slope_squared)
                       : Eigen::RowVectorXd::Ones(train_count);
  d.to_target_units = options.loss_in_target_units
                          ? Eigen::RowVectorXd::Constant(train_count, mean_slope_squared)
                          : d.slope_squared;
  d.loss_weights_s = d.loss_weights.cast<S>();
  return d;
}

double test_set_rmse(const TrainingNetwork& net, std::vector<TrainingMatrix>& acts,
                     const TrainingData& data, MlpOutputTransform output_transform) {
  const Eigen::Index test_count = data.test_count;
  if (test_count == 0) return std::numeric_limits<double>::quiet_NaN();
  const auto predicted = evaluate(net, data.z_test_s, acts);
  double squared_error_sum = 0;
  for (Eigen::Index i = 0; i < test_count; ++i) {
    const double v = static_cast<double>(predicted[i]) * data.y_scale + data.y_mean;
    const double error = from_network_units(output_transform, v) - data.y_test[i];
    squared_error_sum += error * error;
  }
  return std::sqrt(squared_error_sum / static_cast<double>(test_count));
}

void TrainingCurve::add(int pass_number, double train, double test,
                        const MlpTrainingOptions& options) {
  pass.push_back(pass_number);
  train_rmse.push_back(train);
  test_rmse.push_back(test);
  if (options.progress) options.progress(pass_number, train, test);
}

}  // namespace pyrocam::mlp_training
