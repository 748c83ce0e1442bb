#include "pyrocam/runtime/mixed_pixels.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

constexpr int kMaxBands = 3;

struct Offsets {
  // Per band, the (dx, dy) of its samples in the footprint.
  std::array<std::vector<cv::Point>, kMaxBands> of_band;
};

// Whether one band's samples are one level: spread within the allowance.
inline bool uniform(float lo, float hi, const SignalNoise& n, const FootprintCheck& c) {
  const double var = n.shot_gain * (std::max(lo, 0.f) + std::max(hi, 0.f)) + 2 * n.floor_dn2;
  return hi - lo <= c.k_sigma * std::sqrt(var) + c.relative_spread * std::max(hi, 0.f);
}

void set_nan(std::vector<cv::Mat>& planes, int x, int y) {
  for (cv::Mat& p : planes) p.at<float>(y, x) = std::numeric_limits<float>::quiet_NaN();
}

}  // namespace

std::size_t mark_mixed_pixels(const cv::Mat& mosaic, const MosaicLayout& layout,
                              DemosaicMethod method, const FootprintCheck& check,
                              std::vector<cv::Mat>& planes) {
  if (layout.kind != MosaicLayout::Kind::kBayer) return 0;
  if (mosaic.type() != CV_32F) throw InputError("mixed pixels: the mosaic must be CV_32F");
  const int bands = layout.band_count();
  if (bands > kMaxBands || static_cast<int>(check.noise.size()) < bands)
    throw InputError("mixed pixels: a noise model for each of the " + std::to_string(bands) +
                     " bands is needed");
  const cv::Size out = demosaic_output_size(layout, method, mosaic.size());
  if (static_cast<int>(planes.size()) != bands)
    throw InputError("mixed pixels: planes do not match the mosaic's bands");
  for (const cv::Mat& p : planes)
    if (p.type() != CV_32F || p.size() != out)
      throw InputError("mixed pixels: planes do not match demosaic's output");
  const int width = mosaic.cols, height = mosaic.rows;
  std::size_t marked = 0;
  std::array<float, kMaxBands> lo{}, hi{};

  auto test = [&](const Offsets& offsets, int cx, int cy, bool mirror) {
    for (int b = 0; b < bands; ++b) {
      lo[b] = std::numeric_limits<float>::infinity();
      hi[b] = -std::numeric_limits<float>::infinity();
      for (const cv::Point& d : offsets.of_band[static_cast<std::size_t>(b)]) {
        int x = cx + d.x, y = cy + d.y;
        if (mirror) {
          x = x < 0 ? -x : x >= width ? 2 * width - 2 - x : x;
          y = y < 0 ? -y : y >= height ? 2 * height - 2 - y : y;
        }
        const float v = mosaic.at<float>(y, x);
        if (!std::isfinite(v)) continue;
        lo[b] = std::min(lo[b], v);
        hi[b] = std::max(hi[b], v);
      }
      if (hi[b] > lo[b] && !uniform(lo[b], hi[b], check.noise[static_cast<std::size_t>(b)], check))
        return false;
    }
    return true;
  };

  if (method == DemosaicMethod::kBilinear) {
    // The footprint's offsets for each parity of the output pixel.
    std::array<std::array<Offsets, 2>, 2> offsets;  // [y parity][x parity]
    for (int py = 0; py < 2; ++py)
      for (int px = 0; px < 2; ++px)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            offsets[py][px]
                .of_band[static_cast<std::size_t>(layout.band_at(px + dx + 2, py + dy + 2))]
                .push_back({dx, dy});
    for (int y = 0; y < height; ++y) {
      const bool edge_row = y == 0 || y == height - 1;
      for (int x = 0; x < width; ++x) {
        const bool mirror = edge_row || x == 0 || x == width - 1;
        if (!test(offsets[y & 1][x & 1], x, y, mirror)) {
          set_nan(planes, x, y);
          ++marked;
        }
      }
    }
  } else {
    Offsets cell;
    for (int dy = 0; dy < layout.period_height; ++dy)
      for (int dx = 0; dx < layout.period_width; ++dx)
        cell.of_band[static_cast<std::size_t>(layout.band_at(dx, dy))].push_back({dx, dy});
    for (int y = 0; y < out.height; ++y)
      for (int x = 0; x < out.width; ++x)
        if (!test(cell, x * layout.period_width, y * layout.period_height, false)) {
          set_nan(planes, x, y);
          ++marked;
        }
  }
  return marked;
}

}  // namespace pyrocam
