#include "pyrocam/runtime/scaled_brightness.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>

#include "detail/log_positive.h"
#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {
namespace {

// Inverse table points: the log rate spans up to ~25 nats over the model's range, so a step is
// about 1.5e-3 nats, a fraction of a degree, with linear interpolation far below 0.01 degC.
constexpr int kInverseSamples = 16384;

// table[i] at `at` (0 <= at <= last), interpolated, in a form that vectorises (a gather).
inline float lookup(const float* table, int last, float at) {
  const int i = std::min(static_cast<int>(at), last - 1);
  const float f = at - static_cast<float>(i);
  return table[i] + f * (table[i + 1] - table[i]);
}

// The readings a frame arrives in: degC (NaN: no reading) or 0.1 K codes (0: no reading).
struct CelsiusReadings {
  using Value = float;
  static float celsius(float v) { return v; }
  static bool read(float v) { return v == v; }
};
struct CodeReadings {
  using Value = std::uint16_t;
  static float celsius(std::uint16_t code) {  // a sum, not a branch: the loops vectorise
    return static_cast<float>(code) * 0.1f - 273.15f +
           (code != kNoReadingCode ? 0.f : std::numeric_limits<float>::quiet_NaN());
  }
  static bool read(std::uint16_t code) { return code != kNoReadingCode; }
};

// One row of one Bayer phase, cells [first, last) (stride 2 in the mosaic and the readings):
// each cell's log sample (NaN unless usable and read by the ratio), and its scale e with weight
// 1 where the ratio's reading is in the model's range (else 0, 0).
template <class Readings>
PYROCAM_VECTOR_CLONES void scale_row(const float* __restrict signal,
                                     const typename Readings::Value* __restrict ratio, int first,
                                     int last, const float* __restrict log_rate, int rate_last,
                                     float dim_dn, float min_c, float max_c, float* __restrict ln,
                                     float* __restrict e, float* __restrict weight) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (int j = first; j < last; ++j) {
    const float v = signal[2 * j], tr = Readings::celsius(ratio[2 * j]);
    // The weight as a product of selects and the scale as a product with it keep the loop free
    // of branches, so that it vectorises (GCC 12 makes a branch of a bool used twice).
    const float weight_j = (v >= dim_dn ? 1.f : 0.f) * (v < kInf ? 1.f : 0.f) *
                           (tr >= min_c ? 1.f : 0.f) * (tr <= max_c ? 1.f : 0.f);  // NaN fails
    const bool usable = (v >= dim_dn) & (v < kInf);
    const float l = log_positive(usable ? v : 1.f);
    const float lr = lookup(log_rate, rate_last, weight_j > 0.f ? tr - min_c : 0.f);
    ln[j] = usable & (tr == tr) ? l : std::numeric_limits<float>::quiet_NaN();
    e[j] = (l - lr) * weight_j;
    weight[j] = weight_j;
  }
}

// Whether a row of readings has any.
template <class Readings>
PYROCAM_VECTOR_CLONES bool any_read(const typename Readings::Value* __restrict row, int n) {
  int any = 0;
  for (int x = 0; x < n; ++x) any |= Readings::read(row[x]) ? 1 : 0;
  return any != 0;
}

// The window's column sums of scales and weights: += a row entering the window.
PYROCAM_VECTOR_CLONES
void add_columns(const float* __restrict e, const float* __restrict weight, int first, int last,
                 float* __restrict sum_e, float* __restrict sum_w) {
  for (int j = first; j < last; ++j) sum_e[j] += e[j];
  for (int j = first; j < last; ++j) sum_w[j] += weight[j];
}

// -= a row leaving it. The weights are whole numbers, exact in float; where they come back to
// 0 the scales' sum is set to 0 too, so that their rounding cannot build up down the frame.
PYROCAM_VECTOR_CLONES
void remove_columns(const float* __restrict e, const float* __restrict weight, int first, int last,
                    float* __restrict sum_e, float* __restrict sum_w) {
  for (int j = first; j < last; ++j) {
    const float w = sum_w[j] - weight[j];
    sum_w[j] = w;
    sum_e[j] = w > 0.f ? sum_e[j] - e[j] : 0.f;
  }
}

