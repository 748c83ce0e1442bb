#include "pyrocam/runtime/snapshot_brightness.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core/utility.hpp>
#include <string>

#include "detail/log_positive.h"
#include "detail/portable_math.h"
#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {
namespace {

// Gauss-Newton on log rates nearly linear in 1/T: a step of d degrees leaves about d^2 / T
// (kelvin) to go, so after a step under 0.5 degC what is left is under 3e-4 degC (a fit reading
// 15 degC off takes two steps); the steps allowed cover a start hundreds of degrees off.
constexpr int kMaxSteps = 8;
constexpr double kConverged_c = 0.5;

// table[i] at `at` (0 <= at <= last), interpolated, in a form that vectorises (a gather).
inline float lookup(const float* table, int last, float at, float& slope) {
  const int i = std::min(static_cast<int>(at), last - 1);
  slope = table[i + 1] - table[i];
  return table[i] + (at - static_cast<float>(i)) * slope;
}

// One row of one band: each cell's log signal (NaN unless the band reads), and the scale the
// fit's reading implies with count 1 where it is in the range (else 0, 0). Products of selects,
// not branches, so that the loop vectorises. Single precision: a log rate of up to ~30 nats to
// 1e-6 moves a reading by about 1e-3 degC.
PYROCAM_VECTOR_CLONES
void scale_row(const float* __restrict signal, const float* __restrict reading, int n,
               const float* __restrict table, int last, float min_c, float max_c, float dim_dn,
               float* __restrict ln, float* __restrict scale, float* __restrict count) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (int x = 0; x < n; ++x) {
    const float v = signal[x], tr = reading[x];
    const float reads = (v >= dim_dn ? 1.f : 0.f) * (v < kInf ? 1.f : 0.f);
    const float scaled = reads * (tr >= min_c ? 1.f : 0.f) * (tr <= max_c ? 1.f : 0.f);  // NaN
    const float l = log_positive(reads > 0.f ? v : 1.f);
    float slope;
    const float rate = lookup(table, last, scaled > 0.f ? tr - min_c : 0.f, slope);
    ln[x] = reads > 0.f ? l : std::numeric_limits<float>::quiet_NaN();
    scale[x] = (l - rate) * scaled;
    count[x] = scaled;
  }
}

// One row of one band: the log rate each cell's signal and scale ask for, and its weight (the
// inverse variance of ln s; 0 where the band or its scale is missing).
PYROCAM_VECTOR_CLONES
void target_row(const float* __restrict signal, const float* __restrict ln,
                const float* __restrict mean_scale, int n, float shot_gain, float floor_dn2,
                float* __restrict target, float* __restrict weight) {
  for (int x = 0; x < n; ++x) {
    const float v = signal[x];
    const bool both = (ln[x] == ln[x]) & (mean_scale[x] == mean_scale[x]);
    target[x] = both ? ln[x] - mean_scale[x] : 0.f;
    weight[x] = both ? v * v / (shot_gain * v + floor_dn2) : 0.f;
  }
}

// One band's share of a Gauss-Newton step for a row: sums of w r m' and w m'^2 at the cells'
// temperatures t_c (degC from the table's start, within it); `on` is 1 for the cells still
// stepping, 0 for the rest (they add zeros).
PYROCAM_VECTOR_CLONES
void step_sums(const float* __restrict table, int last, const float* __restrict target,
               const float* __restrict weight, const float* __restrict t_c,
               const float* __restrict on, int n, float* __restrict num, float* __restrict den) {
  for (int x = 0; x < n; ++x) {
    float slope;
    const float r = target[x] - lookup(table, last, t_c[x], slope);
    const float w = weight[x] * on[x];
    num[x] += w * r * slope;
    den[x] += w * slope * slope;
  }
}

