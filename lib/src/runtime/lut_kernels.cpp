// The lookup table's per-pixel passes (lut_kernels.h).
#include "runtime/lut_kernels.h"

#include <cmath>

#include "detail/portable_math.h"
#include "detail/vector_clones.h"
#include "pyrocam/core/physics.h"

namespace pyrocam::lut {

// Selects the compiler turns into vector masks: NaN fails every comparison, +INF the upper ones.
PYROCAM_VECTOR_CLONES
bool coordinates(const float* __restrict a, const float* __restrict b, const float* __restrict r,
                 const float* __restrict others_read, std::size_t m, Grid g,
                 float* __restrict status, float* __restrict fx, float* __restrict fy) {
  for (std::size_t k = 0; k < m; ++k) {
    const float av = a[k], bv = b[k], rv = r[k];
    const float scale = g.inv_h / rv;
    const float x = av * scale - g.offset_x, y = bv * scale - g.offset_y;
    const bool inside = x >= 0.f && x < g.cells_x && y >= 0.f && y < g.cells_y;
    const float place = inside ? kInTable : kOffTable;
    const float unsaturated = av < kInf && bv < kInf && rv < kInf ? place : NAN;
    status[k] = av >= g.dim && bv >= g.dim && rv >= g.dim ? unsaturated : NAN;
    fx[k] = inside ? x : 0.f;
    fy[k] = inside ? y : 0.f;
  }
  if (others_read)
    for (std::size_t k = 0; k < m; ++k) status[k] = others_read[k] != 0.f ? status[k] : NAN;
  std::int32_t reads = 0;
  for (std::size_t k = 0; k < m; ++k) reads |= status[k] == status[k] ? 1 : 0;
  return reads != 0;
}

PYROCAM_VECTOR_CLONES
bool any_at_least(const float* __restrict v, std::size_t m, float dim) {
  std::int32_t any = 0;
  for (std::size_t k = 0; k < m; ++k) any |= v[k] >= dim ? 1 : 0;
  return any != 0;
}

PYROCAM_VECTOR_CLONES
void cells(const float* __restrict fx, const float* __restrict fy, std::size_t m, int shift,
           std::int32_t blocks_x, std::int32_t* __restrict block, std::int32_t* __restrict cell,
           float* __restrict wx, float* __restrict wy) {
  const std::int32_t mask = (1 << shift) - 1;
  for (std::size_t k = 0; k < m; ++k) {
    const auto ix = static_cast<std::int32_t>(fx[k]), iy = static_cast<std::int32_t>(fy[k]);
    block[k] = (iy >> shift) * blocks_x + (ix >> shift);
    cell[k] = (iy & mask) * ((1 << shift) + 1) + (ix & mask);
    wx[k] = fx[k] - static_cast<float>(ix);
    wy[k] = fy[k] - static_cast<float>(iy);
  }
}

PYROCAM_VECTOR_CLONES
bool interpolate(const float* __restrict lower, const float* __restrict upper,
                 const float* __restrict wx, const float* __restrict wy,
                 const float* __restrict status, std::size_t m, MlpOutputTransform space,
                 float lowest, float highest, float* __restrict out, float* __restrict special) {
  for (std::size_t k = 0; k < m; ++k) {
    const float c0 = lower[2 * k], c1 = lower[2 * k + 1], c2 = upper[2 * k], c3 = upper[2 * k + 1];
    const float below = c0 + wx[k] * (c1 - c0);
    const float above = c2 + wx[k] * (c3 - c2);
    const float v = below + wy[k] * (above - below);
    out[k] = status[k] == kInTable ? v : NAN;
  }
  // Back from the network's output space to degC (a value <= 0 of 1/T leaves the range).
  constexpr float kZeroCelsiusF = static_cast<float>(kZeroCelsius);
  if (space == MlpOutputTransform::kInverseKelvin) {
    for (std::size_t k = 0; k < m; ++k) out[k] = 1.f / out[k] - kZeroCelsiusF;
  } else if (space == MlpOutputTransform::kLogKelvin) {
    for (std::size_t k = 0; k < m; ++k) out[k] = portable::exp(out[k]) - kZeroCelsiusF;
  }
  // Selects in a separate loop, which the compiler vectorises.
  for (std::size_t k = 0; k < m; ++k) {
    const float t = out[k], st = status[k];
    const float outside_range = t >= lowest && t <= highest ? 0.f : 1.f;
    const float off_table = st == kOffTable ? 1.f : outside_range;
    special[k] = st == kInTable || st == kOffTable ? off_table : 0.f;
  }
  std::int32_t any = 0;
  for (std::size_t k = 0; k < m; ++k) any |= static_cast<std::int32_t>(special[k]);
  return any != 0;
}

}  // namespace pyrocam::lut