// out[j] = the sum of columns j - r .. j + r (zero outside [0, w)), for j in [first, last).
PYROCAM_VECTOR_CLONES
void sum_across(const float* __restrict columns, int w, int r, int first, int last,
                float* __restrict out) {
  for (int j = first; j < last; ++j) out[j] = 0;
  for (int k = -r; k <= r; ++k) {
    const int lo = std::max(first, -k), hi = std::min(last, w - k);
    for (int j = lo; j < hi; ++j) out[j] += columns[j + k];
  }
}

// One row of one phase's brightness readings from its log samples and the scales' window sums,
// cells [first, last): degC (NaN where there is none), or codes to the nearest 0.1 K (0 where
// there is none; the model's range, 500..3500 degC, is well inside a code's).
struct Inverse {
  const float* table;
  int last;
  float log_lo, inv_step;
};
inline float brightness_at(float ln, float e_sum, float weight_sum, const Inverse& inv, float& ok) {
  const float at = (ln - e_sum / weight_sum - inv.log_lo) * inv.inv_step;
  // NaN (no sum, no log) fails both; selects of constants, so that the loop vectorises.
  ok = (at >= 0.f ? 1.f : 0.f) * (at <= static_cast<float>(inv.last) ? 1.f : 0.f);
  return lookup(inv.table, inv.last, ok > 0.f ? at : 0.f);
}
PYROCAM_VECTOR_CLONES
void read_row(const float* __restrict ln, const float* __restrict e_sum,
              const float* __restrict weight_sum, int first, int last, Inverse inv,
              float* __restrict out) {
  for (int j = first; j < last; ++j) {
    float ok;
    const float b = brightness_at(ln[j], e_sum[j], weight_sum[j], inv, ok);
    out[j] = ok > 0.f ? b : std::numeric_limits<float>::quiet_NaN();
  }
}
PYROCAM_VECTOR_CLONES
void read_row(const float* __restrict ln, const float* __restrict e_sum,
              const float* __restrict weight_sum, int first, int last, Inverse inv,
              std::uint16_t* __restrict out) {
  for (int j = first; j < last; ++j) {
    float ok;
    const float code =
        (brightness_at(ln[j], e_sum[j], weight_sum[j], inv, ok) + 273.15f) * 10.f + 0.5f;
    out[j] = static_cast<std::uint16_t>(ok > 0.f ? static_cast<int>(code) : 0);
  }
}

// A phase row's brightness readings (cells [first, last)) written over its ratio readings
// (stride 2) where there are any. `state` (per cell): 1 where the pixel now holds a brightness
// reading, 2 where it keeps a ratio reading, 0 without any. Returns how many keep theirs.
PYROCAM_VECTOR_CLONES
int merge_row(const float* __restrict brightness, int first, int last, float* __restrict t,
              std::uint8_t* __restrict state) {
  int kept = 0;
  for (int j = first; j < last; ++j) {
    const float b = brightness[j], ratio = t[2 * j];
    const int has_b = b == b ? 1 : 0, has_ratio = ratio == ratio ? 1 : 0;
    t[2 * j] = b == b ? b : ratio;
    state[j] = static_cast<std::uint8_t>(has_b + 2 * (1 - has_b) * has_ratio);
    kept += (1 - has_b) * has_ratio;
  }
  return kept;
}
PYROCAM_VECTOR_CLONES
int merge_row(const std::uint16_t* __restrict brightness, int first, int last,
              std::uint16_t* __restrict t, std::uint8_t* __restrict state) {
  int kept = 0;
  for (int j = first; j < last; ++j) {
    const std::uint16_t b = brightness[j], ratio = t[2 * j];
    const int has_b = b != 0 ? 1 : 0, has_ratio = ratio != 0 ? 1 : 0;
    t[2 * j] = b != 0 ? b : ratio;
    state[j] = static_cast<std::uint8_t>(has_b + 2 * (1 - has_b) * has_ratio);
    kept += (1 - has_b) * has_ratio;
  }
  return kept;
}

}  // namespace

