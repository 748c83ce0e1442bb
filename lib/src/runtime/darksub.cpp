#include "pyrocam/runtime/darksub.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

std::string size_text(const cv::Mat& m) {
  return std::to_string(m.cols) + "x" + std::to_string(m.rows);
}

constexpr float kInf = std::numeric_limits<float>::infinity();

// How many of n raw samples are at or above the saturation level, compared as integers (many
// more to a vector register than floats).
template <typename T>
int count_saturated(const T* __restrict r, int n, float saturation) {
  if (!(saturation <= static_cast<float>(std::numeric_limits<T>::max()))) return 0;
  const T at_least = static_cast<T>(std::max(0.0f, std::ceil(saturation)));
  T brightest = 0;  // most rows have none: a maximum is the cheapest way to tell
  for (int x = 0; x < n; ++x) brightest = std::max(brightest, r[x]);
  if (brightest < at_least) return 0;
  int saturated = 0;
  for (int x = 0; x < n; ++x) saturated += r[x] >= at_least;
  return saturated;
}

// One row; __restrict lets the compiler vectorise the select. Returns the saturated samples.
template <typename T>
int subtract_row(const T* __restrict r, const float* __restrict d, float* __restrict o, int n,
                 float saturation) {
  for (int x = 0; x < n; ++x) {
    const float v = static_cast<float>(r[x]);
    const float signal = v - d[x];  // unconditionally, or the loop does not vectorise
    o[x] = v >= saturation ? kInf : signal;
  }
  return count_saturated(r, n, saturation);
}

template <typename T>
int subtract_level_row(const T* __restrict r, float level, float* __restrict o, int n,
                       float saturation) {
  for (int x = 0; x < n; ++x) {
    const float v = static_cast<float>(r[x]);
    o[x] = v >= saturation ? kInf : v - level;
  }
  return count_saturated(r, n, saturation);
}

// The rows for each sample size, compiled for AVX2 too (the conversions to float take several
// SSE2 instructions a vector).
PYROCAM_VECTOR_CLONES
int subtract_row_8(const std::uint8_t* __restrict r, const float* __restrict d, float* __restrict o,
                   int n, float saturation) {
  return subtract_row(r, d, o, n, saturation);
}
PYROCAM_VECTOR_CLONES
int subtract_row_16(const std::uint16_t* __restrict r, const float* __restrict d,
                    float* __restrict o, int n, float saturation) {
  return subtract_row(r, d, o, n, saturation);
}
PYROCAM_VECTOR_CLONES
int subtract_level_row_8(const std::uint8_t* __restrict r, float level, float* __restrict o, int n,
                         float saturation) {
  return subtract_level_row(r, level, o, n, saturation);
}
PYROCAM_VECTOR_CLONES
int subtract_level_row_16(const std::uint16_t* __restrict r, float level, float* __restrict o,
                          int n, float saturation) {
  return subtract_level_row(r, level, o, n, saturation);
}

