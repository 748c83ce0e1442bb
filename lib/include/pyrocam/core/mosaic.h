// Colour filter array layouts: which band each sensor pixel sees.
#pragma once

#include <string>
#include <vector>

namespace pyrocam {

// A periodic mosaic: a period_width x period_height cell of band indices repeated over the
// sensor. Bayer 2x2 patterns and 5x5 snapshot mosaics are both of this form.
struct MosaicLayout {
  enum class Kind { kBayer, kSnapshot };

  Kind kind = Kind::kBayer;
  std::string pattern;  // "RGGB", "BGGR", "GRBG", "GBRG" for Bayer; "5x5" for snapshot mosaics
  int period_width = 2;
  int period_height = 2;
  std::vector<int> band_map;  // period_height rows of period_width band indices, row-major

  int band_at(int x, int y) const {
    return band_map[(y % period_height) * period_width + (x % period_width)];
  }
  int band_count() const;
  // Throws InputError unless width x height is a whole number of periods; `what` names the
  // image in the message.
  void check_whole_periods(int width, int height, const std::string& what) const;

  // Bayer with bands R=0, G=1, B=2. Throws InputError for an unknown pattern.
  static MosaicLayout bayer(const std::string& pattern);
  // Snapshot mosaic; band_map rows of equal length, each band index in [0, bands).
  static MosaicLayout snapshot(int period_width, int period_height, std::vector<int> band_map);
};

}  // namespace pyrocam
