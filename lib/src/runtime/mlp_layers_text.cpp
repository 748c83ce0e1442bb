#include "mlp_layers_text.h"

#include <charconv>
#include <cmath>
#include <cstddef>
#include <system_error>

#include "detail/json_text.h"

namespace pyrocam::detail {
namespace {

class Cursor {
 public:
  explicit Cursor(std::string_view text) : t_(text) {}
  bool eat(char c) {
    space();
    if (i_ >= t_.size() || t_[i_] != c) return false;
    ++i_;
    return true;
  }
  bool at_end() {
    space();
    return i_ == t_.size();
  }

  // A JSON number (its grammar checked: from_chars alone also takes "inf" or "01"), finite, as
  // the JSON parser gives it: an integer token is read as an integer, so "-0" is +0.
  bool number(double& v) {
    space();
    auto digit = [&](std::size_t k) { return k < t_.size() && t_[k] >= '0' && t_[k] <= '9'; };
    std::size_t k = i_;
    if (k < t_.size() && t_[k] == '-') ++k;
    if (!digit(k)) return false;
    if (t_[k] == '0')
      ++k;
    else
      while (digit(k)) ++k;
    bool integer = true;
    if (k < t_.size() && t_[k] == '.') {
      integer = false;
      if (!digit(++k)) return false;
      while (digit(k)) ++k;
    }
    if (k < t_.size() && (t_[k] == 'e' || t_[k] == 'E')) {
      integer = false;
      ++k;
      if (k < t_.size() && (t_[k] == '+' || t_[k] == '-')) ++k;
      if (!digit(k)) return false;
      while (digit(k)) ++k;
    }
    const auto [end, error] = std::from_chars(t_.data() + i_, t_.data() + k, v);
    if (error != std::errc() || end != t_.data() + k || !std::isfinite(v)) return false;
    if (integer && v == 0) v = 0.0;
    i_ = k;
    return true;
  }

  // `[n, n, ...]` appended to `out`; returns how many.
  bool numbers(std::vector<double>& out, std::size_t& count) {
    count = 0;
    if (!eat('[')) return false;
    if (eat(']')) return true;
    do {
      double v;
      if (!number(v)) return false;
      out.push_back(v);
      ++count;
    } while (eat(','));
    return eat(']');
  }

  // `"name":` without escapes.
  bool key(std::string_view& name) {
    if (!eat('"')) return false;
    const std::size_t start = i_;
    while (i_ < t_.size() && t_[i_] != '"') {
      if (t_[i_] == '\\') return false;
      ++i_;
    }
    if (i_ >= t_.size()) return false;
    name = t_.substr(start, i_ - start);
    ++i_;
    return eat(':');
  }

 private:
  void space() {
    while (i_ < t_.size() && json_space(t_[i_])) ++i_;
  }
  std::string_view t_;
  std::size_t i_ = 0;
};

bool read_weights(Cursor& c, Eigen::MatrixXd& weights) {
  if (!c.eat('[')) return false;
  std::vector<double> values;
  std::size_t rows = 0, cols = 0;
  do {
    std::size_t n = 0;
    if (!c.numbers(values, n)) return false;
    if (n == 0 || (rows > 0 && n != cols)) return false;
    cols = n;
    ++rows;
    if (rows > static_cast<std::size_t>(kMlpMaxLayerWidth) ||
        cols > static_cast<std::size_t>(kMlpMaxLayerWidth))
      return false;
  } while (c.eat(','));
  if (!c.eat(']')) return false;
  weights =
      Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          values.data(), static_cast<Eigen::Index>(rows), static_cast<Eigen::Index>(cols));
  return true;
}

bool read_layer(Cursor& c, MlpLayer& layer) {
  if (!c.eat('{')) return false;
  bool have_weights = false, have_bias = false;
  do {
    std::string_view name;
    if (!c.key(name)) return false;
    if (name == "weights" && !have_weights) {
      if (!read_weights(c, layer.weights)) return false;
      have_weights = true;
    } else if (name == "bias" && !have_bias) {
      std::vector<double> bias;
      std::size_t n = 0;
      if (!c.numbers(bias, n) || n > static_cast<std::size_t>(kMlpMaxLayerWidth)) return false;
      layer.bias = Eigen::Map<const Eigen::VectorXd>(bias.data(), static_cast<Eigen::Index>(n));
      have_bias = true;
    } else {
      return false;
    }
  } while (c.eat(','));
  return c.eat('}') && have_weights && have_bias;
}

}  // namespace

std::optional<std::vector<MlpLayer>> read_layers_text(std::string_view text) {
  Cursor c(text);
  std::vector<MlpLayer> layers;
  if (!c.eat('[')) return std::nullopt;
  do {
    if (layers.size() >= static_cast<std::size_t>(kMlpMaxLayers)) return std::nullopt;
    MlpLayer layer;
    if (!read_layer(c, layer)) return std::nullopt;
    layers.push_back(std::move(layer));
  } while (c.eat(','));
  if (!c.eat(']') || !c.at_end()) return std::nullopt;
  return layers;
}

}  // namespace pyrocam::detail
