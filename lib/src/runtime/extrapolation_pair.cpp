#include "pyrocam/runtime/extrapolation_pair.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "detail/portable_math.h"
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
    return portable::log(locus.rates(k, a) / locus.rates(k, j));
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
  const Normalisation& ratios = camera.profile.normalisation;
  const auto place = [&](int band) {
    for (std::size_t k = 0; k < ratios.numerators.size(); ++k)
      if (ratios.numerators[k] == band) return static_cast<int>(k);
    return ratios.reference.size() == 1 && ratios.reference[0] == band ? -1 : -2;
  };
  if (!any || place(i) == -2 || place(j) == -2) return pair;
  pair.numerator = i, pair.denominator = j;
  pair.numerator_ratio = place(i), pair.denominator_ratio = place(j);
  pair.locus_start_c = locus.temperature_c[0];
  pair.locus_step_c = step;
  for (Eigen::Index k = 0; k < n; ++k) pair.log_ratio.push_back(log_ratio(k, i));
  // The branches: runs of intervals over which the ratio moves one way (a flat interval joins
  // the run before it).
  const auto direction = [&](std::size_t k) {
    const double d = pair.log_ratio[k + 1] - pair.log_ratio[k];
    return d > 0 ? 1 : d < 0 ? -1 : 0;
  };
  const std::size_t intervals = pair.log_ratio.size() - 1;
  pair.branch_first.assign(intervals, 0);
  pair.branch_last.assign(intervals, 0);
  for (std::size_t start = 0; start < intervals;) {
    int way = direction(start);
    std::size_t end = start + 1;  // one past the run's last interval
    for (; end < intervals; ++end) {
      const int d = direction(end);
      if (way == 0) way = d;
      if (d != 0 && d != way) break;
    }
    for (std::size_t k = start; k < end; ++k) {
      pair.branch_first[k] = static_cast<int>(start);
      pair.branch_last[k] = static_cast<int>(end);
    }
    start = end;
  }
  return pair;
}

double ExtrapolationPair::weight_at(double t) const {
  const double at = (t - locus_start_c) / locus_step_c;
  const auto last = static_cast<double>(weight.size() - 1);
  if (!(at > 0)) return weight.front();
  if (!(at < last)) return weight.back();
  const auto k = static_cast<std::size_t>(at);
  const double f = at - static_cast<double>(k);
  return weight[k] + f * (weight[k + 1] - weight[k]);
}

double ExtrapolationPair::read(double t, double pixel_log_ratio) const {
  if (!active() || !(t > from_c) || std::isnan(pixel_log_ratio)) return t;
  const auto intervals = static_cast<std::ptrdiff_t>(log_ratio.size()) - 1;
  const std::ptrdiff_t at = std::clamp<std::ptrdiff_t>(
      static_cast<std::ptrdiff_t>(std::floor((t - locus_start_c) / locus_step_c)), 0,
      intervals - 1);
  const auto first = static_cast<std::size_t>(branch_first[static_cast<std::size_t>(at)]);
  const auto last = static_cast<std::size_t>(branch_last[static_cast<std::size_t>(at)]);
  // Along the branch with the ratio rising: s = +-log ratio.
  const double sign = log_ratio[last] >= log_ratio[first] ? 1.0 : -1.0;
  const double l = sign * pixel_log_ratio;
  double pair_t;
  if (l <= sign * log_ratio[first]) {
    pair_t = locus_start_c + static_cast<double>(first) * locus_step_c;
  } else if (l >= sign * log_ratio[last]) {
    pair_t = locus_start_c + static_cast<double>(last) * locus_step_c;
  } else {
    std::size_t lo = first, hi = last;  // sign * ratio at lo < l <= at hi
    while (hi - lo > 1) {
      const std::size_t mid = (lo + hi) / 2;
      (sign * log_ratio[mid] < l ? lo : hi) = mid;
    }
    const double a = sign * log_ratio[lo], b = sign * log_ratio[hi];
    pair_t = locus_start_c + (static_cast<double>(lo) + (l - a) / (b - a)) * locus_step_c;
  }
  const double gap = std::abs(pair_t - t) / (t + kZeroCelsius);
  const double agree = std::clamp((kPairNoGap - gap) / (kPairNoGap - kPairFullGap), 0.0, 1.0);
  const double w = std::min(weight_at(t), weight_at(pair_t)) * agree;
  return t + w * (pair_t - t);
}

}  // namespace pyrocam
