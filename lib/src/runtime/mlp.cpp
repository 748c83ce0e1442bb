// The network at inference: the output transforms, standardisation, the forward passes (single
// sample, batch, with gradient) and the JSON form. Training is in pyrocam-calibration
// (pyrocam/calibration/mlp_training.h).
#include "pyrocam/runtime/mlp.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>

#include "detail/portable_math.h"
#include "pyrocam/core/physics.h"

namespace pyrocam {
namespace {

using json = nlohmann::json;

constexpr double kKelvinOffset = kZeroCelsius;

// Samples per chunk in the batch inference path: activations of the widest layer stay in L2.
constexpr Eigen::Index kInferenceChunk = 256;

// A number in messages: "1e+06", "1e+308", "0.5".
std::string to_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// ---- JSON reading with messages that say where the problem is ----

const json& require(const json& j, const char* key, const std::string& where) {
  if (!j.is_object()) throw MlpError("mlp json: " + where + " is not an object");
  const auto it = j.find(key);
  if (it == j.end()) {
    throw MlpError("mlp json: missing key \"" + std::string(key) + "\" in " + where);
  }
  return *it;
}

double read_number(const json& j, const std::string& where) {
  if (!j.is_number()) {
    throw MlpError("mlp json: " + where + " is not a number (" + std::string(j.type_name()) + ")");
  }
  const double value = j.get<double>();
  if (!std::isfinite(value)) throw MlpError("mlp json: " + where + " is not finite (NaN or inf)");
  return value;
}

Eigen::VectorXd read_vector(const json& j, const std::string& where) {
  if (!j.is_array()) throw MlpError("mlp json: " + where + " is not an array");
  Eigen::VectorXd v(static_cast<Eigen::Index>(j.size()));
  for (std::size_t i = 0; i < j.size(); ++i) {
    v[static_cast<Eigen::Index>(i)] = read_number(j[i], where + "[" + std::to_string(i) + "]");
  }
  return v;
}

Eigen::MatrixXd read_matrix(const json& j, const std::string& where) {
  if (!j.is_array() || j.empty())
    throw MlpError("mlp json: " + where + " is not a non-empty array of rows");
  const std::size_t cols = j[0].is_array() ? j[0].size() : 0;
  // Bounded before the matrix is allocated from the two sizes.
  const auto limit = static_cast<std::size_t>(kMlpMaxLayerWidth);
  if (j.size() > limit || cols > limit) {
    throw MlpError("mlp json: " + where + " is " + std::to_string(j.size()) + " x " +
                   std::to_string(cols) + "; a layer is at most " + std::to_string(limit) +
                   " wide");
  }
  Eigen::MatrixXd m(static_cast<Eigen::Index>(j.size()), static_cast<Eigen::Index>(cols));
  for (std::size_t r = 0; r < j.size(); ++r) {
    const std::string row_where = where + "[" + std::to_string(r) + "]";
    const Eigen::VectorXd row = read_vector(j[r], row_where);
    if (static_cast<std::size_t>(row.size()) != cols || cols == 0) {
      throw MlpError("mlp json: " + row_where + " has " + std::to_string(row.size()) +
                     " columns where row 0 has " + std::to_string(cols));
    }
    m.row(static_cast<Eigen::Index>(r)) = row.transpose();
  }
  return m;
}

json to_json_array(const Eigen::VectorXd& v) {
  return json(std::vector<double>(v.data(), v.data() + v.size()));
}

}  // namespace

// ---------------------------------------------------------------- output transforms

// Target (degC) -> the network's output quantity.
double to_network_units(MlpOutputTransform t, double y) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return 1.0 / (y + kKelvinOffset);
    case MlpOutputTransform::kLogKelvin:
      return portable::log(y + kKelvinOffset);
    case MlpOutputTransform::kNone:
      break;
  }
  return y;
}

