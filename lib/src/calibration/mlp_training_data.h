// Training's first stage: the samples checked, transformed, split into training and held-out
// rows and standardised on the training rows; and the training curve the later stages add to.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "calibration/mlp_network.h"
#include "detail/random.h"
#include "pyrocam/calibration/mlp_training.h"

namespace pyrocam::mlp_training {

// The inputs through the input transform and the targets in network units, checked: shapes,
// finiteness and the transforms' domains. Throws MlpError.
struct TransformedSamples {
  Eigen::MatrixXd inputs;   // one row per sample
  Eigen::VectorXd targets;  // network units
};
TransformedSamples transform_samples(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                     const MlpTrainingOptions& options);

// The order of the samples after the split: the first test_count are held out, the rest
// trained on. Stratified (held-out samples evenly spaced in target order from a random phase,
// never the first or the last) or a shuffle; draws from random.
std::vector<Eigen::Index> split_order(const Eigen::VectorXd& y, Eigen::Index test_count,
                                      bool stratified, Random& random);

// The training and held-out sets as the later stages use them.
struct TrainingData {
  Eigen::Index input_size = 0;
  Eigen::Index train_count = 0, test_count = 0;
  // Rows of X trained on (what augmentation is called with), in the split's order.
  std::vector<Eigen::Index> training_rows;
  // Raw inputs and targets for the final report.
  Eigen::MatrixXd x_train, x_test;
  Eigen::VectorXd y_train, y_test;
  // Fitted on the training rows only, so that the test set stays unseen: the transformed inputs'
  // standardiser and the network output's mean and scale.
  Standardizer input;
  double y_mean = 0, y_scale = 1;
  // Samples as columns: each layer is then one matrix product per batch.
  TrainingMatrix z_train_s, z_test_s;
  Eigen::RowVectorXd t_train;  // standardised network targets of the training rows
  TrainingRow t_train_s;
  // (d target / d standardised output)^2 per training sample: what turns a squared error of the
  // network into one in target units. The loss weights are these over their mean (or 1).
  Eigen::RowVectorXd slope_squared;
  double mean_slope_squared = 0;
  Eigen::RowVectorXd loss_weights;
  TrainingRow loss_weights_s;
  // Per-sample factors from a weighted squared error (w e^2) to one in target units^2.
  Eigen::RowVectorXd to_target_units;
};

// Checks and transforms X and y, splits them (drawing from random) and standardises them.
// Throws MlpError on bad data or when no training sample is left.
TrainingData prepare_training_data(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                                   const MlpTrainingOptions& options, Random& random);

// RMSE (target units) of the network on the held-out rows; NaN with none. acts: evaluate()'s
// scratch.
double test_set_rmse(const TrainingNetwork& net, std::vector<TrainingMatrix>& acts,
                     const TrainingData& data, MlpOutputTransform output_transform);

// The training curve (see MlpTrainingReport).
struct TrainingCurve {
  std::vector<int> pass;
  std::vector<double> train_rmse, test_rmse;
  // Appends a point and calls options.progress with it, if set.
  void add(int pass_number, double train, double test, const MlpTrainingOptions& options);
};

}  // namespace pyrocam::mlp_training