// out[x] = the sum of scale[x .. x + span) over that of count (NaN where it is 0): the window's
// mean scale, from column sums padded with span / 2 zeros at either end. Sums in a fixed order,
// independent from cell to cell (they vectorise).
PYROCAM_VECTOR_CLONES
void window_means(const double* __restrict scale, const double* __restrict count, int n, int span,
                  float* __restrict out) {
  for (int x = 0; x < n; ++x) {
    double e = 0, c = 0;
    for (int k = 0; k < span; ++k) e += scale[x + k], c += count[x + k];
    out[x] = c > 0 ? static_cast<float>(e / c) : std::numeric_limits<float>::quiet_NaN();
  }
}

}  // namespace

SnapshotBrightness::SnapshotBrightness(const ThermalModel& model, int window_radius)
    : radius_(window_radius), profile_(model.profile()) {
  const CameraProfile& profile = profile_;
  if (profile.mosaic.kind != MosaicLayout::Kind::kSnapshot)
    throw InputError("snapshot brightness readings need a snapshot mosaic; the model's camera (" +
                     profile.name + ") has a Bayer mosaic");
  if (window_radius < 1 || window_radius > kMaxWindowRadius)
    throw InputError("brightness window radius " + std::to_string(window_radius) +
                     " cells: must be 1 to " + std::to_string(kMaxWindowRadius));
  dim_dn_ = profile.thresholds.inference_dim_dn;
  const Locus locus = make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, 1);
  min_c_ = locus.temperature_c[0];
  max_c_ = locus.temperature_c[locus.size() - 1];
  for (Eigen::Index b = 0; b < locus.rates.cols(); ++b) {
    std::vector<double> table;
    for (Eigen::Index i = 0; i < locus.size(); ++i) {
      const double rate = locus.rates(i, b);
      if (!(rate > 0) || (!table.empty() && portable::log(rate) <= table.back()))
        throw InputError("brightness readings: band " + std::to_string(b) +
                         " of the model's camera has no rising modelled signal at " +
                         std::to_string(locus.temperature_c[i]) + " degC");
      table.push_back(portable::log(rate));
    }
    log_rate_.emplace_back(table.begin(), table.end());
  }
  shot_gain_.resize(log_rate_.size());
  floor_dn2_.resize(log_rate_.size());
  gain_ = 0;  // made at unity gain below
  set_analogue_gain(1);
}

void SnapshotBrightness::set_analogue_gain(double factor) {
  if (!(factor > 0) || !std::isfinite(factor))
    throw InputError("brightness readings: analogue gain factor " + std::to_string(factor) +
                     " must be a positive number");
  if (factor == gain_) return;
  gain_ = factor;
  for (std::size_t b = 0; b < log_rate_.size(); ++b) {
    const SignalNoise noise = signal_noise(profile_, static_cast<int>(b), factor);
    shot_gain_[b] = noise.shot_gain;
    floor_dn2_[b] = noise.floor_dn2;
  }
}

void SnapshotBrightness::check(const std::vector<cv::Mat>& planes, const cv::Mat& readings,
                               int type) const {
  if (planes.size() != log_rate_.size())
    throw InputError("brightness readings: " + std::to_string(planes.size()) +
                     " band planes for a model of " + std::to_string(log_rate_.size()) + " bands");
  if (readings.type() != type)
    throw InputError(std::string("brightness readings: the readings must be ") +
                     (type == CV_32F ? "float32 degC" : "16-bit 0.1 K codes"));
  for (const cv::Mat& p : planes)
    if (p.type() != CV_32F || p.size() != readings.size())
      throw InputError(
          "brightness readings: every band plane must be float32 of the readings' "
          "size (" +
          std::to_string(readings.cols) + "x" + std::to_string(readings.rows) + ")");
}