// Runs row(y) for every row, over two threads for large frames, and sums up the saturated
// samples that the rows return and their bounds (from `out`'s +INF, on the rows with any).
template <typename Row>
SaturatedSamples for_rows(const cv::Mat& m, const cv::Mat& out, Row row) {
  std::vector<int> per_row(static_cast<std::size_t>(m.rows));
  if (m.total() < 512u * 512u) {
    for (int y = 0; y < m.rows; ++y) per_row[static_cast<std::size_t>(y)] = row(y);
  } else {
    cv::parallel_for_(
        cv::Range(0, m.rows),
        [&](const cv::Range& r) {
          for (int y = r.start; y < r.end; ++y) per_row[static_cast<std::size_t>(y)] = row(y);
        },
        2.0);
  }
  SaturatedSamples s;
  int x0 = m.cols, x1 = -1, y0 = m.rows, y1 = -1;
  for (int y = 0; y < m.rows; ++y) {
    if (per_row[static_cast<std::size_t>(y)] == 0) continue;
    s.count += static_cast<std::size_t>(per_row[static_cast<std::size_t>(y)]);
    y0 = std::min(y0, y);
    y1 = y;
    const float* o = out.ptr<float>(y);
    int first = 0, last = m.cols - 1;
    while (o[first] != kInf) ++first;
    while (o[last] != kInf) --last;
    x0 = std::min(x0, first);
    x1 = std::max(x1, last);
    // The row's tiles with any: from the first to the last, a tile's search ending at its first.
    std::uint64_t& tiles = s.tiles[static_cast<std::size_t>(saturation_tile_of(y, m.rows))];
    for (int t = saturation_tile_of(first, m.cols); t <= saturation_tile_of(last, m.cols); ++t) {
      if (tiles >> t & 1u) continue;
      const cv::Rect r = saturation_tile_rect(0, t, m.cols, 1);
      const int from = std::max(r.x, first), to = std::min(r.x + r.width, last + 1);
      if (std::find(o + from, o + to, kInf) != o + to) tiles |= std::uint64_t{1} << t;
    }
  }
  if (s.count > 0) s.bounds = cv::Rect(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  return s;
}

void check_raw(const cv::Mat& raw) {
  if (raw.type() != CV_8U && raw.type() != CV_16U)
    throw InputError("dark subtraction: raw frame must be 8- or 16-bit single-channel");
}

}  // namespace

int full_scale_dn(int bit_depth) {
  if (bit_depth < 1 || bit_depth > 16)
    throw InputError("bit depth " + std::to_string(bit_depth) + " outside 1..16");
  return (1 << bit_depth) - 1;
}

double default_saturation_level(int bit_depth) {
  return std::round(220.0 / 255.0 * full_scale_dn(bit_depth));
}

SaturatedSamples subtract_dark(const cv::Mat& raw, const cv::Mat& dark, double saturation_level,
                               cv::Mat& out) {
  check_raw(raw);
  if (dark.type() != CV_32F) throw InputError("dark subtraction: dark frame must be CV_32F");
  if (dark.size() != raw.size())
    throw InputError("dark frame is " + size_text(dark) + " but the camera frame is " +
                     size_text(raw));
  out.create(raw.size(), CV_32F);
  // A level above what fits a float exactly still compares correctly against integer samples.
  const float saturation = static_cast<float>(saturation_level);
  const int n = raw.cols;
  if (raw.type() == CV_8U)
    return for_rows(raw, out, [&](int y) {
      return subtract_row_8(raw.ptr<std::uint8_t>(y), dark.ptr<float>(y), out.ptr<float>(y), n,
                            saturation);
    });
  return for_rows(raw, out, [&](int y) {
    return subtract_row_16(raw.ptr<std::uint16_t>(y), dark.ptr<float>(y), out.ptr<float>(y), n,
                           saturation);
  });
}

SaturatedSamples subtract_dark_level(const cv::Mat& raw, double level_dn, double saturation_level,
                                     cv::Mat& out) {
  check_raw(raw);
  out.create(raw.size(), CV_32F);
  const float saturation = static_cast<float>(saturation_level);
  const float level = static_cast<float>(level_dn);
  const int n = raw.cols;
  if (raw.type() == CV_8U)
    return for_rows(raw, out, [&](int y) {
      return subtract_level_row_8(raw.ptr<std::uint8_t>(y), level, out.ptr<float>(y), n,
                                  saturation);
    });
  return for_rows(raw, out, [&](int y) {
    return subtract_level_row_16(raw.ptr<std::uint16_t>(y), level, out.ptr<float>(y), n,
                                 saturation);
  });
}

SaturatedSamples find_saturated(const cv::Mat& signal) {
  if (signal.type() != CV_32F) throw InputError("saturated samples: the mosaic must be CV_32F");
  return for_rows(signal, signal, [&](int y) {
    const float* row = signal.ptr<float>(y);
    int n = 0;
    for (int x = 0; x < signal.cols; ++x) n += row[x] == kInf;
    return n;
  });
}

