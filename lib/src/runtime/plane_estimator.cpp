#include "pyrocam/runtime/plane_estimator.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <exception>
#include <functional>
#include <future>
#include <limits>
#include <string>
#include <utility>

#include "pyrocam/core/error.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/dim_edge.h"
#include "pyrocam/runtime/uncertainty.h"
#include "runtime/estimator_kinds.h"

namespace pyrocam {

PlaneEstimator::PlaneEstimator(std::shared_ptr<const ThermalModel> model, Method method,
                               double misfit_probability)
    : model_(std::move(model)),
      estimator_(make_estimator(model_, method)),
      misfit_(nullptr),
      method_(method) {
  set_misfit_probability(misfit_probability);
}

PlaneEstimator::PlaneEstimator(std::shared_ptr<const ThermalModel> model,
                               std::unique_ptr<TemperatureEstimator> estimator, Method method)
    : model_(std::move(model)),
      estimator_(std::move(estimator)),
      misfit_(nullptr),
      method_(method) {
  if (!estimator_ || !model_ || &estimator_->model() != model_.get())
    throw InputError("plane estimator: the estimator is not of this model");
}

void PlaneEstimator::set_partial_bands(TemperatureEstimator::PartialBands partial) {
  if (partial_set_ && partial == partial_) return;  // called per frame: build once
  partial_set_ = true;
  partial_ = partial;
  estimator_->set_partial_bands(partial);
  partial_fit_.reset();
  sloped_partial_fit_.reset();
  if (method_ == Method::kLikelihood || partial == TemperatureEstimator::PartialBands::kOff) return;
  auto fit = make_estimator(model_, Method::kLikelihood);
  fit->set_partial_bands(partial);
  fit->set_analogue_gain(analogue_gain_);
  // A fit that can read none of them would only cost a call per pixel without a reading.
  if (fit->can_read_partial()) partial_fit_ = std::move(fit);
  make_sloped_partial_fit();
}

void PlaneEstimator::make_sloped_partial_fit() {
  sloped_partial_fit_.reset();
  if (!partial_fit_ || !reads_sloped()) return;
  auto fit = std::make_unique<EmissivitySlopeEstimator>(partial_fit_, sloped_->alpha(), alpha_u_);
  fit->set_analogue_gain(analogue_gain_);
  sloped_partial_fit_ = std::move(fit);
}

void PlaneEstimator::set_misfit_probability(double probability) {
  if (misfit_)
    misfit_->set_probability(probability);
  else if (probability != 0) {  // the check's constructor refuses what set_probability refuses
    misfit_ = std::make_unique<MisfitCheck>(model_, probability);
    misfit_->set_analogue_gain(analogue_gain_);
  }
}

void PlaneEstimator::set_analogue_gain(double factor) {
  if (factor == analogue_gain_) return;   // called per frame
  estimator_->set_analogue_gain(factor);  // refuses before anything changes
  if (sloped_) sloped_->set_analogue_gain(factor);
  if (partial_fit_) partial_fit_->set_analogue_gain(factor);
  if (sloped_partial_fit_) sloped_partial_fit_->set_analogue_gain(factor);
  if (misfit_) misfit_->set_analogue_gain(factor);
  if (above_) std::const_pointer_cast<AboveRangeCheck>(above_)->set_analogue_gain(factor);
  if (audit_) audit_->set_analogue_gain(factor);
  analogue_gain_ = factor;
}

void PlaneEstimator::set_emissivity_slope(double alpha, double alpha_u) {
  const bool grey = alpha == 0 && alpha_u < 0;
  if (sloped_ ? alpha == sloped_->alpha() && alpha_u == alpha_u_ : grey) return;
  if (grey) {
    sloped_.reset();
  } else {  // built before anything changes: a refused value keeps the previous ones
    auto sloped = std::make_unique<EmissivitySlopeEstimator>(estimator_, alpha, alpha_u);
    sloped->set_analogue_gain(analogue_gain_);
    sloped_ = std::move(sloped);
  }
  alpha_u_ = alpha_u;
  make_sloped_partial_fit();
}

void PlaneEstimator::set_above_range_check(bool on) {
  if (!on) {
    if (above_build_.valid()) above_build_.wait();  // not left running on a model going away
    above_build_ = {};
    above_.reset();
    const std::lock_guard<std::mutex> lock(above_mutex_);
    above_found_.clear();
    above_pending_points_.clear();
    above_pending_signals_.clear();
    return;
  }
  if (above_range_check()) return;
  above_build_ = std::async(std::launch::async, [model = model_] {
    return std::shared_ptr<const AboveRangeCheck>(std::make_shared<AboveRangeCheck>(model));
  });
}

void PlaneEstimator::ready_above_range() const {
  above_checked_.store(0, std::memory_order_relaxed);
  if (above_ || !above_build_.valid() ||
      above_build_.wait_for(std::chrono::seconds(0)) != std::future_status::ready)
    return;
  adopt_above_range();
}

void PlaneEstimator::adopt_above_range() const {
  try {
    auto check = std::const_pointer_cast<AboveRangeCheck>(above_build_.get());
    check->set_analogue_gain(analogue_gain_);
    above_ = std::move(check);
  } catch (const std::exception&) {
    // A model whose locus the extended fit cannot take: no check (nothing found above).
  }
}

void PlaneEstimator::finish_above_range() const {
  if (above_pending_points_.empty()) return;
  // Pixels that needed the check while it was being built: it is needed now.
  if (!above_) adopt_above_range();
  if (!above_) {
    above_pending_points_.clear();
    above_pending_signals_.clear();
    return;
  }
  const auto bands = static_cast<std::size_t>(model_->profile().band_count());
  std::vector<cv::Point> found;
  for (std::size_t k = 0; k < above_pending_points_.size(); ++k)
    if (!std::isnan(above_->reading_above(&above_pending_signals_[k * bands])))
      found.push_back(above_pending_points_[k]);
  above_pending_points_.clear();
  above_pending_signals_.clear();
  const std::lock_guard<std::mutex> lock(above_mutex_);
  above_found_.insert(above_found_.end(), found.begin(), found.end());
}

std::vector<cv::Point> PlaneEstimator::take_above_range() const {
  const std::lock_guard<std::mutex> lock(above_mutex_);
  std::vector<cv::Point> found;
  found.swap(above_found_);
  return found;
}

void PlaneEstimator::above_range_row(const float* const* rows, std::size_t n, const float* out,
                                     int x0, int y) const {
  if (!above_ && !above_build_.valid()) return;
  const auto bands = static_cast<std::size_t>(model_->profile().band_count());
  const auto dim = static_cast<float>(model_->profile().thresholds.inference_dim_dn);
  constexpr float kMax = std::numeric_limits<float>::max();
  double s[kMaxBands];
  std::vector<cv::Point> found;
  // Most pixels read, and most of those that do not have a band that does not: chunk by chunk,
  // branch-free passes that vectorise say so before any pixel is looked at. (A per-pixel loop
  // over a 90 % colour plate's rows, whose edges leave pixels without a reading in nearly every
  // row, took 13 % of the estimate's CPU.)
  constexpr std::size_t kChunk = 64;
  for (std::size_t c0 = 0; c0 < n; c0 += kChunk) {
    const std::size_t c1 = std::min(n, c0 + kChunk);
    unsigned unread = 0;
    for (std::size_t i = c0; i < c1; ++i) unread |= static_cast<unsigned>(out[i] != out[i]);
    if (!unread) continue;
    if (bands == 3) {
      const float *r0 = rows[0], *r1 = rows[1], *r2 = rows[2];
      unsigned candidates = 0;
      for (std::size_t i = c0; i < c1; ++i)
        candidates |= static_cast<unsigned>(out[i] != out[i]) & (r0[i] >= dim) & (r1[i] >= dim) &
                      (r2[i] >= dim) & (r0[i] <= kMax) & (r1[i] <= kMax) & (r2[i] <= kMax);
      if (!candidates) continue;
    }
    for (std::size_t i = c0; i < c1; ++i) {
      if (!std::isnan(out[i])) continue;
      bool every_band_reads = true;
      for (std::size_t b = 0; b < bands && every_band_reads; ++b) {
        s[b] = rows[b][i];
        every_band_reads = s[b] >= dim && s[b] <= kMax;
      }
      if (!every_band_reads) continue;
      if (above_checked_.fetch_add(1, std::memory_order_relaxed) >= kAboveRangeBudget) {
        c0 = n;  // this estimate's budget is spent
        break;
      }
      if (!above_) {  // still being built: checked when the estimate ends
        const std::lock_guard<std::mutex> lock(above_mutex_);
        above_pending_points_.emplace_back(x0 + static_cast<int>(i), y);
        above_pending_signals_.insert(above_pending_signals_.end(), s, s + bands);
        continue;
      }
      if (!std::isnan(above_->reading_above(s))) found.emplace_back(x0 + static_cast<int>(i), y);
    }
  }
  if (found.empty()) return;
  const std::lock_guard<std::mutex> lock(above_mutex_);
  above_found_.insert(above_found_.end(), found.begin(), found.end());
}

PlaneEstimator::FitAudit PlaneEstimator::take_fit_audit(bool wait) const {
  if (!audit_) {
    if (audit_refused_) return {};
    // Its tables (a 5x5 locus: tens of ms) on a thread of their own, not in a frame's time.
    if (!audit_build_.valid())
      audit_build_ = std::async(std::launch::async, [model = model_] {
        return std::make_unique<MisfitCheck>(model, kFitAuditProbability, kFitAuditModelError);
      });
    if (wait) audit_build_.wait();
    if (audit_build_.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return {};
    try {
      audit_ = audit_build_.get();
      audit_->set_analogue_gain(analogue_gain_);
    } catch (const std::exception&) {
      audit_refused_ = true;  // a model the check cannot take: no audit
    }
    return {};
  }
  return {audit_counts_->checked.exchange(0), audit_counts_->misfit.exchange(0),
          audit_counts_->too_bright.exchange(0)};
}

void PlaneEstimator::audit_row(const float* const* rows, std::size_t n, const float* out) const {
  if (!audit_) return;
  // Every audit_rows_-th row (or run) that the threads estimate: a pass over its readings.
  if (audit_counts_->rows.fetch_add(1, std::memory_order_relaxed) % audit_rows_ != 0) return;
  const auto bands = static_cast<std::size_t>(model_->profile().band_count());
  std::size_t checked = 0, misfit = 0, too_bright = 0;
  double s[kMaxBands], c[kMaxBands];
  const double black_body_scale = exposure_s_ * analogue_gain_;  // 0: exposure unknown
  // Readings, not pixels, so that a small hot body has its share: the middle one of the row's
  // readings (away from a body's edges) where there are few, else every audit_stride_-th.
  std::size_t readings = 0;
  for (std::size_t i = 0; i < n; ++i) readings += std::isfinite(out[i]) ? 1 : 0;
  std::size_t next = readings < audit_stride_ ? readings / 2 : audit_stride_ / 2;
  for (std::size_t i = 0, k = 0; i < n && k <= next && readings > 0; ++i) {
    if (!std::isfinite(out[i]) || k++ != next) continue;
    next += audit_stride_;
    for (std::size_t b = 0; b < bands; ++b) s[b] = rows[b][i];
    const double* signals = s;
    if (reads_sloped()) {  // the grey surface's signals that the reading corrected them to
      sloped_->corrected_signals(s, out[i], c);
      signals = c;
    }
    int counted = 0;
    double scale = NAN;
    const double chi2 = audit_->chi2(signals, out[i], &counted, &scale);
    if (!std::isfinite(chi2) || counted < 3) continue;  // nothing to check
    ++checked;
    misfit += chi2 > audit_->threshold(counted);
    too_bright += black_body_scale > 0 && scale > kImpossibleBrightness * black_body_scale;
  }
  if (checked == 0) return;
  audit_counts_->checked.fetch_add(checked, std::memory_order_relaxed);
  audit_counts_->misfit.fetch_add(misfit, std::memory_order_relaxed);
  audit_counts_->too_bright.fetch_add(too_bright, std::memory_order_relaxed);
}

void PlaneEstimator::estimate_row(const float* const* rows, std::size_t n, float* out) const {
  const bool sloped = reads_sloped();
  if (sloped)
    sloped_->estimate(rows, n, out);
  else
    estimator_->estimate(rows, n, out);
  if (const TemperatureEstimator* partial =
          sloped ? static_cast<const TemperatureEstimator*>(sloped_partial_fit_.get())
                 : partial_fit_.get()) {
    // Only pixels with a band the network cannot use: a reading outside its range stays none.
    const auto bands = static_cast<std::size_t>(model_->profile().band_count());
    const double dim = model_->profile().thresholds.inference_dim_dn;
    double s[kMaxBands];
    for (std::size_t i = 0; i < n; ++i) {
      if (!std::isnan(out[i])) continue;
      bool some_unusable = false;
      for (std::size_t b = 0; b < bands; ++b) {
        s[b] = rows[b][i];
        some_unusable |= !(s[b] >= dim && std::isfinite(s[b]));
      }
      if (some_unusable) out[i] = static_cast<float>(partial->temperature_c(s));
    }
  }
  audit_row(rows, n, out);
  if (!misfit_) return;
  if (!sloped) {
    misfit_->apply(rows, n, out);
    return;
  }
  // The check sees the signals of the grey surface that the reading corrected them to.
  const auto bands = static_cast<std::size_t>(model_->profile().band_count());
  std::vector<float> corrected(bands * n);
  std::vector<const float*> corrected_rows(bands);
  for (std::size_t b = 0; b < bands; ++b) corrected_rows[b] = corrected.data() + b * n;
  double s[kMaxBands], c[kMaxBands];
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t b = 0; b < bands; ++b) s[b] = rows[b][i];
    sloped_->corrected_signals(s, out[i], c);
    for (std::size_t b = 0; b < bands; ++b) corrected[b * n + i] = static_cast<float>(c[b]);
  }
  misfit_->apply(corrected_rows.data(), n, out);
}