void SnapshotBrightness::apply(const std::vector<cv::Mat>& planes, cv::Mat& temperature_c) {
  check(planes, temperature_c, CV_32F);
  // Only cells with a reading give scales or take readings: the rest of the frame (a melt pool's
  // cold surroundings) is not visited.
  int x0 = temperature_c.cols, x1 = -1, y0 = temperature_c.rows, y1 = -1;
  for (int y = 0; y < temperature_c.rows; ++y) {
    const auto* t = temperature_c.ptr<float>(y);
    for (int x = 0; x < temperature_c.cols; ++x)
      if (t[x] == t[x]) x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = y;
  }
  if (x1 < 0) return;
  const cv::Rect read(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  std::vector<cv::Mat> within;
  for (const cv::Mat& p : planes) within.push_back(p(read));
  cv::Mat readings = temperature_c(read);
  apply_within(within, readings);
}

void SnapshotBrightness::apply_within(const std::vector<cv::Mat>& planes, cv::Mat& temperature_c) {
  const int h = temperature_c.rows, w = temperature_c.cols;
  const int bands = static_cast<int>(planes.size());
  log_signal_.resize(static_cast<std::size_t>(bands));
  mean_scale_.resize(static_cast<std::size_t>(bands));
  for (int b = 0; b < bands; ++b) {
    log_signal_[static_cast<std::size_t>(b)].create(h, w, CV_32F);
    mean_scale_[static_cast<std::size_t>(b)].create(h, w, CV_32F);
  }
  // A stripe of bands, then of rows, per thread, each with scratch kept from frame to frame
  // (allocated anew, a frame's scratch cost more in page faults than its arithmetic).
  const int stripes = std::max(1, std::min(cv::getNumThreads(), bands));
  scratch_.resize(static_cast<std::size_t>(stripes));
  cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k)
      for (int b = bands * k / stripes; b < bands * (k + 1) / stripes; ++b)
        scale_band(planes[static_cast<std::size_t>(b)], b, temperature_c,
                   scratch_[static_cast<std::size_t>(k)]);
  });
  cv::parallel_for_(cv::Range(0, stripes), [&](const cv::Range& range) {
    for (int k = range.start; k < range.end; ++k)
      for (int y = h * k / stripes; y < h * (k + 1) / stripes; ++y)
        read_row(planes, y, temperature_c, scratch_[static_cast<std::size_t>(k)]);
  });
}

void SnapshotBrightness::scale_band(const cv::Mat& plane, int b, const cv::Mat& readings,
                                    Scratch& scratch) {
  const int h = readings.rows, w = readings.cols, r = radius_, span = 2 * r + 1;
  const auto n = static_cast<std::size_t>(w);
  cv::Mat& ln = log_signal_[static_cast<std::size_t>(b)];
  cv::Mat& mean = mean_scale_[static_cast<std::size_t>(b)];
  const std::vector<float>& table = log_rate_[static_cast<std::size_t>(b)];
  // The window's sums stream down the rows: per column, the sums over its last `span` rows (a
  // ring of them kept), then across each row's window. Whole numbers for the counts (exact);
  // where a column's count returns to 0 its scale sum is set to 0, so rounding cannot build up.
  // The columns' sums are padded with r zeros at either end.
  std::vector<float>&ring_scale = scratch.ring_scale, &ring_count = scratch.ring_count;
  std::vector<double>&column_scale = scratch.column_scale, &column_count = scratch.column_count;
  ring_scale.resize(n * static_cast<std::size_t>(span));
  ring_count.resize(ring_scale.size());
  column_scale.assign(n + 2 * static_cast<std::size_t>(r), 0.0);
  column_count.assign(column_scale.size(), 0.0);
  double *scale_sum = column_scale.data() + r, *count_sum = column_count.data() + r;
  for (int y = 0; y < h + r; ++y) {
    float* slot_scale = &ring_scale[static_cast<std::size_t>(y % span) * n];
    float* slot_count = &ring_count[static_cast<std::size_t>(y % span) * n];
    if (y >= span)  // row y - span leaves the window (its slot is row y's)
      for (int x = 0; x < w; ++x) {
        count_sum[x] -= slot_count[x];
        scale_sum[x] = count_sum[x] > 0 ? scale_sum[x] - slot_scale[x] : 0.0;
      }
    if (y < h) {
      scale_row(plane.ptr<float>(y), readings.ptr<float>(y), w, table.data(),
                static_cast<int>(table.size()) - 1, static_cast<float>(min_c_),
                static_cast<float>(max_c_), static_cast<float>(dim_dn_), ln.ptr<float>(y),
                slot_scale, slot_count);
      for (int x = 0; x < w; ++x) scale_sum[x] += slot_scale[x], count_sum[x] += slot_count[x];
    }
    const int out = y - r;  // its window's rows are all in now
    if (out >= 0)
      window_means(column_scale.data(), column_count.data(), w, span, mean.ptr<float>(out));
  }
}