cv::Mat dark_from_image(const cv::Mat& image) {
  if (image.channels() != 1 || (image.depth() != CV_8U && image.depth() != CV_16U))
    throw InputError("dark frame must be an 8- or 16-bit single-channel image");
  cv::Mat dark;
  image.convertTo(dark, CV_32F);
  return dark;
}

void DarkAccumulator::reset() {
  sum_.release();
  count_ = 0;
}

void DarkAccumulator::add(const cv::Mat& raw) {
  if (raw.type() != CV_8U && raw.type() != CV_16U)
    throw InputError("dark capture: frames must be 8- or 16-bit single-channel");
  if (count_ == 0) {
    sum_ = cv::Mat::zeros(raw.size(), CV_64F);
  } else if (raw.size() != sum_.size()) {
    throw InputError("dark capture: frame is " + size_text(raw) + " but the first was " +
                     size_text(sum_));
  }
  cv::add(sum_, raw, sum_, cv::noArray(), CV_64F);
  ++count_;
}

cv::Mat DarkAccumulator::mean() const {
  if (count_ == 0) throw InputError("dark capture: no frame captured");
  cv::Mat dark;
  sum_.convertTo(dark, CV_32F, 1.0 / count_);
  return dark;
}

void add_bayer_cell_sums(const cv::Mat& signal, float lit_dn, float bright_dn, int first_cell_row,
                         int cell_row_step, const SignalNoise& noise, BayerCellSums& sums,
                         std::size_t max_cells) {
  if (signal.type() != CV_32F) throw InputError("Bayer cell sums: the mosaic must be CV_32F");
  if (cell_row_step < 1) throw InputError("Bayer cell sums: the row step must be at least 1");
  if (first_cell_row < 0 || first_cell_row >= cell_row_step)
    throw InputError("Bayer cell sums: the first row must be 0 to the row step less one");
  // Only cells inside a body: the cells left, right and below within 20 % of this one. A cell on
  // an edge has its columns (or rows) lit unequally, which on a small body outweighs the colours.
  const auto like = [](float neighbour, float sum) {
    return neighbour >= 0.8f * sum && neighbour <= 1.25f * sum;
  };
  // Cell sums of a row of cells, NaN or +INF where a sample does not read.
  const int cells = signal.cols / 2;
  std::vector<float> row(static_cast<std::size_t>(cells)), below(row.size());
  const auto cell_sums = [&](int y, std::vector<float>& out) {
    const float* top = signal.ptr<float>(y);
    const float* bottom = signal.ptr<float>(y + 1);
    for (int i = 0; i < cells; ++i)
      out[static_cast<std::size_t>(i)] =
          top[2 * i] + top[2 * i + 1] + bottom[2 * i] + bottom[2 * i + 1];
  };
  // The green pairs to judge, with their means and differences, and the scatter of samples
  // behind one filter: each place of a cell against the same place 5 cells (10 pixels) on, one
  // filter on a Bayer mosaic and on a 5x5 one alike, inside the same body.
  struct Pair {
    int k;
    float mean, difference;
  };
  std::vector<Pair> pairs_seen;
  std::vector<double> same_filter_z2;           // squared differences over their modelled variance
  const auto variance_of = [&](double total) {  // of a difference of two samples summing to this
    return noise.shot_gain * total + 2 * noise.floor_dn2;
  };
  std::size_t cells_here = 0;
  for (int y = 2 * first_cell_row; y + 3 < signal.rows && cells_here < max_cells;
       y += 2 * cell_row_step) {
    cell_sums(y, row);
    cell_sums(y + 2, below);
    const float* top = signal.ptr<float>(y);
    const float* bottom = signal.ptr<float>(y + 1);
    for (std::size_t i = 1; i + 1 < row.size() && cells_here < max_cells; ++i) {
      const float sum = row[i];
      if (!(sum >= 4 * lit_dn) || !std::isfinite(sum)) continue;
      if (!like(row[i - 1], sum) || !like(row[i + 1], sum) || !like(below[i], sum)) continue;
      const std::size_t x = 2 * i;
      sums.at[0][0] += top[x], sums.at[0][1] += top[x + 1];
      sums.at[1][0] += bottom[x], sums.at[1][1] += bottom[x + 1];
      ++sums.cells;
      ++cells_here;
      const float pairs[2][2] = {{top[x], bottom[x + 1]}, {top[x + 1], bottom[x]}};
      for (int k = 0; k < 2; ++k) {
        const float mean = 0.5f * (pairs[k][0] + pairs[k][1]);
        if (mean >= bright_dn) pairs_seen.push_back({k, mean, pairs[k][0] - pairs[k][1]});
      }
      if (i + 5 < row.size() && like(row[i + 5], sum) && std::isfinite(row[i + 5]) &&
          variance_of(0) > 0) {
        const std::size_t x5 = x + 10;
        for (const auto& [a, b] : {std::pair{top[x], top[x5]},
                                   {top[x + 1], top[x5 + 1]},
                                   {bottom[x], bottom[x5]},
                                   {bottom[x + 1], bottom[x5 + 1]}})
          same_filter_z2.push_back(static_cast<double>(a - b) * (a - b) / variance_of(a + b));
      }
    }
  }
  // A camera at a gain the model does not know (darksub has no profile, and no gain without
  // exposure metadata) scatters more than modelled: the model's variance times the measured
  // one's ratio to it, never less (the median of a chi2 with one degree of freedom is 0.455;
  // a gradient along the 10 pixels only widens it, and then fewer cells are called apart).
  double scale = 1;
  if (same_filter_z2.size() >= 32) {
    auto middle = same_filter_z2.begin() + static_cast<long>(same_filter_z2.size() / 2);
    std::nth_element(same_filter_z2.begin(), middle, same_filter_z2.end());
    scale = std::max(1.0, *middle / 0.4549);
  }
  for (const Pair& pair : pairs_seen) {
    ++sums.bright[pair.k];
    if (std::abs(pair.difference) >
        0.12 * pair.mean + 2 * std::sqrt(scale * variance_of(2 * pair.mean)))
      ++sums.apart[pair.k];
  }
}