// The inverse of to_network_units; NaN where v is outside its range.
double from_network_units(MlpOutputTransform t, double v) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return v > 0 ? 1.0 / v - kKelvinOffset : std::numeric_limits<double>::quiet_NaN();
    case MlpOutputTransform::kLogKelvin: {
      const double y = portable::exp(v) - kKelvinOffset;
      return std::isfinite(y) ? y : std::numeric_limits<double>::quiet_NaN();
    }
    case MlpOutputTransform::kNone:
      break;
  }
  return v;
}

// d from_network_units / d v.
double target_slope(MlpOutputTransform t, double v) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return -1.0 / (v * v);
    case MlpOutputTransform::kLogKelvin:
      return portable::exp(v);
    case MlpOutputTransform::kNone:
      break;
  }
  return 1.0;
}

const char* to_string(MlpInputTransform t) { return t == MlpInputTransform::kLog ? "log" : "none"; }

const char* to_string(MlpOutputTransform t) {
  switch (t) {
    case MlpOutputTransform::kInverseKelvin:
      return "inverse_kelvin";
    case MlpOutputTransform::kLogKelvin:
      return "log_kelvin";
    case MlpOutputTransform::kNone:
      break;
  }
  return "none";
}

// ---------------------------------------------------------------- Standardizer

Standardizer Standardizer::fit(const Eigen::MatrixXd& samples) {
  if (samples.rows() < 1) throw MlpError("mlp: cannot standardise zero samples");
  Standardizer s;
  s.mean = samples.colwise().mean().transpose();
  s.scale.resize(samples.cols());
  for (Eigen::Index c = 0; c < samples.cols(); ++c) {
    const double sd = std::sqrt((samples.col(c).array() - s.mean[c]).square().mean());
    s.scale[c] = sd > 1e-12 * std::max(1.0, std::abs(s.mean[c])) ? sd : 1.0;
  }
  return s;
}

Eigen::MatrixXd Standardizer::apply(const Eigen::MatrixXd& samples) const {
  return (samples.rowwise() - mean.transpose()).array().rowwise() / scale.transpose().array();
}

Eigen::MatrixXd Standardizer::invert(const Eigen::MatrixXd& standardized) const {
  return (standardized.array().rowwise() * scale.transpose().array()).matrix().rowwise() +
         mean.transpose();
}

// ---------------------------------------------------------------- model

Mlp::Mlp(MlpInputTransform input_transform, Standardizer input, MlpOutputTransform output_transform,
         double output_mean, double output_scale, std::vector<MlpLayer> layers)
    : input_transform_(input_transform),
      input_(std::move(input)),
      output_transform_(output_transform),
      output_mean_(output_mean),
      output_scale_(output_scale),
      layers_(std::move(layers)) {
  check_and_prepare();
}

