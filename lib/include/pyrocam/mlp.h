// Dense ReLU multilayer perceptron regressor: normalised band ratios -> temperature
// (Sala et al. 2025, section 2.7: hidden layers 250-200-150-100-50, ReLU, MSE loss, Adam,
// batch 32, 70/30 train/test split), with input/output standardisation and a learning-rate
// schedule in place of the paper's constant 1e-5.
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

inline constexpr int kMlpFormatVersion = 1;
// Widest layer (inputs included) the allocation-free single-sample path supports: its scratch
// lives on the stack.
inline constexpr int kMlpMaxLayerWidth = 1024;

// Applied to each input before standardising. Band ratios vary over orders of magnitude along
// the Planck locus (blue/red spans 2 to 8000 between 500 and 3500 degC), so that standardised
// raw ratios crowd the hot end into a sliver of the input range; their logarithms are close to
// linear in 1/T and spread evenly. With kLog every input must be > 0; predictions for samples
// with an input <= 0 are NaN.
enum class MlpInputTransform { kNone, kLog };

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

struct MlpTrainingOptions {
  std::vector<int> hidden = {250, 200, 150, 100, 50};
  MlpInputTransform input_transform = MlpInputTransform::kLog;
  int epochs = 400;
  int batch_size = 32;
  // Per-step schedule: linear warm-up from 0 to learning_rate over the first warmup_fraction
  // of all steps, then half-cosine decay to final_learning_rate at the last step.
  double learning_rate = 1e-3;
  double final_learning_rate = 1e-6;
  double warmup_fraction = 0.02;
  // Decoupled (AdamW) weight decay per step, multiplied by the scheduled learning rate.
  double l2_weight_decay = 0;
  // Then full-batch L-BFGS steps on the training set (0: Adam only, as in the paper). Mini-batch
  // Adam levels off near 1 degC on a noise-free locus; these take it to the 0.1 degC scale.
  int polish_iterations = 200;
  double test_fraction = 0.3;  // held out at random, never trained on; 0 allowed
  std::uint64_t seed = 1;      // initial weights, split and batch order
  // Optional, called after every epoch with that epoch's train and test RMSE (output units).
  std::function<void(int epoch, double train_rmse, double test_rmse)> progress;
};

struct MlpTrainingReport {
  // Per epoch, in output units. train_rmse is the mean over that epoch's mini-batches (weights
  // change during the epoch; it costs nothing), test_rmse is evaluated at the epoch's end.
  // With no test set, test values are NaN.
  std::vector<double> train_rmse, test_rmse;
  // Of the returned model, evaluated with predict() after training.
  double final_train_rmse = 0, final_test_rmse = 0, max_abs_test_error = 0;
  double max_abs_train_error = 0;
  double seconds = 0;  // wall time of train()
  int train_samples = 0, test_samples = 0;
  int polish_iterations_done = 0;  // fewer than asked when no step lowers the loss any more
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
  Mlp(MlpInputTransform input_transform, Standardizer input, double output_mean,
      double output_scale, std::vector<MlpLayer> layers);

  // One sample of input_size() values. Single precision inside (|error| ~1e-6 of the output
  // scale), no heap allocation: for per-pixel use.
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
  double output_mean() const { return output_mean_; }
  double output_scale() const { return output_scale_; }

  // {"format": "pyrocam-mlp", "version": 1, "activation": "relu",
  //  "input_transform": "log" | "none", "input_mean": [...],
  //  "input_scale": [...], "output_mean": m, "output_scale": s,
  //  "layers": [{"weights": [[row of inputs], ...one row per output], "bias": [...]}, ...]}
  // Numbers are written so that they read back bit-identical.
  nlohmann::json to_json() const;
  // Throws MlpError naming the key or element at fault: missing keys, wrong types, shapes that
  // do not chain, non-finite numbers, non-positive scales.
  static Mlp from_json(const nlohmann::json& j);

 private:
  void check_and_prepare();  // validates parts, builds the single-precision copies
  // Transform and standardise one sample into z; false when an input is invalid (NaN, inf, or
  // <= 0 under kLog).
  template <class T>
  bool standardise_input(const double* x, T* z) const;
  template <class Fetch>
  void predict_chunked(Eigen::Index count, Fetch fetch, double* out) const;

  MlpInputTransform input_transform_ = MlpInputTransform::kNone;
  Standardizer input_;
  double output_mean_ = 0, output_scale_ = 1;
  std::vector<MlpLayer> layers_;
  // Single-precision copies for inference: half the memory traffic and twice the SIMD width.
  std::vector<Eigen::MatrixXf> weights_f_;
  std::vector<Eigen::VectorXf> bias_f_;
  Eigen::VectorXd inverse_input_scale_;
  int max_width_ = 0;
};

}  // namespace pyrocam