cv::Size PlaneEstimator::checked_size(const std::vector<cv::Mat>& planes) const {
  const int bands = model_->profile().band_count();
  if (static_cast<int>(planes.size()) != bands)
    throw InputError("the stream has " + std::to_string(planes.size()) + " bands, the model " +
                     std::to_string(bands) + " (" + model_->profile().name + ")");
  const cv::Size size = planes[0].size();
  for (const auto& p : planes)
    if (p.type() != CV_32F || p.size() != size)
      throw InputError("band planes must be CV_32F of equal size");
  return size;
}

void PlaneEstimator::uncertainty_row(const float* const* rows, std::size_t n, const float* t,
                                     float* out, int x0, int y, const DemosaicNoise& noise) const {
  double s[kMaxBands];
  const auto bands = static_cast<std::size_t>(model_->profile().band_count());
  for (std::size_t x = 0; x < n; ++x) {
    if (!std::isfinite(t[x])) {
      out[x] = NAN;
      continue;
    }
    for (std::size_t b = 0; b < bands; ++b) s[b] = rows[b][x];
    out[x] = static_cast<float>(
        expanded_uncertainty_c(estimator(), s, t[x], 1, noise.at(x0 + static_cast<int>(x), y)));
  }
}

bool PlaneEstimator::reads_partial() const {
  return method_ == Method::kLikelihood ? estimator_->can_read_partial() : partial_fit_ != nullptr;
}

