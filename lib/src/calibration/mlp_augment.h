// Training's augmentation stage: the samples MlpTrainingOptions::augment makes from the training
// rows, checked and prepared as the training rows are.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "calibration/mlp_network.h"
#include "calibration/mlp_training_data.h"
#include "pyrocam/calibration/mlp_training.h"

namespace pyrocam::mlp_training {

// Augmented samples, prepared as the training rows are: standardised inputs (columns) and
// targets, loss weights, and the factors to target units.
struct AugmentedSamples {
  Eigen::MatrixXd inputs;  // raw, one row each
  Eigen::VectorXd targets;
  TrainingMatrix z;
  TrainingRow t;
  TrainingRow weights;
  Eigen::RowVectorXd t_double, weights_double, slope_squared;
  Eigen::Index size() const { return targets.size(); }
};

// Calls options.augment(data.training_rows, seed) and prepares what it gives with data's
// standardisation. Throws MlpError on samples of the wrong shape, non-finite ones or ones
// outside the transforms' domains.
AugmentedSamples make_augmented(const MlpTrainingOptions& options, const TrainingData& data,
                                std::uint64_t seed);

}  // namespace pyrocam::mlp_training
