// The "true" system QE of a simulated unit: how a real camera differs from its datasheet.
#include <algorithm>
#include <cmath>

#include "detail/curve_warp.h"
#include "detail/portable_math.h"
#include "detail/random.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam {
namespace {

using detail::shift_curve;
using detail::warp_curve;

// The hostile family's changes to the optics, common to all bands: the filter's pass-band
// edges moved independently by 3-10 nm, one or two narrow leaks within 50 nm outside an edge
// at 0.2-3 % transmission, and a neutral-density glass whose transmission slopes by up to
// +-30 % over 700-1000 nm.
Eigen::VectorXd hostile_optics(const CameraProfile& profile, Random& rng) {
  const WavelengthGrid& grid = profile.grid;
  const double lo = profile.filter_pass_band_nm[0], hi = profile.filter_pass_band_nm[1];
  const auto edge_move = [&]() { return (rng.uniform() < 0.5 ? -1 : 1) * rng.uniform(3, 10); };
  const double d_lo = edge_move(), d_hi = edge_move();
  // Piecewise-linear warp: what sat at an edge now sits d nm further along.
  Eigen::VectorXd source(grid.size());
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    const double x = grid.nm()[i];
    const double f = std::clamp((x - lo) / (hi - lo), 0.0, 1.0);
    source[i] = x - (d_lo * (1 - f) + d_hi * f);
  }
  Eigen::VectorXd optics = warp_curve(profile.optics_transmission, grid, source.array());
  const double slope = rng.uniform(-0.3, 0.3);  // relative change over 700-1000 nm
  const int leaks = 1 + static_cast<int>(rng.below(2));
  for (int k = 0; k < leaks; ++k) {
    const bool below = rng.uniform() < 0.5;
    const double centre = below ? lo + d_lo - rng.uniform(5, 50) : hi + d_hi + rng.uniform(5, 50);
    const double fwhm = rng.uniform(5, 20), peak = rng.uniform(0.002, 0.03);
    const double s = fwhm / 2.3548;
    for (Eigen::Index i = 0; i < grid.size(); ++i) {
      const double z = (grid.nm()[i] - centre) / s;
      optics[i] += peak * portable::exp(-0.5 * z * z);
    }
  }
  for (Eigen::Index i = 0; i < grid.size(); ++i)
    optics[i] =
        std::clamp(optics[i] * std::max(0.05, 1 + slope * (grid.nm()[i] - 850) / 300), 0.0, 1.0);
  return optics;
}

// Per band shape changes beyond scale and tilt: Legendre P2 and P3 terms over the band's
// response span and a Gaussian bump or dip inside it, each of about 5 % rms.
Eigen::VectorXd hostile_shape(const Eigen::VectorXd& sensor, const WavelengthGrid& grid,
                              Random& rng) {
  const double peak = sensor.maxCoeff();
  Eigen::Index first = 0, last = sensor.size() - 1;
  while (first < last && sensor[first] < 0.1 * peak) ++first;
  while (last > first && sensor[last] < 0.1 * peak) --last;
  const double a = grid.nm()[first], b = grid.nm()[last] + grid.step_nm();
  const double p2 = 0.05 * rng.normal(), p3 = 0.05 * rng.normal();
  const double bump = 0.05 * rng.normal(), centre = rng.uniform(a, b);
  const double width = rng.uniform(0.1, 0.3) * (b - a);
  Eigen::VectorXd factor(sensor.size());
  for (Eigen::Index i = 0; i < sensor.size(); ++i) {
    const double x = std::clamp(2 * (grid.nm()[i] - a) / (b - a) - 1, -1.0, 1.0);
    const double z = (grid.nm()[i] - centre) / width;
    factor[i] = std::max(0.0, 1 + p2 * 0.5 * (3 * x * x - 1) + p3 * 0.5 * (5 * x * x * x - 3 * x) +
                                  bump * portable::exp(-0.5 * z * z));
  }
  return factor;
}