std::unique_ptr<const DimEdgeCheck> PlaneEstimator::dim_edge_check(
    const DemosaicNoise& noise) const {
  // Where a band below the threshold leaves the pixel to the likelihood fit, which weighs it
  // by its noise, the threshold does not decide whether a pixel reads.
  if (reads_partial()) return nullptr;
  return std::make_unique<const DimEdgeCheck>(model_->profile(), analogue_gain_, noise);
}

SaturationEdgeCheck PlaneEstimator::saturation_edge_check() const {
  const double level = saturation_level_dn_ > 0
                           ? saturation_level_dn_
                           : model_->profile().thresholds.inference_saturation_dn;
  return SaturationEdgeCheck(model_->profile(), analogue_gain_, level);
}

RingMeans PlaneEstimator::planes_ring_mean_of(const std::vector<cv::Mat>& planes, double saturated,
                                              double foreign_above) const {
  if (dim_edge_mosaic_) return mosaic_window_mean_of(*dim_edge_mosaic_, saturated, foreign_above);
  const DimEdgeCheck::Ring ring = DimEdgeCheck::plane_ring(model_->profile().mosaic);
  return {
      [&planes, ring, saturated, foreign_above](int b, int first, int last, int y) {
        return plane_ring_mean(planes[static_cast<std::size_t>(b)], first, last, y, ring, saturated,
                               foreign_above);
      },
      [&planes, ring, saturated, foreign_above](int b, int first, int span, int y, double* means) {
        plane_ring_means_four(planes[static_cast<std::size_t>(b)], first, span, y, ring, means,
                              saturated, foreign_above);
      }};
}