ScaledBrightness::ScaledBrightness(const ThermalModel& model, int window_radius)
    : ScaledBrightness(model, window_radius, model.profile().mosaic) {}

ScaledBrightness::ScaledBrightness(const ThermalModel& model, int window_radius,
                                   const MosaicLayout& layout)
    : radius_(window_radius) {
  if (model.profile().mosaic.kind != MosaicLayout::Kind::kBayer)
    throw InputError("brightness readings need a Bayer mosaic; the model's camera (" +
                     model.profile().name + ") has a snapshot mosaic");
  if (layout.kind != MosaicLayout::Kind::kBayer)
    throw InputError("brightness readings need a Bayer mosaic, not a snapshot one");
  if (window_radius < 1 || window_radius > kMaxWindowRadius)
    throw InputError("brightness window radius " + std::to_string(window_radius) +
                     " Bayer cells: must be 1 to " + std::to_string(kMaxWindowRadius));
  for (int phase = 0; phase < 4; ++phase)
    phase_band_[phase] = layout.band_at(phase & 1, phase >> 1);
  dim_dn_ = static_cast<float>(model.profile().thresholds.inference_dim_dn);
  const Locus locus = make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, 1);
  min_c_ = static_cast<float>(locus.temperature_c[0]);
  max_c_ = static_cast<float>(locus.temperature_c[locus.size() - 1]);
  for (Eigen::Index b = 0; b < locus.rates.cols(); ++b) {
    BandTables t;
    std::vector<double> forward;
    for (Eigen::Index i = 0; i < locus.size(); ++i) {
      const double rate = locus.rates(i, b);
      if (!(rate > 0) || (!forward.empty() && std::log(rate) <= forward.back()))
        throw InputError("brightness readings: band " + std::to_string(b) +
                         " of the model's camera has no rising modelled signal at " +
                         std::to_string(locus.temperature_c[i]) + " degC");
      forward.push_back(std::log(rate));
    }
    t.log_rate.assign(forward.begin(), forward.end());
    const double lo = forward.front(), hi = forward.back();
    const double step = (hi - lo) / (kInverseSamples - 1);
    t.log_lo = static_cast<float>(lo);
    t.log_hi = static_cast<float>(hi);
    t.inv_log_step = static_cast<float>(1 / step);
    t.temperature.resize(kInverseSamples);
    std::size_t j = 0;
    for (int k = 0; k < kInverseSamples; ++k) {
      const double v = std::min(hi, lo + k * step);
      while (j + 2 < forward.size() && forward[j + 1] < v) ++j;
      const double f = (v - forward[j]) / (forward[j + 1] - forward[j]);
      t.temperature[static_cast<std::size_t>(k)] =
          static_cast<float>(locus.temperature_c[static_cast<Eigen::Index>(j)] + f);
    }
    bands_.push_back(std::move(t));
  }
}

double ScaledBrightness::log_rate(int band, double t_c) const {
  if (!(t_c >= min_c_ && t_c <= max_c_)) return NAN;
  const std::vector<float>& table = bands_.at(static_cast<std::size_t>(band)).log_rate;
  return lookup(table.data(), static_cast<int>(table.size()) - 1, static_cast<float>(t_c - min_c_));
}

double ScaledBrightness::temperature_of_log_rate(int band, double log_rate) const {
  const BandTables& t = bands_.at(static_cast<std::size_t>(band));
  if (!(log_rate >= t.log_lo && log_rate <= t.log_hi)) return NAN;
  return lookup(t.temperature.data(), kInverseSamples - 1,
                static_cast<float>((log_rate - t.log_lo) * t.inv_log_step));
}