// The foreign family: deviations of other kinds than the hostile family's, made to check the QE
// fit on cameras it was not built around (nothing is chosen by its figures). The filter's curve
// moved as a whole (an interference filter seen at an angle moves to the blue: -12..+3 nm) with
// its edges softened (a Gaussian of 1-6 nm), blocking that lets 0.05-0.5 % through everywhere,
// and a lens or window whose transmission bends smoothly over the whole range (its log a linear
// and a quadratic term over the grid, coefficients of 0.1 rms).
Eigen::VectorXd foreign_optics(const CameraProfile& profile, Random& rng) {
  const WavelengthGrid& grid = profile.grid;
  const Eigen::VectorXd moved = shift_curve(profile.optics_transmission, grid, rng.uniform(-12, 3));
  const double sigma = rng.uniform(1, 6), background = rng.uniform(0.0005, 0.005);
  const double a = 0.1 * rng.normal(), b = 0.1 * rng.normal();
  const double first = grid.nm()[0], span = grid.nm()[grid.size() - 1] - first;
  Eigen::VectorXd optics(grid.size());
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    double sum = 0, weights = 0;  // the edges softened
    for (Eigen::Index j = 0; j < grid.size(); ++j) {
      const double z = (grid.nm()[j] - grid.nm()[i]) / sigma;
      if (std::abs(z) > 4) continue;
      const double w = portable::exp(-0.5 * z * z);
      sum += w * moved[j], weights += w;
    }
    const double x = 2 * (grid.nm()[i] - first) / span - 1;
    const double lens = portable::exp(a * x + b * (x * x - 1.0 / 3));
    optics[i] = std::clamp((sum / weights + background) * lens, 0.0, 1.0);
  }
  return optics;
}

// Per band: the sensor's response stretched or squeezed about its peak by 3 % rms, and a smooth
// random change of its shape (four sinusoids of 100-400 nm period in its log, each of 0.05 rms).
Eigen::VectorXd foreign_band(const Eigen::VectorXd& sensor, const WavelengthGrid& grid,
                             Random& rng) {
  Eigen::Index peak = 0;
  sensor.maxCoeff(&peak);
  const double centre = grid.nm()[peak], stretch = 1 + 0.03 * rng.normal();
  Eigen::ArrayXd source = centre + (grid.nm().array() - centre) / stretch;
  Eigen::VectorXd band = detail::warp_curve(sensor, grid, source);
  double period[4], phase[4], amplitude[4];
  for (int k = 0; k < 4; ++k)
    period[k] = rng.uniform(100, 400), phase[k] = rng.uniform(0, 2 * M_PI),
    amplitude[k] = 0.05 * std::sqrt(2.0) * rng.normal();
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    double log_factor = 0;
    for (int k = 0; k < 4; ++k)
      log_factor += amplitude[k] * portable::sin(2 * M_PI * grid.nm()[i] / period[k] + phase[k]);
    band[i] *= portable::exp(log_factor);
  }
  return band;
}

}  // namespace

UnitPerturbation UnitPerturbation::parse(const std::string& name, std::uint64_t seed) {
  if (name != "datasheet" && name != "typical" && name != "hostile" && name != "foreign")
    throw InputError("unknown unit perturbation '" + name +
                     "' (use datasheet, typical, hostile or foreign)");
  return UnitPerturbation{name, seed};
}