RingMeans PlaneEstimator::mosaic_window_mean_of(const MatchedMosaic& source, double saturated,
                                                double foreign_above) {
  return {[&source, saturated, foreign_above](int b, int first, int last, int y) {
            return mosaic_ring_mean(source.mosaic, source.layout, b, first, last, y,
                                    DimEdgeCheck::kMosaicRing, saturated, foreign_above);
          },
          [&source, saturated, foreign_above](int b, int first, int span, int y, double* means) {
            mosaic_ring_means_four(source.mosaic, source.layout, b, first, span, y,
                                   DimEdgeCheck::kMosaicRing, means, saturated, foreign_above);
          }};
}

void PlaneEstimator::estimate(const std::vector<cv::Mat>& planes, cv::Mat& t, cv::Mat* u) const {
  const int bands = model_->profile().band_count();
  const cv::Size size = checked_size(planes);
  ready_above_range();
  t.create(size, CV_32F);
  if (u) u->create(size, CV_32F);
  const std::unique_ptr<const DimEdgeCheck> dim_edge = dim_edge_check(noise_);
  const SaturationEdgeCheck saturation_edge = saturation_edge_check();
  const bool every_band_reads = !reads_partial();
  const auto window_mean = planes_ring_mean_of(planes);
  const auto saturation_window =
      planes_ring_mean_of(planes, saturation_edge.level_dn(), saturation_edge.foreign_above_dn());
  // Rows in parallel: each estimator call is const and thread-safe.
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    std::vector<const float*> row_ptrs(static_cast<std::size_t>(bands));
    std::vector<std::vector<float>> band_scratch;
    for (int y = rows.start; y < rows.end; ++y) {
      for (int b = 0; b < bands; ++b) row_ptrs[b] = planes[b].ptr<float>(y);
      saturation_edge.apply(row_ptrs.data(), static_cast<std::size_t>(size.width), 0, y,
                            saturation_window, band_scratch, DimEdgeCheck::kSpan, every_band_reads);
      float* out = t.ptr<float>(y);
      estimate_row(row_ptrs.data(), static_cast<std::size_t>(size.width), out);
      above_range_row(row_ptrs.data(), static_cast<std::size_t>(size.width), out, 0, y);
      if (dim_edge)
        dim_edge->apply(row_ptrs.data(), static_cast<std::size_t>(size.width), out, 0, y,
                        window_mean);
      if (u)
        uncertainty_row(row_ptrs.data(), static_cast<std::size_t>(size.width), out,
                        u->ptr<float>(y), 0, y, noise_);
    }
  });
  finish_above_range();
}

