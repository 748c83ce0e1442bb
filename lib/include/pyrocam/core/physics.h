// Planck's law and its integration over a camera's system quantum efficiency
// (Sala et al. 2025, eq. 3-4; METHOD.md section 1).
#pragma once

#include <Eigen/Core>

namespace pyrocam {

// CODATA 2018 exact constants; c2 as used by the paper and ITS-90.
inline constexpr double kPlanck = 6.62607015e-34;                              // J s
inline constexpr double kSpeedOfLight = 299792458.0;                           // m/s
inline constexpr double kBoltzmann = 1.380649e-23;                             // J/K
inline constexpr double kC1L = 2.0 * kPlanck * kSpeedOfLight * kSpeedOfLight;  // W m^2 sr^-1
inline constexpr double kC2 = 1.4388e-2;                                       // m K
// Wien constant consistent with kC2: c2 / x where x = 5 (1 - exp(-x)).
inline constexpr double kWienB = kC2 / 4.965114231744276;   // m K
inline constexpr double kStefanBoltzmann = 5.670374419e-8;  // W m^-2 K^-4
inline constexpr double kZeroCelsius = 273.15;              // K

inline double celsius_to_kelvin(double t_c) { return t_c + kZeroCelsius; }
inline double kelvin_to_celsius(double t_k) { return t_k - kZeroCelsius; }

// Graybody spectral radiance, energy form: W m^-2 sr^-1 per metre of wavelength.
double planck_energy_radiance(double wavelength_m, double temperature_k, double emissivity = 1.0);

// Graybody spectral photon radiance: photons s^-1 m^-2 sr^-1 per metre of wavelength.
double planck_photon_radiance(double wavelength_m, double temperature_k, double emissivity = 1.0);

// The most samples any wavelength grid may have (160 MB of vectors): a grid is allocated from
// three numbers, so their ratio is bounded before anything is allocated. Files are held to the
// much smaller kMaxProfileWavelengthSamples (profile.h).
inline constexpr long kMaxWavelengthSamples = 10000001;

// Uniform wavelength sampling with trapezoidal integration weights.
class WavelengthGrid {
 public:
  WavelengthGrid() = default;
  // start..stop inclusive; throws std::invalid_argument unless 0 < start < stop, step > 0
  // divides the span (to 1e-6 nm) and the grid has at most kMaxWavelengthSamples samples.
  WavelengthGrid(double start_nm, double stop_nm, double step_nm);

  double start_nm() const { return start_nm_; }
  double stop_nm() const { return stop_nm_; }
  double step_nm() const { return step_nm_; }
  Eigen::Index size() const { return nm_.size(); }
  const Eigen::VectorXd& nm() const { return nm_; }
  // Trapezoid weights in metres: sum(w .* f) approximates the integral of f over wavelength.
  const Eigen::VectorXd& weights_m() const { return weights_m_; }
  // Index of the sample nearest to wavelength_nm, clamped to the grid.
  Eigen::Index index_of(double wavelength_nm) const;

 private:
  double start_nm_ = 0, stop_nm_ = 0, step_nm_ = 0;
  Eigen::VectorXd nm_, weights_m_;
};

// Photon radiance at every grid wavelength, already multiplied by the integration weights, so
// that a band's photon integral is a dot product with its system QE.
Eigen::VectorXd weighted_photon_radiance(const WavelengthGrid& grid, double temperature_k,
                                         double emissivity = 1.0);

// Integral of Q(lambda) * Lp(lambda, T) d lambda, photons s^-1 m^-2 sr^-1, per band:
// system_qe is bands x wavelengths on `grid`.
Eigen::VectorXd band_photon_integrals(const Eigen::MatrixXd& system_qe, const WavelengthGrid& grid,
                                      double temperature_k, double emissivity = 1.0);

// Wien's displacement law: wavelength of maximum spectral (energy) radiance, metres.
inline double wien_peak_wavelength_m(double temperature_k) { return kWienB / temperature_k; }

}  // namespace pyrocam
