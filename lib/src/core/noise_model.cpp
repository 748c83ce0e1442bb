#include "pyrocam/core/noise_model.h"

#include <algorithm>
#include <cmath>

#include "detail/portable_math.h"

namespace pyrocam {

double analogue_gain_factor(double gain_db) { return portable::pow(10.0, gain_db / 20); }

SignalNoise signal_noise(const CameraProfile& p, int band, double gain) {
  const double k = p.band_gain[band] * p.noise.system_gain_dn_per_e;
  const double read = k * p.noise.read_noise_e;
  return {k * gain, 2 * (read * read + 1.0 / 12)};
}

double signal_variance_dn2(const CameraProfile& p, int band, double signal_dn, int frames,
                           double gain) {
  const SignalNoise n = signal_noise(p, band, gain);
  return (n.shot_gain * std::max(signal_dn, 0.0) + n.floor_dn2) / std::max(frames, 1);
}

double no_signal_level_dn(const std::vector<SignalNoise>& noise) {
  double floor = 0;
  for (const SignalNoise& n : noise) floor = std::max(floor, n.floor_dn2);
  return 5 * std::sqrt(floor);
}

}  // namespace pyrocam