void Mlp::check_and_prepare() {
  if (layers_.empty()) throw MlpError("mlp: no layers");
  const Eigen::Index inputs = input_.mean.size();
  if (inputs < 1 || input_.scale.size() != inputs) {
    throw MlpError("mlp: input_mean has " + std::to_string(inputs) + " values, input_scale " +
                   std::to_string(input_.scale.size()) + "; need the same, at least 1");
  }
  if (!input_.mean.allFinite() || !(input_.scale.array() > 0).all() || !input_.scale.allFinite()) {
    throw MlpError("mlp: input_mean must be finite and input_scale finite and > 0");
  }
  if (!std::isfinite(output_mean_) || !(output_scale_ > 0) || !std::isfinite(output_scale_)) {
    throw MlpError("mlp: output_mean must be finite and output_scale finite and > 0");
  }
  const auto too_large = [](double v) { return !(std::abs(v) <= kMlpMaxAbsParameter); };
  if (input_.mean.unaryExpr(too_large).any() || input_.scale.unaryExpr(too_large).any() ||
      too_large(output_mean_) || too_large(output_scale_)) {
    throw MlpError("mlp: input_mean, input_scale, output_mean and output_scale must lie within +-" +
                   to_text(kMlpMaxAbsParameter));
  }
  if (layers_.size() > static_cast<std::size_t>(kMlpMaxLayers)) {
    throw MlpError("mlp: " + std::to_string(layers_.size()) + " layers; at most " +
                   std::to_string(kMlpMaxLayers) + " supported");
  }
  Eigen::Index width = inputs;
  max_width_ = static_cast<int>(inputs);
  for (std::size_t l = 0; l < layers_.size(); ++l) {
    const auto& layer = layers_[l];
    const std::string name = "layers[" + std::to_string(l) + "]";
    if (layer.weights.cols() != width) {
      throw MlpError("mlp: " + name + ".weights has " + std::to_string(layer.weights.cols()) +
                     " columns, expected " + std::to_string(width) +
                     (l == 0 ? " (input size)" : " (outputs of the layer before)"));
    }
    if (layer.bias.size() != layer.weights.rows()) {
      throw MlpError("mlp: " + name + ".bias has " + std::to_string(layer.bias.size()) +
                     " values for " + std::to_string(layer.weights.rows()) + " weight rows");
    }
    if (!layer.weights.allFinite() || !layer.bias.allFinite()) {
      throw MlpError("mlp: " + name + " has a NaN or infinite weight or bias");
    }
    const double largest =
        std::max(layer.weights.cwiseAbs().maxCoeff(), layer.bias.cwiseAbs().maxCoeff());
    if (largest > kMlpMaxAbsParameter) {
      throw MlpError("mlp: " + name + " has a weight or bias of " + to_text(largest) +
                     "; trained networks stay within +-" + to_text(kMlpMaxAbsParameter));
    }
    width = layer.weights.rows();
    if (width < 1) throw MlpError("mlp: " + name + " has no outputs");
    max_width_ = std::max(max_width_, static_cast<int>(width));
  }
  if (width != 1) {
    throw MlpError("mlp: the last layer has " + std::to_string(width) + " outputs; need 1");
  }
  if (max_width_ > kMlpMaxLayerWidth) {
    throw MlpError("mlp: a layer is " + std::to_string(max_width_) + " wide; at most " +
                   std::to_string(kMlpMaxLayerWidth) + " supported");
  }
  inverse_input_scale_ = input_.scale.cwiseInverse();
  weights_f_.clear();
  bias_f_.clear();
  for (const auto& layer : layers_) {
    weights_f_.push_back(layer.weights.cast<float>());
    bias_f_.push_back(layer.bias.cast<float>());
  }
}

std::vector<int> Mlp::hidden_sizes() const {
  std::vector<int> sizes;
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    sizes.push_back(static_cast<int>(layers_[l].weights.rows()));
  }
  return sizes;
}

template <class T>
bool Mlp::standardise_input(const double* x, T* z) const {
  bool valid = true;
  for (Eigen::Index j = 0; j < input_.mean.size(); ++j) {
    const double v = input_transform_ == MlpInputTransform::kLog ? portable::log(x[j]) : x[j];
    const double standardised = (v - input_.mean[j]) * inverse_input_scale_[j];
    valid = valid && std::isfinite(standardised);  // log of <= 0 gives -inf or NaN
    z[j] = static_cast<T>(standardised);
  }
  return valid;
}

double Mlp::output_from_network(double z) const {
  return from_network_units(output_transform_, z * output_scale_ + output_mean_);
}

