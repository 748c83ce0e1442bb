// Dense ReLU multilayer perceptron regressor at inference: normalised band ratios -> temperature
// (Sala et al. 2025, section 2.7: hidden layers 250-200-150-100-50, ReLU), with input and output
// transforms (log ratios in, 1/T out) and its JSON form. Training (Adam, L-BFGS polish) is in
// pyrocam/calibration/mlp_training.h.
#pragma once

#include <Eigen/Core>
#include <nlohmann/json_fwd.hpp>
#include <optional>
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

// Target (degC) -> the network's output quantity.
double to_network_units(MlpOutputTransform t, double y);
// The inverse of to_network_units; NaN where v is outside its range.
double from_network_units(MlpOutputTransform t, double v);
// d from_network_units / d v.
double target_slope(MlpOutputTransform t, double v);
// The transforms' names in the JSON form.
const char* to_string(MlpInputTransform t);
const char* to_string(MlpOutputTransform t);

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

struct MlpLayer {
  Eigen::MatrixXd weights;  // outputs x inputs
  Eigen::VectorXd bias;     // outputs
};

// Immutable once built; every const member is safe to call from several threads at once.
class Mlp {
 public:
  Mlp() = default;  // empty: input_size() == 0, predictions NaN

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
  // `layers`, when given, are the layers already read (the model loader reads them from the
  // file's text, faster): j's "layers" is then not read.
  static Mlp from_json(const nlohmann::json& j,
                       std::optional<std::vector<MlpLayer>> layers = std::nullopt);

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
