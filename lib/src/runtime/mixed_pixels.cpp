#include "pyrocam/runtime/mixed_pixels.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

constexpr int kMaxBands = 3;

struct Offsets {
  // Per band, the (dx, dy) of its samples in the footprint.
  std::array<std::vector<cv::Point>, kMaxBands> of_band;
};

// Whether one band's samples are one level: spread within the allowance. Squares, not a square
// root: most footprints are well inside the relative allowance alone.
inline bool uniform(float lo, float hi, const SignalNoise& n, const FootprintCheck& c) {
  const double beyond = (hi - lo) - c.relative_spread * std::max(hi, 0.f);
  if (beyond <= 0) return true;
  const double var = n.shot_gain * (std::max(lo, 0.f) + std::max(hi, 0.f)) + 2 * n.floor_dn2;
  return beyond * beyond <= c.k_sigma * c.k_sigma * var;
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
    // Each band's samples lie on period-2 lattices (R and B one each, G two: the even and the
    // odd rows' G); the samples of a lattice in a pixel's 3x3 window are those in the rows and
    // the columns of the window on the lattice: {y} or {y-1, y+1}, times {x} or {x-1, x+1}.
    // Row by row: min and max down the lattice rows for every column, then across the lattice
    // columns: a few contiguous passes the compiler vectorises, not 9 loads per pixel.
    struct Lattice {
      int band, row_parity, column_parity;
    };
    std::vector<Lattice> lattices;
    for (int py = 0; py < 2; ++py)
      for (int px = 0; px < 2; ++px) lattices.push_back({layout.band_at(px, py), py, px});
    auto row = [&](int y) {
      return mosaic.ptr<float>(y < 0 ? -y : y >= height ? 2 * height - 2 - y : y);
    };
    std::vector<float> vlo(static_cast<std::size_t>(width) + 2),
        vhi(static_cast<std::size_t>(width) + 2);
    std::vector<float> hlo(static_cast<std::size_t>(width)), hhi(static_cast<std::size_t>(width));
    std::vector<std::uint8_t> mixed(static_cast<std::size_t>(width));
    for (int y = 0; y < height; ++y) {
      std::fill(mixed.begin(), mixed.end(), 0);
      for (const Lattice& l : lattices) {
        const SignalNoise& n = check.noise[static_cast<std::size_t>(l.band)];
        // Down the rows: vlo/vhi[x + 1] for column x, mirrored columns at both ends.
        const float* a = row((y & 1) == l.row_parity ? y : y - 1);
        const float* b = row((y & 1) == l.row_parity ? y : y + 1);
        float* lo_col = vlo.data() + 1;
        float* hi_col = vhi.data() + 1;
        for (int x = 0; x < width; ++x) {
          // Non-finite samples (saturated, no reading) are left out: +INF never lowers a min,
          // and it is replaced by -INF for the max.
          const float u = a[x], v = b[x];
          const float u_hi = u < std::numeric_limits<float>::infinity() ? u : -u;
          const float v_hi = v < std::numeric_limits<float>::infinity() ? v : -v;
          lo_col[x] = u < v ? u : v;
          hi_col[x] = u_hi > v_hi ? u_hi : v_hi;
        }
        if (width > 1) {
          vlo[0] = vlo[2], vhi[0] = vhi[2];
          vlo[static_cast<std::size_t>(width) + 1] = vlo[static_cast<std::size_t>(width) - 1];
          vhi[static_cast<std::size_t>(width) + 1] = vhi[static_cast<std::size_t>(width) - 1];
        }
        // Across the columns, then the test: branch-free passes.
        for (int x = l.column_parity; x < width; x += 2)
          hlo[static_cast<std::size_t>(x)] = lo_col[x],
          hhi[static_cast<std::size_t>(x)] = hi_col[x];
        for (int x = 1 - l.column_parity; x < width; x += 2) {
          hlo[static_cast<std::size_t>(x)] = std::min(lo_col[x - 1], lo_col[x + 1]);
          hhi[static_cast<std::size_t>(x)] = std::max(hi_col[x - 1], hi_col[x + 1]);
        }
        const float rel = static_cast<float>(check.relative_spread);
        const float k2 = static_cast<float>(check.k_sigma * check.k_sigma);
        const float gain = static_cast<float>(n.shot_gain);
        const float floor2 = static_cast<float>(2 * n.floor_dn2);
        const float* lo = hlo.data();
        const float* hi = hhi.data();
        std::uint8_t* m = mixed.data();
        for (int x = 0; x < width; ++x) {
          const float h = std::max(hi[x], 0.f);
          const float beyond = (hi[x] - lo[x]) - rel * h;
          const float var = gain * (std::max(lo[x], 0.f) + h) + floor2;
          // Footprints without two finite samples have hi < lo: beyond < 0.
          m[x] |= static_cast<std::uint8_t>(beyond > 0.f && beyond * beyond > k2 * var);
        }
      }
      for (int x = 0; x < width; ++x)
        if (mixed[static_cast<std::size_t>(x)]) {
          set_nan(planes, x, y);
          ++marked;
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