void PlaneEstimator::estimate_codes(const std::vector<cv::Mat>& planes, cv::Mat& codes) const {
  const int bands = model_->profile().band_count();
  const cv::Size size = checked_size(planes);
  ready_above_range();
  codes.create(size, CV_16U);
  const std::unique_ptr<const DimEdgeCheck> dim_edge = dim_edge_check(noise_);
  const SaturationEdgeCheck saturation_edge = saturation_edge_check();
  const bool every_band_reads = !reads_partial();
  const auto window_mean = planes_ring_mean_of(planes);
  const auto saturation_window =
      planes_ring_mean_of(planes, saturation_edge.level_dn(), saturation_edge.foreign_above_dn());
  // Row by row: a row's temperatures are encoded while they are in cache.
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    std::vector<const float*> row_ptrs(static_cast<std::size_t>(bands));
    std::vector<std::vector<float>> band_scratch;
    std::vector<float> t(static_cast<std::size_t>(size.width));
    for (int y = rows.start; y < rows.end; ++y) {
      for (int b = 0; b < bands; ++b) row_ptrs[b] = planes[b].ptr<float>(y);
      saturation_edge.apply(row_ptrs.data(), static_cast<std::size_t>(size.width), 0, y,
                            saturation_window, band_scratch, DimEdgeCheck::kSpan, every_band_reads);
      estimate_row(row_ptrs.data(), static_cast<std::size_t>(size.width), t.data());
      above_range_row(row_ptrs.data(), static_cast<std::size_t>(size.width), t.data(), 0, y);
      if (dim_edge)
        dim_edge->apply(row_ptrs.data(), static_cast<std::size_t>(size.width), t.data(), 0, y,
                        window_mean);
      encode_temperature_row(t.data(), codes.ptr<std::uint16_t>(y), size.width);
    }
  });
  finish_above_range();
}

