// The saturation level as an edge that a band value's own noise does not decide.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <type_traits>
#include <vector>

#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/dim_edge.h"

namespace pyrocam {

// darksub marks a raw sample at the saturation level +INF, and a band value drawn from such a
// sample is dropped (partial bands) or leaves its pixel without a reading. On a surface whose
// band lies near that level, the values that stay are those whose noise pulled them down, and
// the readings lean one way (a colour 1500 degC plate with red at the level: a fifth of it read,
// 8 degC high; a 5x5 2600 degC plate with a band at the level: 3 degC lower than the exposures
// around it read). The check decides from the band's values around the pixel, in the ring outside
// its demosaicking footprint that the dim-edge check reads (dim_edge.h): a band value near the
// level is marked saturated too where the mean of one of the ring's halves, its saturated
// values counted at the level, lies within kNoiseMargin of a raw sample's noise below the
// level. (Counted as brighter than any, one saturated sample of 38 in a ring marked the band:
// a plate 3 standard deviations below the level lost 14 % of its readings.) A uniform
// surface then keeps the band on all its pixels or on none; near a saturated spot the band is
// dropped within the ring's reach (its pixels read from the other bands, or not at all where
// every band must read). Values further above the level than the check's margin are not the
// frame's own samples (mosaicfuse scales a shorter exposure's up): neither they nor pixels
// whose ring holds one are checked. (Checked, the bracket targets' fused mosaics read 75 % of
// the pool hotter than 1300 degC instead of 87 %: every band must read there.)
class SaturationEdgeCheck {
 public:
  // A raw sample's noise at the level, in standard deviations: where the surface lies this far
  // below it, the level cuts off 2.3 % of a normal noise and leaves the rest's mean 0.055 of
  // them low.
  static constexpr double kNoiseMargin = 2.0;
  // A band value further below the level than this is not checked.
  static constexpr double kCheckedMargin = 6.0;
  static constexpr std::size_t kMaxBands = 64;  // the constructor refuses more

  // Levels per band from the raw saturation level (DN, samples at or above it are +INF) less
  // the profile's dark offset, and the noise model at it with the analogue gain (a factor); a
  // level of +INF (nothing saturates) checks nothing. Throws InputError for NaN.
  SaturationEdgeCheck(const CameraProfile& profile, double gain, double saturation_level_dn);
  int bands() const { return static_cast<int>(mark_dn_.size()); }  // 0: no check
  // The level less the dark offset, DN: what the ring's saturated values count as.
  double level_dn() const { return level_dn_; }
  // Above this (DN) a value is not a sample of the frame's own exposure (a fused bracket's,
  // scaled up; no plain frame has one short of +INF): a ring holding one is no evidence, and the
  // check leaves its pixels alone.
  double foreign_above_dn() const { return foreign_above_dn_; }
  // Per band; +INF for every band where the check is off (bands() 0).
  float mark_dn(int band) const { return level(mark_dn_, band); }
  float checked_dn(int band) const { return level(checked_dn_, band); }

  // Marks +INF the values rows[b][0 .. n) (output pixels x0 .. x0 + n - 1 of row y) between
  // checked_dn and the level plus its margin whose span's ring's largest half mean
  // `window_mean(b, first, last, y)` (spans of `span_columns` from column 0 on; saturated values
  // counted at level_dn) is at least mark_dn: such a band's row is copied into scratch[b] (n
  // values) and rows[b] points there. A band's row without a value to check costs one
  // vectorised pass. With `every_band_reads` (no partial fit), a pixel with a band already
  // saturated or invalid has no reading anyway and is not checked (on a plate whose red
  // saturates, green near the level cost a ring per span for nothing: 60 % more of the colour
  // chain's time).
  template <class WindowMean>
  void apply(const float** rows, std::size_t n, int x0, int y, const WindowMean& window_mean,
             std::vector<std::vector<float>>& scratch, int span_columns,
             bool every_band_reads) const {
    const std::size_t nb = mark_dn_.size();
    if (scratch.size() < nb) scratch.resize(nb);
    for (std::size_t b = 0; b < nb; ++b) {
      const float low = checked_dn_[b], high = upper_dn_[b];
      const float* row = rows[b];
      if (!any_within(row, n, low, high)) continue;
      float* copy = nullptr;  // made at the first mark
      int span_of = -1;
      bool span_marks = false;
      int four_from = -1;  // RingMeans: the first of four spans' means held
      double four[4];
      for (std::size_t i = 0; i < n; ++i) {
        if (!(row[i] >= low && row[i] <= high)) continue;
        if (every_band_reads && !all_finite(rows, nb, i)) continue;
        const int span = (x0 + static_cast<int>(i)) / span_columns * span_columns;
        if (span != span_of) {  // the span's ring, read once
          span_of = span;
          double mean;
          if constexpr (std::is_same_v<WindowMean, RingMeans>) {
            if (four_from < 0 || span < four_from || span >= four_from + 4 * span_columns) {
              four_from = span;
              window_mean.four(static_cast<int>(b), span, span_columns, y, four);
            }
            mean = four[(span - four_from) / span_columns];
          } else {
            mean = window_mean(static_cast<int>(b), span, span + span_columns - 1, y);
          }
          span_marks = marks(b, mean);
        }
        if (!span_marks) continue;
        if (!copy) {
          scratch[b].assign(row, row + n);
          copy = scratch[b].data();
        }
        copy[i] = INFINITY;
      }
      if (copy) rows[b] = copy;
    }
  }

  // Whether a checked band value with `ring_mean` (the largest half's, saturated values at
  // level_dn; NaN where the ring holds a foreign value) around it is marked saturated.
  bool marks(std::size_t band, double ring_mean) const { return ring_mean >= mark_dn_[band]; }

 private:
  static float level(const std::vector<float>& levels, int band) {
    return levels.empty() ? INFINITY : levels[static_cast<std::size_t>(band)];
  }
  // Whether one of values[0 .. n) lies in [low, high] (vectorised).
  static bool any_within(const float* values, std::size_t n, float low, float high);
  static bool all_finite(const float* const* rows, std::size_t bands, std::size_t i) {
    for (std::size_t b = 0; b < bands; ++b)
      if (!std::isfinite(rows[b][i])) return false;
    return true;
  }
  double level_dn_ = 0, foreign_above_dn_ = 0;
  std::vector<float> mark_dn_, checked_dn_, upper_dn_;
};

}  // namespace pyrocam
