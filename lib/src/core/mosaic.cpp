#include "pyrocam/core/mosaic.h"

#include <algorithm>

#include "pyrocam/core/error.h"

namespace pyrocam {

int MosaicLayout::band_count() const {
  return band_map.empty() ? 0 : *std::max_element(band_map.begin(), band_map.end()) + 1;
}

void MosaicLayout::check_whole_periods(int width, int height, const std::string& what) const {
  if (width % period_width || height % period_height)
    throw InputError(what + ": " + std::to_string(width) + "x" + std::to_string(height) +
                     " is not a whole number of " + pattern + " mosaic periods (" +
                     std::to_string(period_width) + "x" + std::to_string(period_height) + ")");
}

MosaicLayout MosaicLayout::bayer(const std::string& pattern) {
  std::string p = pattern;
  std::transform(p.begin(), p.end(), p.begin(), ::toupper);
  MosaicLayout layout;
  layout.kind = Kind::kBayer;
  layout.pattern = p;
  if (p == "RGGB")
    layout.band_map = {0, 1, 1, 2};
  else if (p == "BGGR")
    layout.band_map = {2, 1, 1, 0};
  else if (p == "GRBG")
    layout.band_map = {1, 0, 2, 1};
  else if (p == "GBRG")
    layout.band_map = {1, 2, 0, 1};
  else
    throw InputError("unknown Bayer pattern '" + pattern + "' (use RGGB, BGGR, GRBG or GBRG)");
  return layout;
}

MosaicLayout MosaicLayout::snapshot(int period_width, int period_height, std::vector<int> map) {
  if (period_width < 1 || period_height < 1 ||
      map.size() != static_cast<std::size_t>(period_width * period_height))
    throw InputError("snapshot mosaic band map must have " + std::to_string(period_height) +
                     " rows of " + std::to_string(period_width) + " band indices");
  std::vector<int> sorted = map;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i)
    if (sorted[i] != static_cast<int>(i))
      throw InputError("snapshot mosaic band map must use each band index 0.." +
                       std::to_string(map.size() - 1) + " exactly once");
  MosaicLayout layout;
  layout.kind = Kind::kSnapshot;
  layout.pattern = std::to_string(period_width) + "x" + std::to_string(period_height);
  layout.period_width = period_width;
  layout.period_height = period_height;
  layout.band_map = std::move(map);
  return layout;
}

}  // namespace pyrocam