double Mlp::predict(const double* x) const {
  if (layers_.empty()) return std::numeric_limits<double>::quiet_NaN();
  alignas(64) float buffer_a[kMlpMaxLayerWidth];
  alignas(64) float buffer_b[kMlpMaxLayerWidth];
  float* in = buffer_a;
  float* out = buffer_b;
  if (!standardise_input(x, in)) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t layers = weights_f_.size();
  for (std::size_t l = 0; l + 1 < layers; ++l) {
    const Eigen::MatrixXf& w = weights_f_[l];
    Eigen::Map<Eigen::VectorXf> o(out, w.rows());
    o = bias_f_[l];
    // Column by column so that the inputs ReLU zeroed (about half) cost nothing.
    for (Eigen::Index j = 0; j < w.cols(); ++j) {
      if (in[j] != 0.0f) o.noalias() += in[j] * w.col(j);
    }
    o = o.cwiseMax(0.0f);
    std::swap(in, out);
  }
  const Eigen::MatrixXf& w_out = weights_f_.back();
  const float z =
      w_out.row(0).dot(Eigen::Map<const Eigen::VectorXf>(in, w_out.cols())) + bias_f_.back()[0];
  return output_from_network(static_cast<double>(z));
}

template <class Fetch>
void Mlp::predict_chunked(Eigen::Index count, Fetch fetch, double* out) const {
  if (layers_.empty()) {
    std::fill(out, out + count, std::numeric_limits<double>::quiet_NaN());
    return;
  }
  const Eigen::Index inputs = input_.mean.size();
  const Eigen::Index chunk = std::min(count, kInferenceChunk);
  Eigen::MatrixXf a(max_width_, chunk), b(max_width_, chunk);
  std::vector<double> sample(static_cast<std::size_t>(inputs));
  std::vector<char> valid(static_cast<std::size_t>(chunk));
  for (Eigen::Index start = 0; start < count; start += chunk) {
    const Eigen::Index n = std::min(chunk, count - start);
    for (Eigen::Index k = 0; k < n; ++k) {
      for (Eigen::Index j = 0; j < inputs; ++j)
        sample[static_cast<std::size_t>(j)] = fetch(start + k, j);
      valid[static_cast<std::size_t>(k)] = standardise_input(sample.data(), &a(0, k));
      if (!valid[static_cast<std::size_t>(k)]) a.col(k).head(inputs).setZero();
    }
    Eigen::Index width = inputs;
    for (std::size_t l = 0; l < weights_f_.size(); ++l) {
      const Eigen::MatrixXf& w = weights_f_[l];
      auto next = b.topLeftCorner(w.rows(), n);
      next.noalias() = w * a.topLeftCorner(width, n);
      next.colwise() += bias_f_[l];
      if (l + 1 < weights_f_.size()) next = next.cwiseMax(0.0f);
      width = w.rows();
      a.swap(b);
    }
    for (Eigen::Index k = 0; k < n; ++k) {
      out[start + k] = valid[static_cast<std::size_t>(k)]
                           ? output_from_network(static_cast<double>(a(0, k)))
                           : std::numeric_limits<double>::quiet_NaN();
    }
  }
}

Eigen::VectorXd Mlp::predict(const Eigen::MatrixXd& X) const {
  if (X.cols() != input_.mean.size()) {
    throw MlpError("mlp: predict got " + std::to_string(X.cols()) +
                   " inputs per sample, model has " + std::to_string(input_.mean.size()));
  }
  Eigen::VectorXd out(X.rows());
  predict_chunked(
      X.rows(), [&X](Eigen::Index i, Eigen::Index j) { return X(i, j); }, out.data());
  return out;
}

void Mlp::predict_rows(const double* rows, Eigen::Index count, double* out) const {
  const Eigen::Index inputs = input_.mean.size();
  predict_chunked(
      count, [rows, inputs](Eigen::Index i, Eigen::Index j) { return rows[i * inputs + j]; }, out);
}