Eigen::MatrixXd true_system_qe(const CameraProfile& profile, const UnitPerturbation& unit) {
  if (unit.name == "datasheet") return profile.system_qe();
  const bool hostile = unit.name == "hostile", foreign = unit.name == "foreign";
  const UnitVariation& v = profile.unit_variation;
  Random rng(mix(unit.seed));
  const auto normal = [](Random& r) { return r.normal(); };
  const auto uniform = [](Random& r) { return r.uniform(0.7, 1.3); };
  const WavelengthGrid& grid = profile.grid;
  const double centre_nm = 0.5 * (profile.filter_pass_band_nm[0] + profile.filter_pass_band_nm[1]);

  // A filter leak adds transmission; what it adds to each band follows that band's sensor QE.
  Eigen::VectorXd leak = Eigen::VectorXd::Zero(grid.size());
  const double a = v.leak_range_nm[0], b = v.leak_range_nm[1];
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    const double x = grid.nm()[i];
    if (x > a && x < b) leak[i] = 0.5 - 0.5 * portable::cos(2 * M_PI * (x - a) / (b - a));
  }
  double peak_qe = 0;
  for (Eigen::Index i = 0; i < grid.size(); ++i)
    if (leak[i] > 0) peak_qe = std::max(peak_qe, profile.sensor_qe.col(i).maxCoeff());
  const double leak_level = peak_qe > 0 ? v.leak_system_qe * uniform(rng) / peak_qe : 0.0;

  // The deviations no QE solver here models (its own random stream, so that the components
  // above stay the same for a seed whatever these are set to).
  Random unmodelled(mix(unit.seed ^ 0x5EC0DE5ull));
  const auto unmodelled_normal = [](Random& r) { return r.normal(); };
  Eigen::VectorXd optics =
      v.filter_shift_sigma_nm > 0
          ? shift_curve(profile.optics_transmission, grid,
                        v.filter_shift_sigma_nm * unmodelled_normal(unmodelled))
          : profile.optics_transmission;
  const auto ripple = [&]() {
    // Three sinusoids of random period and phase, together of relative rms v.ripple_rms.
    Eigen::VectorXd factor = Eigen::VectorXd::Ones(grid.size());
    if (!(v.ripple_rms > 0)) return factor;
    const auto period = [&](Random& r) {
      return r.uniform(v.ripple_period_nm[0], v.ripple_period_nm[1]);
    };
    const auto phase = [](Random& r) { return r.uniform(0.0, 2 * M_PI); };
    const double amplitude = v.ripple_rms * std::sqrt(2.0 / 3.0);
    for (int k = 0; k < 3; ++k) {
      const double p = period(unmodelled), f = phase(unmodelled);
      for (Eigen::Index i = 0; i < grid.size(); ++i)
        factor[i] += amplitude * portable::sin(2 * M_PI * grid.nm()[i] / p + f);
    }
    return Eigen::VectorXd(factor.cwiseMax(0.0));
  };
  const Eigen::VectorXd common_ripple = ripple();
  // The hostile family on top of the typical one, from a third stream (typical units of a seed
  // stay as they were).
  Random hostile_rng(mix(unit.seed ^ 0x4057115Eull));
  if (hostile) optics = hostile_optics(profile, hostile_rng);
  if (foreign) optics = foreign_optics(profile, hostile_rng);

  Eigen::MatrixXd q(profile.band_count(), grid.size());
  for (int band = 0; band < profile.band_count(); ++band) {
    const double shift = v.shift_sigma_nm * normal(rng);
    const double scale = 1.0 + v.scale_sigma * normal(rng);
    const double tilt = v.tilt_sigma * normal(rng);
    Eigen::VectorXd sensor = shift_curve(profile.sensor_qe.row(band).transpose(), grid, shift);
    if (hostile) sensor = sensor.cwiseProduct(hostile_shape(sensor, grid, hostile_rng));
    if (foreign) sensor = foreign_band(sensor, grid, hostile_rng);
    const Eigen::VectorXd band_ripple = ripple().cwiseProduct(common_ripple);
    for (Eigen::Index i = 0; i < grid.size(); ++i) {
      const double factor =
          std::max(0.0, scale * (1.0 + tilt * (grid.nm()[i] - centre_nm) / 100.0));
      const double value =
          sensor[i] * optics[i] * band_ripple[i] * factor + leak_level * leak[i] * sensor[i];
      q(band, i) = std::clamp(value, 0.0, 1.0);
    }
  }
  return q;
}

}  // namespace pyrocam
