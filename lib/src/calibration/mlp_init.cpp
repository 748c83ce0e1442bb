#include "calibration/mlp_init.h"

#include <cmath>
#include <cstddef>
#include <utility>

namespace pyrocam::mlp_training {

TrainingNetwork initial_network(int input_size, const std::vector<int>& hidden,
                                const TrainingMatrix& z_train, Random& random) {
  using S = TrainingScalar;
  using Matrix = TrainingMatrix;
  const Eigen::Index train_count = z_train.cols();
  // He initialisation for ReLU layers, variance 1/fan_in for the linear output.
  Network<S> net;
  std::vector<int> widths{input_size};
  widths.insert(widths.end(), hidden.begin(), hidden.end());
  widths.push_back(1);
  for (std::size_t l = 0; l + 1 < widths.size(); ++l) {
    const bool is_output = l + 2 == widths.size();
    const double sd = std::sqrt((is_output ? 1.0 : 2.0) / widths[l]);
    Matrix w(widths[l + 1], widths[l]);
    // Row by row, the order the JSON lists them.
    for (Eigen::Index r = 0; r < w.rows(); ++r) {
      for (Eigen::Index c = 0; c < w.cols(); ++c) w(r, c) = static_cast<S>(sd * random.normal());
    }
    net.weights.push_back(std::move(w));
    net.bias.push_back(Network<S>::Vector::Zero(widths[l + 1]));
  }
  const std::size_t layers = net.layer_count();
  // Data-dependent hidden biases: each hidden unit's kink passes through a random training
  // sample, so that the kinks spread along the data instead of all crossing the origin, and no
  // unit starts dead. The output bias stays 0 (the target mean).
  {
    Matrix a = z_train;
    for (std::size_t l = 0; l + 1 < layers; ++l) {
      Matrix z = net.weights[l] * a;
      for (Eigen::Index i = 0; i < z.rows(); ++i) {
        const auto sample =
            static_cast<Eigen::Index>(random.below(static_cast<std::size_t>(train_count)));
        net.bias[l][i] = -z(i, sample);
      }
      z.colwise() += net.bias[l];
      a = z.cwiseMax(S(0));
    }
  }
  return net;
}

}  // namespace pyrocam::mlp_training
