// A natural log that vectorises and gives the same bits on every machine, for band samples.
#pragma once

#include <cstdint>
#include <cstring>

namespace pyrocam {

// Natural log of a positive normal float to about 1e-6, with +, -, *, / and bit operations only:
// the same bits on every machine, and a loop of it vectorises. x = 2^k m with m in [sqrt(1/2),
// sqrt(2)) (the offset moves the exponent's boundary there, as musl's logf does); log m =
// 2 atanh(s), s = (m - 1) / (m + 1), |s| < 0.172, five terms of the series.
inline float log_positive(float x) {
  constexpr std::uint32_t kOne = 0x3f800000u, kSqrtHalf = 0x3f3504f3u;
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  bits += kOne - kSqrtHalf;
  const int k = static_cast<int>(bits >> 23) - 127;
  bits = (bits & 0x7fffffu) + kSqrtHalf;
  float m;
  std::memcpy(&m, &bits, sizeof m);
  const float s = (m - 1.f) / (m + 1.f), z = s * s;
  const float series = 1.f + z * (1.f / 3 + z * (1.f / 5 + z * (1.f / 7 + z * (1.f / 9))));
  return static_cast<float>(k) * 0.693147181f + 2.f * s * series;
}

}  // namespace pyrocam
