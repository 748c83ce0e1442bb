#include "pyrocam/runtime/mixed_pixels.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core/utility.hpp>

#include "detail/vector_clones.h"
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

// The bilinear check of one row (see mark_mixed_pixels) in one branch-free pass that the
// compiler vectorises: mixed[x] = 1 where a footprint is not uniform. Non-finite samples
// (saturated, no reading) are left out: +INF never lowers a min, and it is replaced by -INF for
// the max. `r` is the row, `a` and `b` the rows above and below (mirrored at the ends); columns
// x - 1 and x + 1 must exist: the two end columns go through pixel_mixed with mirrored ones.
struct RowNoise {
  const float* gain[3];    // per column, the band of test t's lattice (0: row neighbours,
  const float* floor2[3];  // 1: column neighbours, 2: corners)
};

inline float high(float v) { return v < std::numeric_limits<float>::infinity() ? v : -v; }
// std::min and std::max on values (theirs select a reference, which does not vectorise).
inline float min_of(float a, float b) { return b < a ? b : a; }
inline float max_of(float a, float b) { return a < b ? b : a; }

// 1 where a band's samples spread beyond the allowance, else 0 (floats: one vector type).
inline float spread_exceeds(float lo, float hi, float gain, float floor2, float rel, float k2) {
  const float h = max_of(hi, 0.f);
  const float beyond = (hi - lo) - rel * h;
  const float var = gain * (max_of(lo, 0.f) + h) + floor2;
  // Footprints without two finite samples have hi < lo: beyond < 0.
  const float over = beyond * beyond > k2 * var ? 1.f : 0.f;
  return beyond > 0.f ? over : 0.f;
}

// One pixel from its footprint's samples: the row's at columns x - 1 and x + 1 (rl, rr), and
// the rows above and below at x - 1, x and x + 1.
inline float footprint_mixed(float rl, float rr, float al, float ac, float ar, float bl, float bc,
                             float br, float g0, float f0, float g1, float f1, float g2, float f2,
                             float rel, float k2) {
  const float row_lo = min_of(rl, rr);
  const float row_hi = max_of(high(rl), high(rr));
  const float col_lo = ac < bc ? ac : bc;
  const float ach = high(ac), bch = high(bc);
  const float col_hi = ach > bch ? ach : bch;
  const float lo_l = al < bl ? al : bl, lo_r = ar < br ? ar : br;
  const float alh = high(al), blh = high(bl), arh = high(ar), brh = high(br);
  const float hi_l = alh > blh ? alh : blh, hi_r = arh > brh ? arh : brh;
  const float corner_lo = min_of(lo_l, lo_r), corner_hi = max_of(hi_l, hi_r);
  return max_of(max_of(spread_exceeds(row_lo, row_hi, g0, f0, rel, k2),
                       spread_exceeds(col_lo, col_hi, g1, f1, rel, k2)),
                spread_exceeds(corner_lo, corner_hi, g2, f2, rel, k2));
}

// Pixel x with its neighbour columns xl and xr (mirrored at the row's ends).
inline float pixel_mixed(const float* r, const float* a, const float* b, std::size_t x,
                         std::size_t xl, std::size_t xr, const RowNoise& n, float rel, float k2) {
  return footprint_mixed(r[xl], r[xr], a[xl], a[x], a[xr], b[xl], b[x], b[xr], n.gain[0][x],
                         n.floor2[0][x], n.gain[1][x], n.floor2[1][x], n.gain[2][x], n.floor2[2][x],
                         rel, k2);
}

// Columns 1 to w - 2 (both neighbours inside the row).
PYROCAM_VECTOR_CLONES
void row_mixed(const float* __restrict r, const float* __restrict a, const float* __restrict b,
               std::size_t w, const float* __restrict g0, const float* __restrict f0,
               const float* __restrict g1, const float* __restrict f1, const float* __restrict g2,
               const float* __restrict f2, float rel, float k2, float* __restrict mixed) {
  for (std::size_t x = 1; x + 1 < w; ++x)
    mixed[x] = footprint_mixed(r[x - 1], r[x + 1], a[x - 1], a[x], a[x + 1], b[x - 1], b[x],
                               b[x + 1], g0[x], f0[x], g1[x], f1[x], g2[x], f2[x], rel, k2);
}