void ScaledBrightness::check(const cv::Mat& signal, const cv::Mat& temperature_c, int type) const {
  if (signal.type() != CV_32F || temperature_c.type() != type)
    throw InputError(type == CV_32F
                         ? "brightness readings: the mosaic and the readings must be float32"
                         : "brightness readings: the mosaic must be float32, the codes 16-bit");
  if (signal.size() != temperature_c.size() || signal.rows % 2 != 0 || signal.cols % 2 != 0)
    throw InputError("brightness readings: a " + std::to_string(signal.cols) + "x" +
                     std::to_string(signal.rows) + " mosaic and " +
                     std::to_string(temperature_c.cols) + "x" + std::to_string(temperature_c.rows) +
                     " readings; they must have one size, whole Bayer cells (full-resolution "
                     "demosaicking)");
}

template <class Readings>
void ScaledBrightness::apply_to(const cv::Mat& signal, cv::Mat& readings) {
  using Value = typename Readings::Value;
  const int h = readings.rows, w = readings.cols, h2 = h / 2, w2 = w / 2, r = radius_;
  const int slots = 2 * r + 2;  // the window's rows and the one leaving it
  const auto row_floats = static_cast<std::size_t>(w2);
  // Per Bayer phase: a ring of `slots` rows of log samples, raw scales and raw weights; the
  // window's column sums; a row each of window sums. Per cell, what it reads (state_), and per
  // row whether any cell keeps its ratio reading (kept_).
  for (int phase = 0; phase < 4; ++phase) {
    scratch_[phase].assign((3 * static_cast<std::size_t>(slots) + 4) * row_floats, 0.f);
    state_[phase].create(h2, w2, CV_8U);
    kept_[phase].assign(static_cast<std::size_t>(h2), 0);
  }
  // Each Bayer phase on its own grid of cells, a row at a time while the rows its windows need
  // are in cache: row i reads once row i + r is made, its window's sums the column sums of rows
  // i - r .. i + r across cells j - r .. j + r. Each phase reads and writes only its own pixels
  // (a row's ratio readings are read before they are written over), so the phases run side by
  // side; the two of a row parity in turn, so that each mosaic row comes from memory once.
  cv::parallel_for_(cv::Range(0, 2), [&](const cv::Range& range) {
    std::vector<Value> out(row_floats);
    for (int py = range.start; py < range.end; ++py) {
      struct Phase {
        const BandTables* table;
        float *ring_ln, *ring_e, *ring_w, *col_e, *col_w, *sum_e, *sum_w;
        std::vector<std::array<int, 2>> span;  // per ring slot: cells [first, last) that read
      } phases[2];
      for (int px = 0; px < 2; ++px) {
        const int phase = px + 2 * py;
        Phase& p = phases[px];
        p.table = &bands_[static_cast<std::size_t>(phase_band_[phase])];
        p.ring_ln = scratch_[phase].data();
        p.ring_e = p.ring_ln + slots * row_floats;
        p.ring_w = p.ring_e + slots * row_floats;
        p.col_e = p.ring_w + slots * row_floats;
        p.col_w = p.col_e + row_floats;
        p.sum_e = p.col_w + row_floats;
        p.sum_w = p.sum_e + row_floats;
        p.span.assign(static_cast<std::size_t>(slots), {0, 0});
      }
      for (int made = 0; made < h2 + r; ++made) {
        const bool reads = made < h2 && any_read<Readings>(readings.ptr<Value>(2 * made + py), w);
        for (int px = 0; px < 2; ++px) {
          Phase& p = phases[px];
          const int gone = made - 2 * r - 1;  // the row leaving the window of row made - r
          if (gone >= 0) {
            const std::size_t slot = static_cast<std::size_t>(gone % slots);
            remove_columns(p.ring_e + slot * row_floats, p.ring_w + slot * row_floats,
                           p.span[slot][0], p.span[slot][1], p.col_e, p.col_w);
          }
          if (made >= h2) continue;
          const std::size_t slot = static_cast<std::size_t>(made % slots);
          const Value* ratio = readings.ptr<Value>(2 * made + py) + px;
          int first = 0, last = reads ? w2 : 0;
          while (first < last && !Readings::read(ratio[2 * first])) ++first;
          while (last > first && !Readings::read(ratio[2 * (last - 1)])) --last;
          p.span[slot] = {first, last};
          if (first == last) continue;
          float* e = p.ring_e + slot * row_floats;
          float* weight = p.ring_w + slot * row_floats;
          scale_row<Readings>(signal.ptr<float>(2 * made + py) + px, ratio, first, last,
                              p.table->log_rate.data(),
                              static_cast<int>(p.table->log_rate.size()) - 1, dim_dn_, min_c_,
                              max_c_, p.ring_ln + slot * row_floats, e, weight);
          add_columns(e, weight, first, last, p.col_e, p.col_w);
        }
        const int i = made - r;
        if (i < 0) continue;
        for (int px = 0; px < 2; ++px) {
          Phase& p = phases[px];
          const std::size_t slot = static_cast<std::size_t>(i % slots);
          const auto [first, last] = p.span[slot];
          std::uint8_t* state = state_[px + 2 * py].ptr<std::uint8_t>(i);
          std::fill(state, state + first, std::uint8_t{0});
          std::fill(state + last, state + w2, std::uint8_t{0});
          if (first == last) continue;
          sum_across(p.col_e, w2, r, first, last, p.sum_e);
          sum_across(p.col_w, w2, r, first, last, p.sum_w);
          const Inverse inverse{p.table->temperature.data(), kInverseSamples - 1, p.table->log_lo,
                                p.table->inv_log_step};
          read_row(p.ring_ln + slot * row_floats, p.sum_e, p.sum_w, first, last, inverse,
                   out.data());
          kept_[px + 2 * py][static_cast<std::size_t>(i)] =
              merge_row(out.data(), first, last, readings.ptr<Value>(2 * i + py) + px, state) > 0;
        }
      }
    }
  });
  // A pixel without its own brightness reading: its neighbours' mean, else its ratio reading.
  // The neighbours across a row are of the other phase of its row parity, those above and
  // below of the same column parity in the other row parity.
  const auto has_brightness = [&](int y, int x) {
    return y >= 0 && y < h && x >= 0 && x < w &&
           state_[(x & 1) + 2 * (y & 1)].at<std::uint8_t>(y / 2, x / 2) == 1;
  };
  for (int y = 0; y < h; ++y) {
    const int py = y & 1, i = y / 2;
    if (!kept_[2 * py][static_cast<std::size_t>(i)] &&
        !kept_[2 * py + 1][static_cast<std::size_t>(i)])
      continue;
    Value* t = readings.ptr<Value>(y);
    for (int x = 0; x < w; ++x) {
      if (state_[(x & 1) + 2 * py].at<std::uint8_t>(i, x / 2) != 2) continue;
      float sum = 0;
      int n = 0;
      for (const auto& [yy, xx] : {std::pair{y - 1, x}, {y + 1, x}, {y, x - 1}, {y, x + 1}})
        if (has_brightness(yy, xx)) {
          sum += Readings::celsius(readings.ptr<Value>(yy)[xx]);
          ++n;
        }
      if (n == 0) continue;
      const float mean = sum / static_cast<float>(n);
      if constexpr (std::is_same_v<Value, float>)
        t[x] = mean;
      else
        t[x] = temperature_code(mean);
    }
  }
}

void ScaledBrightness::apply(const cv::Mat& signal, cv::Mat& temperature_c) {
  check(signal, temperature_c, CV_32F);
  apply_to<CelsiusReadings>(signal, temperature_c);
}

void ScaledBrightness::apply_codes(const cv::Mat& signal, cv::Mat& codes) {
  check(signal, codes, CV_16U);
  apply_to<CodeReadings>(signal, codes);
}

}  // namespace pyrocam
