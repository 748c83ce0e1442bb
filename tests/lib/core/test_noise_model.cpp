// The EMVA 1288 signal noise: shot noise grows with the signal by the band's gain, the read and
// quantisation noise of the frame and of its dark both count, and averaging frames divides it.
#include <gtest/gtest.h>

#include <cmath>

#include "pyrocam/core/error.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/physics.h"
#include "pyrocam/core/precision_limit.h"
#include "pyrocam/core/profile.h"

namespace pyrocam {
namespace {

TEST(NoiseModel, variance_is_shot_noise_plus_frame_and_dark_floors) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  for (int b = 0; b < p.band_count(); ++b) {
    const double k = p.band_gain[b] * p.noise.system_gain_dn_per_e;  // DN per electron
    const double read_dn = k * p.noise.read_noise_e;
    // One frame's read and quantisation noise, and the same again for its dark.
    const double floor = 2 * (read_dn * read_dn + 1.0 / 12);
    EXPECT_NEAR(signal_variance_dn2(p, b, 0), floor, 1e-12 * floor) << b;
    // Shot noise: the variance in DN^2 grows by k per DN of signal.
    EXPECT_NEAR(signal_variance_dn2(p, b, 100) - signal_variance_dn2(p, b, 0), 100 * k, 1e-9 * k)
        << b;
    // A negative signal (noise below the dark) has no shot noise.
    EXPECT_EQ(signal_variance_dn2(p, b, -20), signal_variance_dn2(p, b, 0)) << b;
    // The mean of four frames: a quarter of the variance; 0 frames count as one.
    EXPECT_NEAR(signal_variance_dn2(p, b, 100, 4), signal_variance_dn2(p, b, 100) / 4,
                1e-12 * signal_variance_dn2(p, b, 100))
        << b;
    EXPECT_EQ(signal_variance_dn2(p, b, 100, 0), signal_variance_dn2(p, b, 100)) << b;
    // The per-band form the pixel loops use.
    const SignalNoise n = signal_noise(p, b);
    EXPECT_DOUBLE_EQ(n.shot_gain, k) << b;
    EXPECT_DOUBLE_EQ(n.floor_dn2, floor) << b;
  }
}

TEST(NoiseModel, bands_with_more_gain_are_noisier) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  for (int a = 0; a < p.band_count(); ++a)
    for (int b = 0; b < p.band_count(); ++b)
      if (p.band_gain[a] > p.band_gain[b]) {
        EXPECT_GT(signal_variance_dn2(p, a, 50), signal_variance_dn2(p, b, 50)) << a << " " << b;
      }
}

// Bands of one wavelength each (500, 600, 700 nm) with shot noise only: the bound is METHOD.md's
// shot-noise limit T^4 / (c2^2 N Var_w(1/lambda)), Wien's law being exact to 1e-7 there at
// 1000 degC; with two bands it is the ratio formula dT = T^2 / c2 lambda1 lambda2 /
// (lambda2 - lambda1) sqrt(1/N1 + 1/N2); one band tells nothing.
TEST(PrecisionLimit, is_the_shot_noise_limit_for_bands_of_one_wavelength) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const double lambda_nm[3] = {500, 600, 700};
  Eigen::MatrixXd qe = Eigen::MatrixXd::Zero(3, p.grid.size());
  for (int b = 0; b < 3; ++b) qe(b, p.grid.index_of(lambda_nm[b])) = 1;
  const CameraModel camera{p, qe, Eigen::VectorXd::Ones(3)};
  const double t_c = 1000, t_k = celsius_to_kelvin(t_c);
  const Eigen::VectorXd k = p.dn_per_electron();
  // A graybody's means at some scale, and shot noise only: N_b electrons.
  Eigen::VectorXd mean = camera.rates(t_c);
  mean *= 150 / mean.maxCoeff();
  const Eigen::VectorXd electrons = mean.cwiseQuotient(k), shot = mean.cwiseProduct(k);
  double n = 0, mean_inverse = 0, mean_square = 0;
  for (int b = 0; b < 3; ++b) {
    const double inverse = 1 / (lambda_nm[b] * 1e-9);
    n += electrons[b], mean_inverse += electrons[b] * inverse,
        mean_square += electrons[b] * inverse * inverse;
  }
  mean_inverse /= n, mean_square /= n;
  const double limit =
      t_k * t_k / (kC2 * std::sqrt(n * (mean_square - mean_inverse * mean_inverse)));
  EXPECT_NEAR(temperature_precision_limit_k(camera, t_c, mean, shot), limit, 1e-5 * limit);

  Eigen::VectorXd two = mean;
  two[2] = 0;  // no light: no information
  const double l1 = 500e-9, l2 = 600e-9;
  const double ratio_limit =
      t_k * t_k / kC2 * l1 * l2 / (l2 - l1) * std::sqrt(1 / electrons[0] + 1 / electrons[1]);
  EXPECT_NEAR(temperature_precision_limit_k(camera, t_c, two, shot), ratio_limit,
              1e-5 * ratio_limit);
  two[1] = NAN;
  EXPECT_TRUE(std::isinf(temperature_precision_limit_k(camera, t_c, two, shot)));
  // Read noise only adds variance: the bound grows.
  Eigen::VectorXd noisy = shot;
  for (int b = 0; b < 3; ++b) noisy[b] = signal_variance_dn2(p, b, mean[b]);
  EXPECT_GT(temperature_precision_limit_k(camera, t_c, mean, noisy), limit);
  EXPECT_THROW(temperature_precision_limit_k(camera, t_c, mean.head(2), shot), InputError);
}

}  // namespace
}  // namespace pyrocam