template <class LitRun, class DarkRun>
void PlaneEstimator::for_each_strip(const MatchedMosaic& source, const LitRun& lit_run,
                                    const DarkRun& dark_run) const {
  const cv::Mat& mosaic = source.mosaic;
  const int width = mosaic.cols, height = mosaic.rows;
  const int blocks = matched_bayer_blocks(width);
  // 16 rows of three float planes: 0.4 MB at 2048 columns, within a core's cache.
  constexpr int kStripRows = 16;
  const int strips = (height + kStripRows - 1) / kStripRows;
  // Runs of strips, each strip demosaicked after the last without reading its rows again: a few
  // runs a thread, so that a hot region's strips still spread over the threads.
  const double runs = std::min<double>(strips, 4.0 * std::max(1, cv::getNumThreads()));
  cv::parallel_for_(
      cv::Range(0, strips),
      [&](const cv::Range& range) {
        MatchedBayerRows matched(mosaic, source.layout, source.no_signal_dn);
        std::vector<cv::Mat> strip;
        std::vector<std::uint8_t> lit;
        std::vector<float> scratch(static_cast<std::size_t>(width));
        std::vector<std::vector<float>> band_scratch;
        for (int k = range.start; k < range.end; ++k) {
          const int y0 = k * kStripRows, y1 = std::min(height, y0 + kStripRows);
          matched.rows(y0, y1, strip, lit);
          for (int y = y0; y < y1; ++y) {
            const std::uint8_t* row_lit = lit.data() + static_cast<std::ptrdiff_t>(y - y0) * blocks;
            for (int b0 = 0; b0 < blocks;) {
              int b1 = b0 + 1;
              while (b1 < blocks && (row_lit[b1] != 0) == (row_lit[b0] != 0)) ++b1;
              const int x0 = b0 * kMatchedBlockColumns,
                        x1 = std::min(width, b1 * kMatchedBlockColumns);
              if (row_lit[b0]) {
                const float* rows[3] = {strip[0].ptr<float>(y - y0) + x0,
                                        strip[1].ptr<float>(y - y0) + x0,
                                        strip[2].ptr<float>(y - y0) + x0};
                lit_run(y, x0, x1, rows, scratch.data(), band_scratch);
              } else {
                dark_run(y, x0, x1);
              }
              b0 = b1;
            }
          }
        }
      },
      runs);
}