double Mlp::predict_with_gradient(const double* x, double* grad_out) const {
  const Eigen::Index inputs = input_.mean.size();
  if (layers_.empty()) {
    std::fill(grad_out, grad_out + inputs, std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::quiet_NaN();
  }
  // Every hidden activation is kept for the backward pass; sized once per thread.
  thread_local std::vector<double> scratch;
  std::size_t needed = static_cast<std::size_t>(inputs) + 2 * static_cast<std::size_t>(max_width_);
  for (std::size_t l = 0; l + 1 < layers_.size(); ++l) {
    needed += static_cast<std::size_t>(layers_[l].weights.rows());
  }
  if (scratch.size() < needed) scratch.resize(needed);

  double* z0 = scratch.data();
  if (!standardise_input(x, z0)) {
    std::fill(grad_out, grad_out + inputs, std::numeric_limits<double>::quiet_NaN());
    return std::numeric_limits<double>::quiet_NaN();
  }
  double* cursor = z0 + inputs;
  const double* in = z0;
  const std::size_t layers = layers_.size();
  for (std::size_t l = 0; l + 1 < layers; ++l) {
    const auto& layer = layers_[l];
    Eigen::Map<Eigen::VectorXd> o(cursor, layer.weights.rows());
    o.noalias() = layer.weights * Eigen::Map<const Eigen::VectorXd>(in, layer.weights.cols());
    o = (o + layer.bias).cwiseMax(0.0);
    in = cursor;
    cursor += layer.weights.rows();
  }
  const auto& last = layers_.back();
  const double z =
      last.weights.row(0).dot(Eigen::Map<const Eigen::VectorXd>(in, last.weights.cols())) +
      last.bias[0];

  // Backward: g = d z / d (activations of layer l), starting from the output row.
  double* g = cursor;
  double* g_below = cursor + max_width_;
  Eigen::Map<Eigen::VectorXd>(g, last.weights.cols()) = last.weights.row(0).transpose();
  const double* act_end = cursor;
  for (std::size_t l = layers - 1; l-- > 0;) {
    const auto& layer = layers_[l];
    const Eigen::Index outputs = layer.weights.rows();
    const double* act = act_end - outputs;
    Eigen::Map<Eigen::VectorXd> grad(g, outputs);
    grad.array() *= (Eigen::Map<const Eigen::ArrayXd>(act, outputs) > 0.0).cast<double>();
    Eigen::Map<Eigen::VectorXd>(g_below, layer.weights.cols()).noalias() =
        layer.weights.transpose() * grad;
    std::swap(g, g_below);
    act_end = act;
  }
  const double v = z * output_scale_ + output_mean_;
  const double output_slope = target_slope(output_transform_, v) * output_scale_;
  for (Eigen::Index j = 0; j < inputs; ++j) {
    // d log(x) / dx = 1 / x
    const double input_slope = input_transform_ == MlpInputTransform::kLog ? 1.0 / x[j] : 1.0;
    grad_out[j] = g[j] * output_slope * inverse_input_scale_[j] * input_slope;
  }
  const double y = from_network_units(output_transform_, v);
  if (std::isnan(y)) std::fill(grad_out, grad_out + inputs, y);
  return y;
}

// ---------------------------------------------------------------- JSON

json Mlp::to_json() const {
  if (layers_.empty()) throw MlpError("mlp: cannot write an empty model");
  json layers = json::array();
  for (const auto& layer : layers_) {
    json rows = json::array();
    for (Eigen::Index r = 0; r < layer.weights.rows(); ++r) {
      const Eigen::VectorXd row = layer.weights.row(r).transpose();
      rows.push_back(to_json_array(row));
    }
    layers.push_back({{"weights", std::move(rows)}, {"bias", to_json_array(layer.bias)}});
  }
  return {{"format", "pyrocam-mlp"},
          {"version", kMlpFormatVersion},
          {"activation", "relu"},
          {"input_transform", to_string(input_transform_)},
          {"input_mean", to_json_array(input_.mean)},
          {"input_scale", to_json_array(input_.scale)},
          {"output_transform", to_string(output_transform_)},
          {"output_mean", output_mean_},
          {"output_scale", output_scale_},
          {"layers", std::move(layers)}};
}

Mlp Mlp::from_json(const json& j, std::optional<std::vector<MlpLayer>> read_layers) {
  const std::string top = "the MLP object";
  const json& format = require(j, "format", top);
  if (!format.is_string() || format.get<std::string>() != "pyrocam-mlp") {
    throw MlpError("mlp json: \"format\" is " + format.dump() + ", expected \"pyrocam-mlp\"");
  }
  const json& version = require(j, "version", top);
  if (!version.is_number_integer() || version.get<int>() < 1 ||
      version.get<int>() > kMlpFormatVersion) {
    throw MlpError("mlp json: unsupported \"version\" " + version.dump() +
                   ", this build reads 1 to " + std::to_string(kMlpFormatVersion));
  }
  const int format_version = version.get<int>();
  if (j.contains("activation") && j["activation"] != "relu") {
    throw MlpError("mlp json: unsupported \"activation\" " + j["activation"].dump() +
                   ", expected \"relu\"");
  }
  // Version 1 had no transforms: both were "none".
  MlpInputTransform input_transform = MlpInputTransform::kNone;
  MlpOutputTransform output_transform = MlpOutputTransform::kNone;
  if (format_version >= 2) {
    const json& in = require(j, "input_transform", top);
    if (in == to_string(MlpInputTransform::kLog)) {
      input_transform = MlpInputTransform::kLog;
    } else if (in != to_string(MlpInputTransform::kNone)) {
      throw MlpError("mlp json: unsupported \"input_transform\" " + in.dump() +
                     ", expected \"none\" or \"log\"");
    }
    const json& out = require(j, "output_transform", top);
    bool known = false;
    for (const auto t : {MlpOutputTransform::kNone, MlpOutputTransform::kInverseKelvin,
                         MlpOutputTransform::kLogKelvin}) {
      if (out == to_string(t)) output_transform = t, known = true;
    }
    if (!known) {
      throw MlpError("mlp json: unsupported \"output_transform\" " + out.dump() +
                     ", expected \"none\", \"inverse_kelvin\" or \"log_kelvin\"");
    }
  } else if (j.contains("input_transform") || j.contains("output_transform")) {
    throw MlpError("mlp json: version 1 has no transforms, yet the file names one");
  }
  Standardizer input;
  input.mean = read_vector(require(j, "input_mean", top), "input_mean");
  input.scale = read_vector(require(j, "input_scale", top), "input_scale");
  const double output_mean = read_number(require(j, "output_mean", top), "output_mean");
  const double output_scale = read_number(require(j, "output_scale", top), "output_scale");
  std::vector<MlpLayer> layers;
  if (read_layers) {
    layers = std::move(*read_layers);
  } else {
    const json& layers_json = require(j, "layers", top);
    if (!layers_json.is_array() || layers_json.empty()) {
      throw MlpError("mlp json: \"layers\" must be a non-empty array");
    }
    if (layers_json.size() > static_cast<std::size_t>(kMlpMaxLayers)) {
      throw MlpError("mlp json: \"layers\" holds " + std::to_string(layers_json.size()) +
                     " layers; at most " + std::to_string(kMlpMaxLayers) + " supported");
    }
    for (std::size_t l = 0; l < layers_json.size(); ++l) {
      const std::string name = "layers[" + std::to_string(l) + "]";
      MlpLayer layer;
      layer.weights = read_matrix(require(layers_json[l], "weights", name), name + ".weights");
      layer.bias = read_vector(require(layers_json[l], "bias", name), name + ".bias");
      layers.push_back(std::move(layer));
    }
  }
  if (layers.empty()) throw MlpError("mlp json: \"layers\" must be a non-empty array");
  try {
    return Mlp(input_transform, std::move(input), output_transform, output_mean, output_scale,
               std::move(layers));
  } catch (const MlpError& e) {
    // Same message, marked as coming from the file.
    std::string message = e.what();
    if (message.rfind("mlp: ", 0) == 0) message = "mlp json: " + message.substr(5);
    throw MlpError(message);
  }
}

}  // namespace pyrocam
