// Training's initialisation stage (calibration/mlp_init.h): He-initialised weights and hidden
// units whose kinks pass through training samples.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "calibration/mlp_init.h"

namespace pyrocam::mlp_training {
namespace {

TrainingMatrix training_columns(Eigen::Index inputs, Eigen::Index samples) {
  Random random(9);
  TrainingMatrix z(inputs, samples);
  for (Eigen::Index i = 0; i < z.size(); ++i) z.data()[i] = static_cast<float>(random.normal());
  return z;
}

TEST(MlpInit, layers_have_the_asked_widths_and_he_scaled_weights) {
  const TrainingMatrix z = training_columns(3, 200);
  Random random(1);
  const TrainingNetwork net = initial_network(3, {400, 300}, z, random);
  ASSERT_EQ(net.layer_count(), 3u);
  EXPECT_EQ(net.weights[0].rows(), 400);
  EXPECT_EQ(net.weights[0].cols(), 3);
  EXPECT_EQ(net.weights[1].rows(), 300);
  EXPECT_EQ(net.weights[1].cols(), 400);
  EXPECT_EQ(net.weights[2].rows(), 1);
  EXPECT_EQ(net.bias[2][0], 0.0f) << "the output starts at the target mean";
  // Standard deviation sqrt(2 / fan_in) for ReLU layers, sqrt(1 / fan_in) for the output.
  const auto sd = [](const TrainingMatrix& w) {
    return std::sqrt(static_cast<double>(w.squaredNorm()) / static_cast<double>(w.size()));
  };
  EXPECT_NEAR(sd(net.weights[1]), std::sqrt(2.0 / 400), 0.01 * std::sqrt(2.0 / 400));
  EXPECT_NEAR(sd(net.weights[0]), std::sqrt(2.0 / 3), 0.05 * std::sqrt(2.0 / 3));
  EXPECT_NEAR(sd(net.weights[2]), std::sqrt(1.0 / 300), 0.1 * std::sqrt(1.0 / 300));
}

TEST(MlpInit, every_hidden_unit_has_its_kink_at_a_training_sample) {
  const TrainingMatrix z = training_columns(2, 50);
  Random random(1);
  const TrainingNetwork net = initial_network(2, {20, 10}, z, random);
  TrainingMatrix a = z;
  for (std::size_t l = 0; l < 2; ++l) {
    TrainingMatrix pre = net.weights[l] * a;
    pre.colwise() += net.bias[l];
    for (Eigen::Index unit = 0; unit < pre.rows(); ++unit) {
      // Exactly 0 at the sample its bias was taken from (same product, same rounding).
      EXPECT_EQ(pre.row(unit).cwiseAbs().minCoeff(), 0.0f) << "layer " << l << " unit " << unit;
    }
    a = pre.cwiseMax(0.0f);
  }
}

TEST(MlpInit, same_seed_same_network_other_seed_differs) {
  const TrainingMatrix z = training_columns(2, 30);
  Random a(5), b(5), c(6);
  const TrainingNetwork na = initial_network(2, {8}, z, a), nb = initial_network(2, {8}, z, b),
                        nc = initial_network(2, {8}, z, c);
  EXPECT_EQ(na.weights[0], nb.weights[0]);
  EXPECT_EQ(na.bias[0], nb.bias[0]);
  EXPECT_NE(na.weights[0], nc.weights[0]);
}

}  // namespace
}  // namespace pyrocam::mlp_training