void PlaneEstimator::estimate(const MatchedMosaic& source, cv::Mat& t, cv::Mat* u) const {
  check_matched_mosaic(source);
  ready_above_range();
  t.create(source.mosaic.size(), CV_32F);
  if (u) u->create(source.mosaic.size(), CV_32F);
  const DemosaicNoise noise = demosaic_noise(source.layout, DemosaicMethod::kMatched);
  const std::unique_ptr<const DimEdgeCheck> dim_edge = dim_edge_check(noise);
  const SaturationEdgeCheck saturation_edge = saturation_edge_check();
  const bool every_band_reads = !reads_partial();
  const auto window_mean = mosaic_window_mean_of(source);
  const auto saturation_window =
      mosaic_window_mean_of(source, saturation_edge.level_dn(), saturation_edge.foreign_above_dn());
  for_each_strip(
      source,
      [&](int y, int x0, int x1, const float** rows, float*, std::vector<std::vector<float>>& bs) {
        const auto n = static_cast<std::size_t>(x1 - x0);
        saturation_edge.apply(rows, n, x0, y, saturation_window, bs, DimEdgeCheck::kSpan,
                              every_band_reads);
        float* out = t.ptr<float>(y) + x0;
        estimate_row(rows, n, out);
        above_range_row(rows, n, out, x0, y);
        if (dim_edge) dim_edge->apply(rows, n, out, x0, y, window_mean);
        if (u) uncertainty_row(rows, n, out, u->ptr<float>(y) + x0, x0, y, noise);
      },
      [&](int y, int x0, int x1) {
        std::fill(t.ptr<float>(y) + x0, t.ptr<float>(y) + x1, NAN);
        if (u) std::fill(u->ptr<float>(y) + x0, u->ptr<float>(y) + x1, NAN);
      });
  finish_above_range();
}

void PlaneEstimator::estimate_codes(const MatchedMosaic& source, cv::Mat& codes) const {
  check_matched_mosaic(source);
  ready_above_range();
  codes.create(source.mosaic.size(), CV_16U);
  const std::unique_ptr<const DimEdgeCheck> dim_edge =
      dim_edge_check(demosaic_noise(source.layout, DemosaicMethod::kMatched));
  const SaturationEdgeCheck saturation_edge = saturation_edge_check();
  const bool every_band_reads = !reads_partial();
  const auto window_mean = mosaic_window_mean_of(source);
  const auto saturation_window =
      mosaic_window_mean_of(source, saturation_edge.level_dn(), saturation_edge.foreign_above_dn());
  for_each_strip(
      source,
      [&](int y, int x0, int x1, const float** rows, float* t,
          std::vector<std::vector<float>>& bs) {
        saturation_edge.apply(rows, static_cast<std::size_t>(x1 - x0), x0, y, saturation_window, bs,
                              DimEdgeCheck::kSpan, every_band_reads);
        // The run's temperatures, encoded while they are in cache.
        estimate_row(rows, static_cast<std::size_t>(x1 - x0), t);
        above_range_row(rows, static_cast<std::size_t>(x1 - x0), t, x0, y);
        if (dim_edge)
          dim_edge->apply(rows, static_cast<std::size_t>(x1 - x0), t, x0, y, window_mean);
        encode_temperature_row(t, codes.ptr<std::uint16_t>(y) + x0, x1 - x0);
        if (curvature_)
          curvature_->apply_run(source.mosaic, codes.ptr<std::uint16_t>(y), y, x0, x1);
      },
      [&](int y, int x0, int x1) {
        std::fill(codes.ptr<std::uint16_t>(y) + x0, codes.ptr<std::uint16_t>(y) + x1,
                  kNoReadingCode);
      });
  finish_above_range();
}

void PlaneEstimator::check_matched_mosaic(const MatchedMosaic& source) const {
  if (source.layout.kind != MosaicLayout::Kind::kBayer)
    throw InputError("the fused path demosaics Bayer mosaics only, not " + source.layout.pattern);
  if (model_->profile().band_count() != 3)
    throw InputError("a Bayer mosaic gives 3 bands, the model has " +
                     std::to_string(model_->profile().band_count()) + " (" +
                     model_->profile().name + ")");
  if (source.mosaic.type() != CV_32F)
    throw InputError("the fused path takes a CV_32F dark-subtracted mosaic");
}

}  // namespace pyrocam
