// Dense ReLU multilayer perceptron regressor: normalised band ratios -> temperature
// (Sala et al. 2025, section 2.7: hidden layers 250-200-150-100-50, ReLU, MSE loss, Adam,
// batch 32, 70/30 train/test split), with input and output transforms (log ratios in, 1/T out),
// a learning-rate schedule in place of the paper's constant 1e-5, and an L-BFGS polish.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <stdexcept>
#include <vector>

namespace pyrocam {

struct MlpError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Written by to_json; from_json also reads version 1 (before the transforms).
inline constexpr int kMlpFormatVersion = 2;
// Widest layer (inputs included) the allocation-free single-sample path supports: its scratch
// lives on the stack.
inline constexpr int kMlpMaxLayerWidth = 1024;
// Most layers a network may have, and the largest magnitude of any weight, bias or
// standardisation number. Trained networks stay far inside (weights of order 1, set by weight
// decay); a file beyond these is corrupt, and its readings would be nonsense that looks valid.
inline constexpr int kMlpMaxLayers = 64;
inline constexpr double kMlpMaxAbsParameter = 1e6;

// Applied to each input before standardising. Band ratios vary over orders of magnitude along
// the Planck locus (blue/red spans 2 to 8000 between 500 and 3500 degC), so that standardised
// raw ratios crowd the hot end into a sliver of the input range; their logarithms are close to
// linear in 1/T and spread evenly. With kLog every input must be > 0; predictions for samples
// with an input <= 0 are NaN.
enum class MlpInputTransform { kNone, kLog };

// What the network's output unit stands for, the targets being temperatures in degC. By Wien's
// law the log band ratios are linear in 1/T (T in kelvin), nearly so for real bands, so with kLog
// inputs kInverseKelvin leaves the network only a small curvature to learn; kLogKelvin is halfway
// between that and kNone. The network's error in 1/T is amplified by T^2 in degC, which the
// training's loss weighting (MlpTrainingOptions::loss_in_target_units) accounts for.
// Predictions where the network's output leaves the transform's domain (1/T <= 0) are NaN.
enum class MlpOutputTransform { kNone, kInverseKelvin, kLogKelvin };

// Per-column affine map to zero mean and unit scale: z = (x - mean) / scale.
struct Standardizer {
  Eigen::VectorXd mean, scale;

  // Column means and population standard deviations of samples (one row per sample). A column
  // that is constant (std <= 1e-12 max(1, |mean|)) gets scale 1 so that it maps to 0, not inf.
  static Standardizer fit(const Eigen::MatrixXd& samples);
  Eigen::Index size() const { return mean.size(); }
  Eigen::MatrixXd apply(const Eigen::MatrixXd& samples) const;
  Eigen::MatrixXd invert(const Eigen::MatrixXd& standardized) const;
};

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
// train()'s X), targets in target units.
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

  // Optional augmentation: extra samples made from the training rows (indices into train()'s X;
  // held-out rows are never among them), e.g. noisy copies of them with the reading they should
  // give. Called with a seed drawn from `seed`, once per Adam epoch (fresh samples every epoch)
  // and once for the polish, which keeps its samples. Without it the network is trained on X
  // alone and its answer off the rows of X is whatever the fit left there.
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
  // output transform, as is the polish's. Both are of the rows of X only (augmented samples are
  // reported apart). test_rmse is evaluated at the point; NaN with no test set.
  std::vector<int> pass;
  std::vector<double> train_rmse, test_rmse;
  // Of the returned model, evaluated with predict() after training.
  double final_train_rmse = 0, final_test_rmse = 0, max_abs_test_error = 0;
  double max_abs_train_error = 0;
  double seconds = 0;  // wall time of train()
  int train_samples = 0, test_samples = 0;
  int epochs = 0;                  // Adam epochs run
  int polish_iterations_done = 0;  // fewer than asked when no step lowers the loss any more
  // Augmented samples trained on in the polish (0 without augmentation), and the returned
  // model's rmse and median absolute error on them (target units; NaN without).
  int augmented_samples = 0;
  double augmented_rmse = 0, augmented_median_abs_error = 0;
};

