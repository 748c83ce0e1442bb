#include "pyrocam/core/physics.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>

#include "detail/portable_math.h"
#include "detail/vector_clones.h"

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

namespace {

// Four doubles (and four 64-bit integers) that the compiler keeps in one AVX register, two SSE
// ones in the baseline version.
typedef double Quad __attribute__((vector_size(32)));
typedef std::int64_t QuadInt __attribute__((vector_size(32)));

// Beyond this portable::exp overflows; from 0.5 on portable::expm1 is exp(x) - 1.
constexpr double kExpMainLow = 0.5, kExpMainHigh = 709.782712893383973096;

// portable::expm1 on four x within [kExpMainLow, kExpMainHigh]: its exp's main path operation
// for operation (the same constants and order, so the same bits; the library is built without
// fused multiply-adds). Results by reference: a vector returned by value changes the baseline's
// ABI.
inline void expm1_main_path(const Quad& x, Quad& out) {
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kInvLn2 = 1.44269504088896338700e+00;
  constexpr double kP1 = 1.66666666666666019037e-01, kP2 = -2.77777777770155933842e-03,
                   kP3 = 6.61375632143793436117e-05, kP4 = -1.65339022054652515390e-06,
                   kP5 = 4.13813679705723846039e-08;
  const QuadInt k = __builtin_convertvector(kInvLn2 * x + 0.5, QuadInt);  // x > 0: truncates
  const Quad kd = __builtin_convertvector(k, Quad);
  const Quad hi = x - kd * kLn2Hi, lo = kd * kLn2Lo, r = hi - lo;
  const Quad t = r * r;
  const Quad c = r - t * (kP1 + t * (kP2 + t * (kP3 + t * (kP4 + t * kP5))));
  const Quad y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
  const QuadInt half = k / 2;
  const Quad first = reinterpret_cast<Quad>((half + 1023) << 52);
  const Quad second = reinterpret_cast<Quad>((k - half + 1023) << 52);
  out = y * first * second - 1.0;
}

}  // namespace

// Four wavelengths at a time where Planck's exponent lies on portable::exp's main path (every
// temperature these cameras see): the same bits as planck_photon_radiance times the weight, at a
// fraction of its cost (its divisions pipeline across the lanes). Other wavelengths go through
// planck_photon_radiance itself.
PYROCAM_VECTOR_CLONES
Eigen::VectorXd weighted_photon_radiance(const WavelengthGrid& grid, double temperature_k,
                                         double emissivity) {
  const Eigen::Index n = grid.size();
  Eigen::VectorXd out(n);
  const double* nm = grid.nm().data();
  const double* weight = grid.weights_m().data();
  const double scale = emissivity * 2.0 * kSpeedOfLight;
  Eigen::Index i = 0;
  for (; i + 4 <= n; i += 4) {
    Quad wavelength, w;
    std::memcpy(&wavelength, nm + i, sizeof wavelength);
    std::memcpy(&w, weight + i, sizeof w);
    wavelength = wavelength * 1e-9;
    const Quad x = kC2 / (wavelength * temperature_k);
    bool main_path = true;
    for (int j = 0; j < 4; ++j) main_path &= x[j] >= kExpMainLow && x[j] <= kExpMainHigh;
    if (!main_path) break;
    Quad em1;
    expm1_main_path(x, em1);
    const Quad radiance = scale / (wavelength * wavelength * wavelength * wavelength) / em1 * w;
    std::memcpy(out.data() + i, &radiance, sizeof radiance);
  }
  for (; i < n; ++i)
    out[i] = planck_photon_radiance(nm[i] * 1e-9, temperature_k, emissivity) * weight[i];
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
