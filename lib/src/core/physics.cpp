#include "pyrocam/core/physics.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "detail/portable_math.h"

namespace pyrocam {

double planck_energy_radiance(double wavelength_m, double temperature_k, double emissivity) {
  const double x = kC2 / (wavelength_m * temperature_k);
  // expm1 keeps precision in the Rayleigh-Jeans limit (x small).
  return emissivity * kC1L /
         (wavelength_m * wavelength_m * wavelength_m * wavelength_m * wavelength_m) /
         portable::expm1(x);
}

double planck_photon_radiance(double wavelength_m, double temperature_k, double emissivity) {
  const double x = kC2 / (wavelength_m * temperature_k);
  return emissivity * 2.0 * kSpeedOfLight /
         (wavelength_m * wavelength_m * wavelength_m * wavelength_m) / portable::expm1(x);
}

WavelengthGrid::WavelengthGrid(double start_nm, double stop_nm, double step_nm)
    : start_nm_(start_nm), stop_nm_(stop_nm), step_nm_(step_nm) {
  if (!(start_nm > 0) || !(stop_nm > start_nm) || !(step_nm > 0))
    throw std::invalid_argument("wavelength grid needs 0 < start < stop and step > 0 (got " +
                                std::to_string(start_nm) + ".." + std::to_string(stop_nm) +
                                " step " + std::to_string(step_nm) + " nm)");
  const double steps = (stop_nm - start_nm) / step_nm;
  // Checked before lround, which is undefined for values beyond a long.
  if (!(steps < static_cast<double>(kMaxWavelengthSamples) - 0.5))
    throw std::invalid_argument("wavelength grid " + std::to_string(start_nm) + ".." +
                                std::to_string(stop_nm) + " nm step " + std::to_string(step_nm) +
                                " nm has more than " + std::to_string(kMaxWavelengthSamples) +
                                " samples");
  const long n = std::lround(steps);
  if (std::abs(steps - n) > 1e-6)
    throw std::invalid_argument("wavelength grid step " + std::to_string(step_nm) +
                                " nm does not divide " + std::to_string(start_nm) + ".." +
                                std::to_string(stop_nm) + " nm");
  nm_.resize(n + 1);
  for (long i = 0; i <= n; ++i) nm_[i] = start_nm + i * step_nm;
  weights_m_ = Eigen::VectorXd::Constant(n + 1, step_nm * 1e-9);
  weights_m_[0] *= 0.5;
  weights_m_[n] *= 0.5;
}

Eigen::Index WavelengthGrid::index_of(double wavelength_nm) const {
  const long i = std::lround((wavelength_nm - start_nm_) / step_nm_);
  if (i < 0) return 0;
  if (i >= nm_.size()) return nm_.size() - 1;
  return i;
}

Eigen::VectorXd weighted_photon_radiance(const WavelengthGrid& grid, double temperature_k,
                                         double emissivity) {
  Eigen::VectorXd out(grid.size());
  for (Eigen::Index i = 0; i < grid.size(); ++i)
    out[i] = planck_photon_radiance(grid.nm()[i] * 1e-9, temperature_k, emissivity) *
             grid.weights_m()[i];
  return out;
}

Eigen::VectorXd band_photon_integrals(const Eigen::MatrixXd& system_qe, const WavelengthGrid& grid,
                                      double temperature_k, double emissivity) {
  if (system_qe.cols() != grid.size())
    throw std::invalid_argument("system QE has " + std::to_string(system_qe.cols()) +
                                " wavelength samples, the grid " + std::to_string(grid.size()));
  return system_qe * weighted_photon_radiance(grid, temperature_k, emissivity);
}

}  // namespace pyrocam
