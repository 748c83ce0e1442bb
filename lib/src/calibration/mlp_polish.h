// Training's polish stage: full-batch L-BFGS in which the output layer is solved by least squares
// at every step (variable projection), in Lawson rounds that reweight the training rows towards
// the smallest maximum error.
#pragma once

#include <Eigen/Core>
#include <functional>

#include "calibration/mlp_augment.h"
#include "calibration/mlp_network.h"
#include "calibration/mlp_training_data.h"
#include "detail/random.h"
#include "pyrocam/calibration/mlp_training.h"

namespace pyrocam::mlp_training {

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

// The training rows of data, with options.polish_weight_decay, then the augmented samples (none
// when augmented is empty).
PolishProblem make_polish_problem(const TrainingData& data, const MlpTrainingOptions& options,
                                  const AugmentedSamples& augmented);

// The output layer (weights and bias) that minimises the polish's loss given the last hidden
// layer's activations (one column per sample): ridge least squares in double precision.
void fit_output_layer(TrainingNetwork& net, const Eigen::MatrixXf& hidden,
                      const PolishProblem& problem);

// Full-batch L-BFGS (two-loop recursion, Armijo backtracking) from the network as it is, in
// single precision. The output layer is refitted by least squares at every evaluation
// (variable projection), so that L-BFGS moves the hidden layers only, against a loss in which
// the output layer is always optimal: far better conditioned than moving all layers at once.
// Calls on_iteration(train_rmse) after every iteration, the network at the new point, the rmse
// in target units to first order. Returns the number of iterations done: fewer than asked when
// no step lowers the loss any more (the limit of single precision).
int polish_with_lbfgs(TrainingNetwork& net, const PolishProblem& problem, int iterations,
                      const std::function<void(double train_rmse)>& on_iteration);

// Lawson's iteration: multiplies each training row's weight by the network's absolute error on it
// (target units), with a floor of a twentieth of the largest error so that no sample drops out,
// and rescales them to mean 1. False, weights untouched, when the largest error is 0 or NaN.
bool reweight_towards_minimax(const TrainingNetwork& net, const TrainingData& data,
                              MlpOutputTransform output_transform,
                              std::vector<TrainingMatrix>& acts, PolishProblem& problem);

// The polish stage: options.polish_iterations L-BFGS iterations over options.polish_rounds
// Lawson rounds, on the training rows and (with options.augment) a fresh set of augmented
// samples drawn from random, which becomes augmented. Adds a point to curve every 10 iterations
// and at the last. Returns the iterations done. Throws MlpError when the polish diverges.
int polish(TrainingNetwork& net, const TrainingData& data, const MlpTrainingOptions& options,
           Random& random, AugmentedSamples& augmented, TrainingCurve& curve);

}  // namespace pyrocam::mlp_training
