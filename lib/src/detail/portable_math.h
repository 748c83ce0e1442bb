// exp, log, pow, sin and cos that give the same bits on every x86-64 machine. glibc picks a
// variant of its libm functions per CPU (FMA, AVX2) when the program loads, and those variants
// differ in the last bit now and then; the calibration (simulated campaigns, QE fit, network
// training) is chaotic enough to turn one such bit into another network, and a test that passed on
// one machine into one that fails on another. These use only +, -, *, / and exact scaling by powers
// of two, which IEEE 754 rounds the same everywhere (the library is built with -ffp-contract=off,
// and x86-64 has no excess precision). Accuracy: about 1 ulp (fdlibm's algorithms and
// coefficients, Sun Microsystems 1993, freely usable).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace pyrocam::portable {

namespace detail {
// 2^k for k in [-1022, 1023], exactly.
inline double power_of_two(int k) {
  const std::uint64_t bits = static_cast<std::uint64_t>(k + 1023) << 52;
  double d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}
}  // namespace detail

inline double exp(double x) {
  constexpr double kLn2Hi = 6.93147180369123816490e-01;  // trailing zeros: k * kLn2Hi is exact
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kInvLn2 = 1.44269504088896338700e+00;
  constexpr double kP1 = 1.66666666666666019037e-01, kP2 = -2.77777777770155933842e-03,
                   kP3 = 6.61375632143793436117e-05, kP4 = -1.65339022054652515390e-06,
                   kP5 = 4.13813679705723846039e-08;
  if (!(x <= 709.782712893383973096)) return x > 0 ? std::numeric_limits<double>::infinity() : x;
  if (x < -745.13321910194110842) return 0.0;
  if (std::fabs(x) < 0x1p-28) return 1.0 + x;
  const int k = static_cast<int>(kInvLn2 * x + (x < 0 ? -0.5 : 0.5));
  const double hi = x - k * kLn2Hi, lo = k * kLn2Lo, r = hi - lo;
  const double t = r * r;
  const double c = r - t * (kP1 + t * (kP2 + t * (kP3 + t * (kP4 + t * kP5))));
  const double y = 1.0 - ((lo - (r * c) / (2.0 - c)) - hi);
  // Two exact factors keep 2^k representable for k from -1075 to 1024.
  return y * detail::power_of_two(k / 2) * detail::power_of_two(k - k / 2);
}

inline double log(double x) {
  constexpr double kLn2Hi = 6.93147180369123816490e-01, kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kLg1 = 6.666666666666735130e-01, kLg2 = 3.999999999940941908e-01,
                   kLg3 = 2.857142874366239149e-01, kLg4 = 2.222219843214978396e-01,
                   kLg5 = 1.818357216161805012e-01, kLg6 = 1.531383769920937332e-01,
                   kLg7 = 1.479819860511658591e-01;
  if (std::isnan(x) || x < 0) return std::numeric_limits<double>::quiet_NaN();
  if (x == 0) return -std::numeric_limits<double>::infinity();
  if (std::isinf(x)) return x;
  int k = 0;
  if (x < 0x1p-1000) {  // subnormal and tiny: scale up first (exact)
    x *= 0x1p100;
    k = -100;
  }
  std::uint64_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  k += static_cast<int>((bits >> 52) & 0x7ff) - 1022;
  bits = (bits & 0x000fffffffffffffull) | 0x3fe0000000000000ull;  // mantissa in [0.5, 1)
  double m;
  std::memcpy(&m, &bits, sizeof m);
  if (m < 0.70710678118654752440) {
    m *= 2;
    --k;
  }
  const double f = m - 1.0;  // exact (Sterbenz), in [-0.293, 0.415)
  const double s = f / (2.0 + f), z = s * s, w = z * z;
  const double t1 = w * (kLg2 + w * (kLg4 + w * kLg6));
  const double t2 = z * (kLg1 + w * (kLg3 + w * (kLg5 + w * kLg7)));
  const double r = t2 + t1, hfsq = 0.5 * f * f, dk = k;
  return dk * kLn2Hi - ((hfsq - (s * (hfsq + r) + dk * kLn2Lo)) - f);
}

// e^x - 1 without the loss near 0 (Kahan's trick: the rounding of e^x is undone by log).
inline double expm1(double x) {
  if (std::fabs(x) >= 0.5) return exp(x) - 1.0;
  const double u = exp(x);
  if (u == 1.0) return x;
  const double um1 = u - 1.0;
  if (um1 == -1.0) return -1.0;
  return um1 * x / log(u);
}

// x^y for x > 0 (the only use here).
inline double pow(double x, double y) {
  if (y == 0) return 1.0;
  return exp(y * log(x));
}

namespace detail {
// sin and cos on [-pi/4, pi/4].
inline double kernel_sin(double x) {
  constexpr double kS1 = -1.66666666666666324348e-01, kS2 = 8.33333333332248946124e-03,
                   kS3 = -1.98412698298579493134e-04, kS4 = 2.75573137070700676789e-06,
                   kS5 = -2.50507602534068634195e-08, kS6 = 1.58969099521155010221e-10;
  const double z = x * x, v = z * x;
  const double r = kS2 + z * (kS3 + z * (kS4 + z * (kS5 + z * kS6)));
  return x + v * (kS1 + z * r);
}
inline double kernel_cos(double x) {
  constexpr double kC1 = 4.16666666666666019037e-02, kC2 = -1.38888888888741095749e-03,
                   kC3 = 2.48015872894767294178e-05, kC4 = -2.75573143513906633035e-07,
                   kC5 = 2.08757232129817482790e-09, kC6 = -1.13596475577881948265e-11;
  const double z = x * x;
  const double r = z * (kC1 + z * (kC2 + z * (kC3 + z * (kC4 + z * (kC5 + z * kC6)))));
  const double hz = 0.5 * z, w = 1.0 - hz;
  return w + (((1.0 - w) - hz) + z * r);
}
// x = n pi/2 + r, |r| <= pi/4; good to about 1 ulp for |x| < 2^19 pi/2 (every use here is far
// smaller).
inline double reduce_half_pi(double x, int& n) {
  constexpr double kInvPio2 = 6.36619772367581382433e-01;
  constexpr double kPio2_1 = 1.57079632673412561417e+00;   // first 33 bits of pi/2
  constexpr double kPio2_1t = 6.07710050650619224932e-11;  // pi/2 - kPio2_1
  n = static_cast<int>(x * kInvPio2 + (x < 0 ? -0.5 : 0.5));
  const double fn = n;
  return (x - fn * kPio2_1) - fn * kPio2_1t;
}
}  // namespace detail

inline double sin(double x) {
  if (!std::isfinite(x)) return std::numeric_limits<double>::quiet_NaN();
  int n = 0;
  const double r = detail::reduce_half_pi(x, n);
  switch (n & 3) {
    case 0:
      return detail::kernel_sin(r);
    case 1:
      return detail::kernel_cos(r);
    case 2:
      return -detail::kernel_sin(r);
    default:
      return -detail::kernel_cos(r);
  }
}

inline double cos(double x) {
  if (!std::isfinite(x)) return std::numeric_limits<double>::quiet_NaN();
  int n = 0;
  const double r = detail::reduce_half_pi(x, n);
  switch (n & 3) {
    case 0:
      return detail::kernel_cos(r);
    case 1:
      return -detail::kernel_sin(r);
    case 2:
      return -detail::kernel_cos(r);
    default:
      return detail::kernel_sin(r);
  }
}

}  // namespace pyrocam::portable
