// Training of the network (pyrocam/runtime/mlp.h) on samples of the locus (Sala et al. 2025,
// section 2.7: MSE loss, Adam, batch 32, 70/30 train/test split), with a learning-rate schedule
// in place of the paper's constant 1e-5 and an L-BFGS polish. Stages: mlp_training_data.cpp
// (validation, split, standardisation), mlp_augment.cpp, mlp_init.cpp, mlp_adam.cpp,
// mlp_polish.cpp, mlp_report.cpp, orchestrated by mlp_training.cpp.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <vector>

#include "pyrocam/runtime/mlp.h"

namespace pyrocam {

// Training has two phases. Adam on mini-batches (the paper's optimiser, with a warm-up and
// cosine schedule in place of its constant 1e-5) starts from He-initialised weights whose hidden
// units each put their kink at a training sample. Then the polish: full-batch L-BFGS in which
// the output layer is solved by least squares at every step (variable projection), in rounds
// that reweight the samples towards the smallest maximum error. Calibration also trains on
// noisy single-pixel copies of the locus (`augment`, see noisy_locus.h), at a third of a locus
// sample's weight. On the noise-free 1 degC locus of calibrated models of the shipped cameras the
// defaults reach a max |error| of 0.29 degC (colour) and 0.11 degC (5x5) over 500-3500 degC, in
// 84 and 88 s on two cores, and single noisy pixels read within 1.5-1.8 degC rms of the
// likelihood fit (bench/mlp_locus.cpp). Without the copies the locus was fitted to 0.21 and
// 0.16 degC but noisy pixels read 36-190 degC rms away from that fit: the network was free off
// the locus. 400 Adam epochs and 200 plain L-BFGS iterations reached 0.6 and 0.4 degC.
// Samples added to the training set, never to the test set: inputs one row each (raw, as
// train_mlp()'s inputs), targets in target units.
struct MlpSamples {
  Eigen::MatrixXd inputs;
  Eigen::VectorXd targets;
};

struct MlpTrainingOptions {
  std::vector<int> hidden = {250, 200, 150, 100, 50};
  MlpInputTransform input_transform = MlpInputTransform::kLog;
  MlpOutputTransform output_transform = MlpOutputTransform::kInverseKelvin;
  // Weights each sample's squared error in network units by (d target / d network output)^2,
  // so that the loss is the mean squared error in target units (degC) to first order whatever
  // the output transform.
  bool loss_in_target_units = true;

  double test_fraction = 0.3;  // held out, never trained on; 0 allowed
  // Held-out samples evenly spaced in target order (from a random phase) instead of drawn at
  // random: each then lies between training samples, so that the held-out error measures the
  // fit between them and no run of untrained samples leaves a stretch of the locus unfitted.
  bool stratified_split = true;

  // Adam.
  int epochs = 1;  // 0: no Adam phase
  int batch_size = 32;
  // Per-step schedule: linear warm-up from 0 to learning_rate over the first warmup_fraction
  // of all steps, then half-cosine decay to final_learning_rate at the last step.
  double learning_rate = 1e-3;
  double final_learning_rate = 1e-6;
  double warmup_fraction = 0.02;
  // Decoupled (AdamW) weight decay per step, multiplied by the scheduled learning rate.
  double l2_weight_decay = 0;

  // The polish (0 iterations: Adam only, as in the paper). It stops early when no step lowers
  // the loss any more.
  int polish_iterations = 800;
  // Lawson reweighting rounds the iterations are split into (1: plain least squares).
  int polish_rounds = 3;
  // Added to the polish's loss (mean squared error in standardised units, about 1e-9 at the
  // end) times the sum of squared weights: discourages the sharp features that would fit the
  // training samples by bending between them.
  double polish_weight_decay = 1e-13;

  // Optional augmentation: extra samples made from the training rows (indices into the rows of
  // train_mlp()'s inputs; held-out rows are never among them), e.g. noisy copies of them with the
  // reading they should give. Called with a seed drawn from `seed`, once per Adam epoch (fresh
  // samples every epoch) and once for the polish, which keeps its samples. Without it the network
  // is trained on the inputs alone and its answer off them is whatever the fit left there.
  std::function<MlpSamples(const std::vector<Eigen::Index>& training_rows, std::uint64_t seed)>
      augment;
  // Loss weight of an augmented sample relative to a training row. The polish's reweighting
  // rounds reweight the training rows only.
  double augmented_weight = 0.3;

  std::uint64_t seed = 1;  // initial weights, split, batch order and augmentation seeds
  // Optional, called at every point of the training curve (see MlpTrainingReport) with its pass
  // number and train and test RMSE (target units).
  std::function<void(int pass, double train_rmse, double test_rmse)> progress;
};

struct MlpTrainingReport {
  // The training curve, in target units: a point after every Adam epoch, then one every 10
  // polish iterations and at the last. pass counts the passes over the training set so far (an
  // epoch, or an L-BFGS iteration, each). Adam's train_rmse is the mean over that epoch's
  // mini-batches (weights change during the epoch; it costs nothing), to first order in the
  // output transform, as is the polish's. Both are of the rows of the inputs only (augmented
  // samples are reported apart). test_rmse is evaluated at the point; NaN with no test set.
  std::vector<int> pass;
  std::vector<double> train_rmse, test_rmse;
  // Of the returned model, evaluated with predict() after training.
  double final_train_rmse = 0, final_test_rmse = 0, max_abs_test_error = 0;
  double max_abs_train_error = 0;
  double seconds = 0;  // wall time of train_mlp()
  int train_samples = 0, test_samples = 0;
  int epochs = 0;                  // Adam epochs run
  int polish_iterations_done = 0;  // fewer than asked when no step lowers the loss any more
  // Augmented samples trained on in the polish (0 without augmentation), and the returned
  // model's rmse and median absolute error on them (target units; NaN without).
  int augmented_samples = 0;
  double augmented_rmse = 0, augmented_median_abs_error = 0;
};

// inputs: one row per sample, targets: one per sample (degC). Deterministic: the same data,
// options and seed give bit-identical weights with the same build on the same CPU (Eigen's
// matrix product blocking follows the CPU's cache sizes). Throws MlpError on bad data or
// options, or when training diverges.
Mlp train_mlp(const Eigen::MatrixXd& inputs, const Eigen::VectorXd& targets,
              const MlpTrainingOptions& options, MlpTrainingReport* report = nullptr);

}  // namespace pyrocam