bool bayer_greens_elsewhere(const BayerCellSums& sums, const std::string& pattern) {
  // The pattern's greens: on the anti-diagonal for rggb and bggr, on the diagonal for grbg and
  // gbrg.
  bool anti;
  if (pattern == "rggb" || pattern == "bggr")
    anti = true;
  else if (pattern == "grbg" || pattern == "gbrg")
    anti = false;
  else
    return false;
  const double g1 = anti ? sums.at[0][1] : sums.at[0][0], g2 = anti ? sums.at[1][0] : sums.at[1][1];
  const double o1 = anti ? sums.at[0][0] : sums.at[0][1], o2 = anti ? sums.at[1][1] : sums.at[1][0];
  if (!(g1 > 0 && g2 > 0 && o1 > 0 && o2 > 0)) return false;
  const auto apart = [](double p, double q) { return std::max(p, q) / std::min(p, q); };
  return apart(g1, g2) > 1.10 && apart(o1, o2) < 1.03;
}

bool bayer_greens_disagree(const BayerCellSums& sums, const std::string& pattern) {
  int k;  // the diagonal of the pattern's greens
  if (pattern == "rggb" || pattern == "bggr")
    k = 1;
  else if (pattern == "grbg" || pattern == "gbrg")
    k = 0;
  else
    return false;
  return sums.bright[k] >= 64 && 4 * sums.apart[k] > sums.bright[k];
}

}  // namespace pyrocam