// 1 where spread_exceeds is 0 whatever the band: a spread within the relative allowance plus the
// noise allowance of the quietest band's floor, k2_floor = k_sigma^2 * min(2 floor) (the shot
// terms only add to a band's allowance, and float rounding is monotone). +INF (saturated) makes
// `beyond` NaN, which counts too.
inline std::int32_t within(float lo, float hi, float rel, float k2_floor) {
  const float beyond = (hi - lo) - rel * max_of(hi, 0.f);
  // Bitwise, not ||: a branch would keep the loop from being vectorised.
  return static_cast<std::int32_t>(beyond <= 0.f) |
         static_cast<std::int32_t>(beyond * beyond <= k2_floor);
}

// How many pixels of columns 1 to w - 2 a test may flag (not `within`). Where none may, row_mixed
// would find nothing: this costs about a third of it (the same three tests without +INF's care
// and the noise per column), and in a hot object's interior, where noise alone rarely reaches
// the allowance, it is all that runs.
PYROCAM_VECTOR_CLONES
std::int32_t count_may_exceed(const float* __restrict r, const float* __restrict a,
                              const float* __restrict b, std::size_t w, float rel, float k2_floor) {
  std::int32_t n = 0;
  for (std::size_t x = 1; x + 1 < w; ++x) {
    const float row_lo = min_of(r[x - 1], r[x + 1]), row_hi = max_of(r[x - 1], r[x + 1]);
    const float col_lo = min_of(a[x], b[x]), col_hi = max_of(a[x], b[x]);
    const float corner_lo = min_of(min_of(a[x - 1], b[x - 1]), min_of(a[x + 1], b[x + 1]));
    const float corner_hi = max_of(max_of(a[x - 1], b[x - 1]), max_of(a[x + 1], b[x + 1]));
    n += 1 - (within(row_lo, row_hi, rel, k2_floor) & within(col_lo, col_hi, rel, k2_floor) &
              within(corner_lo, corner_hi, rel, k2_floor));
  }
  return n;
}

// How many samples of three rows' columns [x0, x1) are at least `dim` (+INF, saturated, is).
PYROCAM_VECTOR_CLONES
std::int32_t count_bright(const float* __restrict r, const float* __restrict a,
                          const float* __restrict b, std::size_t x0, std::size_t x1, float dim) {
  std::int32_t n = 0;
  for (std::size_t x = x0; x < x1; ++x)
    n += (r[x] >= dim ? 1 : 0) + (a[x] >= dim ? 1 : 0) + (b[x] >= dim ? 1 : 0);
  return n;
}

// How many of a row's flags are set.
PYROCAM_VECTOR_CLONES
std::int32_t count_mixed(const float* __restrict mixed, std::size_t w) {
  std::int32_t n = 0;
  for (std::size_t x = 0; x < w; ++x) n += static_cast<std::int32_t>(mixed[x]);
  return n;
}

