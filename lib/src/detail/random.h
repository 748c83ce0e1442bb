// Seeded random numbers that mean the same with any standard library and on any CPU:
// std::mt19937_64 is specified exactly, the standard distributions are not (and libstdc++'s call
// glibc's per-CPU log), so these are written out over the library's own exp, log and cos.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "detail/portable_math.h"

namespace pyrocam {

// SplitMix64: decorrelated seeds for frames, stripes and units from one user seed.
inline std::uint64_t mix(std::uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  std::uint64_t bits() { return engine_(); }
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }    // [lo, hi)
  double normal() {                     // Box-Muller, one value per pair
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * portable::log(u1)) * portable::cos(2.0 * M_PI * u2);
  }
  // Poisson counts by multiplying uniforms (Knuth): exact in distribution, meant for small means
  // (the cost grows with the mean).
  long poisson(double mean) {
    const double limit = portable::exp(-mean);
    long k = 0;
    for (double p = uniform(); p > limit; p *= uniform()) ++k;
    return k;
  }
  // Uniform in [0, n); modulo bias is below 2^-40 for any n we shuffle.
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(engine_() % n); }
  template <class T>
  void shuffle(std::vector<T>& v) {
    for (std::size_t i = v.size(); i > 1; --i) std::swap(v[i - 1], v[below(i)]);
  }

 private:
  std::mt19937_64 engine_;
};

}  // namespace pyrocam