struct MlpLayer {
  Eigen::MatrixXd weights;  // outputs x inputs
  Eigen::VectorXd bias;     // outputs
};

// Immutable once built; every const member is safe to call from several threads at once.
class Mlp {
 public:
  Mlp() = default;  // empty: input_size() == 0, predictions NaN

  // X: one row per sample, y: one target per sample. Deterministic: the same data, options
  // and seed give bit-identical weights with the same build on the same CPU (Eigen's matrix
  // product blocking follows the CPU's cache sizes). Throws MlpError on bad data or options, or
  // when training diverges.
  static Mlp train(const Eigen::MatrixXd& X, const Eigen::VectorXd& y,
                   const MlpTrainingOptions& options, MlpTrainingReport* report = nullptr);

  // Builds a model from given parts (checked as from_json checks them).
  // output_mean and output_scale are of the transformed output.
  Mlp(MlpInputTransform input_transform, Standardizer input, MlpOutputTransform output_transform,
      double output_mean, double output_scale, std::vector<MlpLayer> layers);

  // One sample of input_size() values. Single precision inside (|error| ~1e-6 of the output
  // scale in network units, a few thousandths of a degree), no heap allocation: for per-pixel
  // use.
  double predict(const double* x) const;
  // Many samples, one row each, through matrix-matrix products in chunks; same precision.
  Eigen::VectorXd predict(const Eigen::MatrixXd& X) const;
  // count samples stored one after another (row-major count x input_size()), into out[count].
  void predict_rows(const double* rows, Eigen::Index count, double* out) const;

  // Double precision output and its gradient d output / d x (input_size() values into
  // grad_out), for uncertainty propagation. Allocation-free after a thread's first call.
  double predict_with_gradient(const double* x, double* grad_out) const;

  int input_size() const { return static_cast<int>(input_.size()); }
  bool empty() const { return layers_.empty(); }
  std::vector<int> hidden_sizes() const;
  const std::vector<MlpLayer>& layers() const { return layers_; }
  MlpInputTransform input_transform() const { return input_transform_; }
  // Of the transformed inputs.
  const Standardizer& input_standardizer() const { return input_; }
  MlpOutputTransform output_transform() const { return output_transform_; }
  // Of the transformed output.
  double output_mean() const { return output_mean_; }
  double output_scale() const { return output_scale_; }

  // {"format": "pyrocam-mlp", "version": 2, "activation": "relu",
  //  "input_transform": "none" | "log", "input_mean": [...], "input_scale": [...],
  //  "output_transform": "none" | "inverse_kelvin" | "log_kelvin",
  //  "output_mean": m, "output_scale": s,
  //  "layers": [{"weights": [[row of inputs], ...one row per output], "bias": [...]}, ...]}
  // Numbers are written so that they read back bit-identical. Version 1 files (no transform
  // keys) read as both transforms "none".
  nlohmann::json to_json() const;
  // Throws MlpError naming the key or element at fault: missing keys, wrong types, unknown
  // versions or transforms, shapes that do not chain, non-finite numbers, non-positive scales.
  static Mlp from_json(const nlohmann::json& j);

 private:
  void check_and_prepare();  // validates parts, builds the single-precision copies
  // Transform and standardise one sample into z; false when an input is invalid (NaN, inf, or
  // <= 0 under kLog).
  template <class T>
  bool standardise_input(const double* x, T* z) const;
  // Standardised network output -> target units; NaN outside the output transform's domain.
  double output_from_network(double z) const;
  template <class Fetch>
  void predict_chunked(Eigen::Index count, Fetch fetch, double* out) const;

  MlpInputTransform input_transform_ = MlpInputTransform::kNone;
  Standardizer input_;
  MlpOutputTransform output_transform_ = MlpOutputTransform::kNone;
  double output_mean_ = 0, output_scale_ = 1;
  std::vector<MlpLayer> layers_;
  // Single-precision copies for inference: half the memory traffic and twice the SIMD width.
  std::vector<Eigen::MatrixXf> weights_f_;
  std::vector<Eigen::VectorXf> bias_f_;
  Eigen::VectorXd inverse_input_scale_;
  int max_width_ = 0;
};

}  // namespace pyrocam