void SnapshotBrightness::read_row(const std::vector<cv::Mat>& planes, int y, cv::Mat& temperature_c,
                                  Scratch& scratch) const {
  const int w = temperature_c.cols, bands = static_cast<int>(planes.size());
  const auto n = static_cast<std::size_t>(w);
  std::vector<float>&at = scratch.at, &on = scratch.on, &num = scratch.num, &den = scratch.den;
  std::vector<float>&target = scratch.target, &weight = scratch.weight;
  at.resize(n), on.resize(n), num.resize(n), den.resize(n);
  target.resize(n * static_cast<std::size_t>(bands)), weight.resize(target.size());
  auto* t = temperature_c.ptr<float>(y);
  const auto last = static_cast<float>(log_rate_[0].size() - 1);
  bool any = false;
  for (int x = 0; x < w; ++x) {
    const bool in = t[x] >= min_c_ && t[x] <= max_c_;  // no reading, or out of range: kept
    at[x] = in ? static_cast<float>(t[x] - min_c_) : 0.f;
    on[x] = in ? 1.f : 0.f;
    any |= in;
  }
  for (int b = 0; b < bands; ++b)
    target_row(planes[static_cast<std::size_t>(b)].ptr<float>(y),
               log_signal_[static_cast<std::size_t>(b)].ptr<float>(y),
               mean_scale_[static_cast<std::size_t>(b)].ptr<float>(y), w,
               static_cast<float>(shot_gain_[b]), static_cast<float>(floor_dn2_[b]),
               &target[static_cast<std::size_t>(b) * n], &weight[static_cast<std::size_t>(b) * n]);
  // Gauss-Newton from the fit's reading, every cell of the row a step at a time.
  for (int step = 0; step < kMaxSteps && any; ++step) {
    std::fill(num.begin(), num.end(), 0.f);
    std::fill(den.begin(), den.end(), 0.f);
    for (int b = 0; b < bands; ++b) {
      const std::vector<float>& table = log_rate_[static_cast<std::size_t>(b)];
      step_sums(table.data(), static_cast<int>(table.size()) - 1,
                &target[static_cast<std::size_t>(b) * n], &weight[static_cast<std::size_t>(b) * n],
                at.data(), on.data(), w, num.data(), den.data());
    }
    any = false;
    for (int x = 0; x < w; ++x) {
      if (on[x] == 0.f) continue;
      const float move = num[x] / den[x];
      at[x] += move;
      if (!(den[x] > 0.f) || !(at[x] >= 0.f && at[x] <= last)) {
        on[x] = 0.f;  // no band to read, or out of the range: the fit's reading stays
        at[x] = 0.f;
      } else if (std::abs(move) < kConverged_c) {
        t[x] = static_cast<float>(at[x] + min_c_);
        on[x] = 0.f;
      } else {
        any = true;
      }
    }
  }
}

void SnapshotBrightness::apply_codes(const std::vector<cv::Mat>& planes, cv::Mat& codes) {
  check(planes, codes, CV_16U);
  cv::Mat t = decode_decikelvin(codes);
  const cv::Mat ratio = t.clone();
  apply(planes, t);
  for (int y = 0; y < codes.rows; ++y) {
    const auto *before = ratio.ptr<float>(y), *after = t.ptr<float>(y);
    auto* c = codes.ptr<std::uint16_t>(y);
    for (int x = 0; x < codes.cols; ++x)
      if (after[x] != before[x]) c[x] = temperature_code(after[x]);  // unchanged: the same code
  }
}

}  // namespace pyrocam
