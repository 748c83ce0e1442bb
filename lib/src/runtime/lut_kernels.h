// The lookup table's per-pixel passes (lut_estimator.cpp; not installed), compiled for AVX2 too
// (PYROCAM_VECTOR_CLONES): the same bits in every version.
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>

#include "pyrocam/runtime/mlp.h"

namespace pyrocam::lut {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr float kInTable = 0.0f, kOffTable = -1.0f;  // pixel status codes; NaN: no reading

struct Grid {
  float dim, inv_h, offset_x, offset_y, cells_x, cells_y;
};

// Status and table coordinates (cells) of m pixels from their two numerators a, b and their
// reference r; `others_read` (may be null) flags pixels whose other bands are all readable.
// Coordinates are 0 where the status is not kInTable. Returns whether any pixel reads.
bool coordinates(const float* a, const float* b, const float* r, const float* others_read,
                 std::size_t m, Grid g, float* status, float* fx, float* fy);

// Whether any of m values is at least `dim` (NaN is not).
bool any_at_least(const float* v, std::size_t m, float dim);

// Block of each pixel, the index of its cell's first corner among the block's nodes, and its
// position in the cell.
void cells(const float* fx, const float* fy, std::size_t m, int shift, std::int32_t blocks_x,
           std::int32_t* block, std::int32_t* cell, float* wx, float* wy);

// Bilinear interpolation from each pixel's four cell corners (pairs: below[2k], below[2k + 1] the
// cell's lower corners, above[...] its upper ones; 0 where the status is not kInTable), then
// `special` = 1 for the pixels the network answers: off the table, or near or beyond a range
// end. Returns whether there are any.
bool interpolate(const float* lower, const float* upper, const float* wx, const float* wy,
                 const float* status, std::size_t m, MlpOutputTransform space, float lowest,
                 float highest, float* out, float* special);

}  // namespace pyrocam::lut
