#include "pyrocam/runtime/saturation_edge.h"

#include <string>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/noise_model.h"

namespace pyrocam {

SaturationEdgeCheck::SaturationEdgeCheck(const CameraProfile& profile, double gain,
                                         double saturation_level_dn) {
  const int bands = profile.band_count();
  if (bands > static_cast<int>(kMaxBands))
    throw InputError("saturation-edge check: " + std::to_string(bands) + " bands, at most " +
                     std::to_string(kMaxBands));
  if (std::isnan(saturation_level_dn) || saturation_level_dn == -INFINITY)
    throw InputError("saturation-edge check: saturation level " +
                     std::to_string(saturation_level_dn) + " DN is not a number");
  if (saturation_level_dn == INFINITY) {  // nothing is saturated: no check
    level_dn_ = foreign_above_dn_ = INFINITY;
    return;
  }
  // The signal of a sample at the level, after the dark frame (about the profile's offset).
  const double level = saturation_level_dn - profile.dark_offset_dn;
  level_dn_ = level;
  double largest_sd = 0;
  for (int b = 0; b < bands; ++b) {
    const double sd = std::sqrt(signal_variance_dn2(profile, b, std::max(level, 0.0), 1, gain));
    mark_dn_.push_back(static_cast<float>(level - kNoiseMargin * sd));
    checked_dn_.push_back(static_cast<float>(level - kCheckedMargin * sd));
    upper_dn_.push_back(static_cast<float>(level + kCheckedMargin * sd));
    largest_sd = std::max(largest_sd, sd);
  }
  foreign_above_dn_ = level + kCheckedMargin * largest_sd;
}

PYROCAM_VECTOR_CLONES
bool SaturationEdgeCheck::any_within(const float* values, std::size_t n, float low, float high) {
  int any = 0;
  for (std::size_t i = 0; i < n; ++i) any |= (values[i] >= low) & (values[i] <= high);
  return any != 0;
}

}  // namespace pyrocam
