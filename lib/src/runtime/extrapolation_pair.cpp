#include "pyrocam/runtime/extrapolation_pair.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/physics.h"

namespace pyrocam {
namespace {

// Of each band, the overlap of its normalised signal spectra at two temperatures.
std::vector<double> spectral_overlap(const CameraModel& camera, double cool_c, double hot_c) {
  const WavelengthGrid& grid = camera.profile.grid;
  const Eigen::ArrayXd cool = weighted_photon_radiance(grid, celsius_to_kelvin(cool_c)).array();
  const Eigen::ArrayXd hot = weighted_photon_radiance(grid, celsius_to_kelvin(hot_c)).array();
  std::vector<double> overlap;
  for (Eigen::Index b = 0; b < camera.system_qe.rows(); ++b) {
    const Eigen::ArrayXd q = camera.system_qe.row(b).transpose().array();
    const Eigen::ArrayXd a = q * cool, h = q * hot;
    const double sa = a.sum(), sh = h.sum();
    overlap.push_back(sa > 0 && sh > 0 ? (a / sa).min(h / sh).sum() : 0.0);
  }
  return overlap;
}

}  // namespace

ExtrapolationPair extrapolation_pair(const CameraModel& camera, const Locus& locus,
                                     double calibrated_up_to_c, double top_c) {
  ExtrapolationPair pair;
  const Eigen::Index n = locus.size();
  if (camera.system_qe.rows() != 3 || n < 3 || !std::isfinite(calibrated_up_to_c) ||
      !(calibrated_up_to_c >= locus.temperature_c[0] &&
        calibrated_up_to_c < locus.temperature_c[n - 1]))
    return pair;
  pair.from_c = calibrated_up_to_c;
  if (std::isnan(top_c)) top_c = locus.temperature_c[n - 1];
  pair.overlap = spectral_overlap(camera, calibrated_up_to_c, kExtrapolationOverlapC);
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int a, int b) { return pair.overlap[a] > pair.overlap[b]; });
  const int i = std::min(order[0], order[1]), j = std::max(order[0], order[1]), o = order[2];
  // The noise of both readings in log ratios against the denominator: x1 = ln(s_i / s_j) (the
  // pair), x2 = ln(s_o / s_j); v_b the relative variance of band b.
  const double step = locus.temperature_c[1] - locus.temperature_c[0];
  const auto log_ratio = [&](Eigen::Index k, int a) {
    return std::log(locus.rates(k, a) / locus.rates(k, j));
  };
  pair.noise_ratio.assign(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
  pair.weight.assign(static_cast<std::size_t>(n), 0.0);
  bool any = false;
  for (Eigen::Index k = 1; k + 1 < n; ++k) {
    const Eigen::Vector3d rates = locus.rates.row(k).transpose();
    if (!(rates.minCoeff() > 0)) continue;
    const Eigen::Vector3d s = rates * (kPairNoiseSignalDn / rates.maxCoeff());
    double v[3];
    for (int b = 0; b < 3; ++b) v[b] = signal_variance_dn2(camera.profile, b, s[b]) / (s[b] * s[b]);
    const Eigen::Vector2d g((log_ratio(k + 1, i) - log_ratio(k - 1, i)) / (2 * step),
                            (log_ratio(k + 1, o) - log_ratio(k - 1, o)) / (2 * step));
    Eigen::Matrix2d c;
    c << v[i] + v[j], v[j], v[j], v[o] + v[j];
    const double information_all = g.dot(c.ldlt().solve(g));
    const double information_pair = g[0] * g[0] / (v[i] + v[j]);
    if (!(information_pair > 0 && information_all > 0)) continue;
    const double ratio = std::sqrt(information_all / information_pair);
    pair.noise_ratio[static_cast<std::size_t>(k)] = ratio;
    const double t = locus.temperature_c[k];
    if (t <= calibrated_up_to_c) continue;
    const double ramp =
        std::clamp(std::min(t - calibrated_up_to_c, top_c - t) / kExtrapolationBlendC, 0.0, 1.0);
    const double precise = std::clamp(
        (kPairNoNoiseRatio - ratio) / (kPairNoNoiseRatio - kPairFullNoiseRatio), 0.0, 1.0);
    pair.weight[static_cast<std::size_t>(k)] = ramp * precise;
    any = any || ramp * precise > 0;
  }
  if (any) pair.numerator = i, pair.denominator = j;
  return pair;
}

}  // namespace pyrocam
