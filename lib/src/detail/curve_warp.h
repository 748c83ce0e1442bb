// A spectral curve read at other wavelengths: how the simulator makes a unit's shifted bands and
// moved filter edges, and how the QE fit models them (the same interpolation on both sides).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "pyrocam/core/spectrum.h"

namespace pyrocam::detail {

// curve(source_nm[i]) for each grid sample i, linear between samples, clamped to the grid.
inline Eigen::VectorXd warp_curve(const Eigen::VectorXd& curve, const WavelengthGrid& grid,
                                  const Eigen::ArrayXd& source_nm) {
  Eigen::VectorXd out(curve.size());
  const double last = static_cast<double>(curve.size() - 1);
  for (Eigen::Index i = 0; i < curve.size(); ++i) {
    const double pos = std::clamp((source_nm[i] - grid.start_nm()) / grid.step_nm(), 0.0, last);
    const auto i0 = static_cast<Eigen::Index>(std::floor(pos));
    const auto i1 = std::min<Eigen::Index>(i0 + 1, curve.size() - 1);
    const double f = pos - static_cast<double>(i0);
    out[i] = curve[i0] * (1 - f) + curve[i1] * f;
  }
  return out;
}

// The curve moved by shift_nm towards longer wavelengths.
inline Eigen::VectorXd shift_curve(const Eigen::VectorXd& curve, const WavelengthGrid& grid,
                                   double shift_nm) {
  return warp_curve(curve, grid, grid.nm().array() - shift_nm);
}

}  // namespace pyrocam::detail