// The bilinear check (see mark_mixed_pixels) of output rows, any block of rows from any thread.
// Each band's samples lie on a period-2 lattice (R and B one each, G two: the even and the odd
// rows' G). In the 3x3 window of pixel (x, y) the lattice through the pixel itself has one
// sample (always uniform); the lattice on its row has the samples at x - 1 and x + 1; the
// lattice on its column those at y - 1 and y + 1; the fourth the four corners. So per row three
// tests per pixel from contiguous arrays shifted by one column, which the compiler vectorises.
// The arithmetic is that of `uniform`, in the same order.
class BilinearCheck {
 public:
  BilinearCheck(const cv::Mat& mosaic, const MosaicLayout& layout, const FootprintCheck& check)
      : mosaic_(mosaic),
        bands_(layout.band_count()),
        rel_(static_cast<float>(check.relative_spread)),
        k2_(static_cast<float>(check.k_sigma * check.k_sigma)),
        skip_(check.skip_below_dn) {
    const int width = mosaic.cols;
    for (int py = 0; py < 2; ++py)
      for (int t = 0; t < 3; ++t) {
        BandNoise& bn = noise_of_[static_cast<std::size_t>(py)][static_cast<std::size_t>(t)];
        bn.gain.resize(static_cast<std::size_t>(width));
        bn.floor2.resize(static_cast<std::size_t>(width));
        for (int x = 0; x < width; ++x) {
          const int lattice_x = t == 1 ? x : x + 1, lattice_y = t == 0 ? py : py + 1;
          const SignalNoise& n =
              check.noise[static_cast<std::size_t>(layout.band_at(lattice_x % 2, lattice_y % 2))];
          bn.gain[static_cast<std::size_t>(x)] = static_cast<float>(n.shot_gain);
          bn.floor2[static_cast<std::size_t>(x)] = static_cast<float>(2 * n.floor_dn2);
        }
      }
    float floor_min = std::numeric_limits<float>::infinity();
    for (int b = 0; b < bands_; ++b)
      floor_min = std::min(
          floor_min, static_cast<float>(2 * check.noise[static_cast<std::size_t>(b)].floor_dn2));
    k2_floor_ = k2_ * floor_min;
  }

  // Marks the mixed pixels of output rows [y0, y1); returns how many.
  std::size_t rows(int y0, int y1, std::vector<cv::Mat>& planes) const {
    const int height = mosaic_.rows;
    const auto w = static_cast<std::size_t>(mosaic_.cols);
    auto row = [&](int y) {
      return mosaic_.ptr<float>(y < 0 ? -y : y >= height ? 2 * height - 2 - y : y);
    };
    std::vector<float> mixed(w);
    std::size_t marked = 0;
    for (int y = y0; y < y1; ++y) {
      const auto& noise = noise_of_[static_cast<std::size_t>(y & 1)];
      RowNoise n{};
      for (std::size_t t = 0; t < 3; ++t) {
        n.gain[t] = noise[t].gain.data();
        n.floor2[t] = noise[t].floor2.data();
      }
      const float *r = row(y), *a = row(y - 1), *b = row(y + 1);
      // Only the marked pixels are written: a pass over the planes of every row with a mark
      // (most rows of a frame with an object) would cost more than all the tests.
      float* out[kMaxBands] = {};
      for (int band = 0; band < bands_; ++band)
        out[band] = planes[static_cast<std::size_t>(band)].ptr<float>(y);
      auto blank = [&](std::size_t x) {
        for (int band = 0; band < bands_; ++band)
          out[band][x] = std::numeric_limits<float>::quiet_NaN();
        ++marked;
      };
      // In chunks; a chunk whose footprints hold no sample at the skip level, or none whose
      // test may flag (count_may_exceed), is left out.
      constexpr std::size_t kChunk = 64;
      for (std::size_t x0 = 1; x0 + 1 < w; x0 += kChunk) {
        const std::size_t x1 = std::min(x0 + kChunk, w - 1);
        if (count_bright(r, a, b, x0 - 1, x1 + 1, skip_) == 0 ||
            count_may_exceed(r + x0 - 1, a + x0 - 1, b + x0 - 1, x1 - x0 + 2, rel_, k2_floor_) == 0)
          continue;
        row_mixed(r + x0 - 1, a + x0 - 1, b + x0 - 1, x1 - x0 + 2, n.gain[0] + x0 - 1,
                  n.floor2[0] + x0 - 1, n.gain[1] + x0 - 1, n.floor2[1] + x0 - 1,
                  n.gain[2] + x0 - 1, n.floor2[2] + x0 - 1, rel_, k2_, mixed.data() + x0 - 1);
        if (count_mixed(mixed.data() + x0, x1 - x0) == 0) continue;
        for (std::size_t x = x0; x < x1; ++x)
          if (mixed[x] != 0.f) blank(x);
      }
      // The end columns, their missing neighbour mirrored in (column -1 is 1, w is w - 2).
      const std::size_t inner = w > 1 ? 1 : 0;
      if (pixel_mixed(r, a, b, 0, inner, inner, n, rel_, k2_) != 0.f) blank(0);
      if (w > 1 && pixel_mixed(r, a, b, w - 1, w - 2, w - 2, n, rel_, k2_) != 0.f) blank(w - 1);
    }
    return marked;
  }

