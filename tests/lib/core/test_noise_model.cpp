// The EMVA 1288 signal noise: shot noise grows with the signal by the band's gain, the read and
// quantisation noise of the frame and of its dark both count, and averaging frames divides it.
#include <gtest/gtest.h>

#include "pyrocam/core/noise_model.h"
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

}  // namespace
}  // namespace pyrocam