 private:
  struct BandNoise {
    std::vector<float> gain, floor2;  // per column: the band of the lattice tested there
  };
  const cv::Mat& mosaic_;
  int bands_;
  float rel_, k2_, skip_, k2_floor_ = 0;
  // For a row parity and a test (0: row neighbours, 1: column neighbours, 2: corners), the
  // noise of the band tested at each column.
  std::array<std::array<BandNoise, 3>, 2> noise_of_;
};

// Throws InputError unless the check can run on this mosaic; returns the resolved method.
DemosaicMethod check_inputs(const cv::Mat& mosaic, const MosaicLayout& layout,
                            DemosaicMethod method, const FootprintCheck& check) {
  method = resolve_demosaic_method(method, layout);
  if (mosaic.type() != CV_32F) throw InputError("mixed pixels: the mosaic must be CV_32F");
  const int bands = layout.band_count();
  if (bands > kMaxBands || static_cast<int>(check.noise.size()) < bands)
    throw InputError("mixed pixels: a noise model for each of the " + std::to_string(bands) +
                     " bands is needed");
  return method;
}

}  // namespace

std::size_t mark_mixed_pixels(const cv::Mat& mosaic, const MosaicLayout& layout,
                              DemosaicMethod method, const FootprintCheck& check,
                              std::vector<cv::Mat>& planes) {
  if (layout.kind != MosaicLayout::Kind::kBayer) return 0;
  method = check_inputs(mosaic, layout, method, check);
  const int bands = layout.band_count();
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
    const BilinearCheck bilinear(mosaic, layout, check);
    std::atomic<std::size_t> total{0};
    cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
      total.fetch_add(bilinear.rows(rows.start, rows.end, planes), std::memory_order_relaxed);
    });
    marked = total.load();
  } else if (method == DemosaicMethod::kMatched) {
    // Each band's kernel samples at each pixel parity, one pixel at a time (slower than the
    // bilinear pass). Pixels without a finite band at the skip level are left alone: they have
    // no reading whatever their footprint.
    std::array<std::array<Offsets, 2>, 2> footprint;  // row parity, column parity
    for (int py = 0; py < 2; ++py)
      for (int px = 0; px < 2; ++px)
        for (int b = 0; b < bands; ++b)
          footprint[py][px].of_band[static_cast<std::size_t>(b)] =
              matched_footprint(layout, b, px, py);
    for (int y = 0; y < height; ++y)
      for (int x = 0; x < width; ++x) {
        bool lit = false;
        for (const cv::Mat& p : planes) {
          const float v = p.at<float>(y, x);
          lit = lit || (std::isfinite(v) && v >= check.skip_below_dn);
        }
        if (lit && !test(footprint[y & 1][x & 1], x, y, true)) {
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

std::size_t demosaic_marking_mixed(const cv::Mat& mosaic, const MosaicLayout& layout,
                                   DemosaicMethod method, const FootprintCheck& check,
                                   std::vector<cv::Mat>& planes, float no_signal_dn) {
  if (layout.kind != MosaicLayout::Kind::kBayer ||
      resolve_demosaic_method(method, layout) != DemosaicMethod::kBilinear) {
    demosaic(mosaic, layout, method, planes, no_signal_dn);
    return mark_mixed_pixels(mosaic, layout, method, check, planes);
  }
  check_inputs(mosaic, layout, method, check);
  const BilinearCheck bilinear(mosaic, layout, check);
  std::atomic<std::size_t> total{0};
  demosaic(mosaic, layout, method, planes, no_signal_dn, [&](int y0, int y1) {
    total.fetch_add(bilinear.rows(y0, y1, planes), std::memory_order_relaxed);
  });
  return total.load();
}

}  // namespace pyrocam
