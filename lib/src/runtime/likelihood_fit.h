// The likelihood fit's shared part (likelihood_estimator.cpp, the fast fit, and
// likelihood_exhaustive.cpp, the exhaustive scan it is tested against): weights, exact chi2 and
// the decision.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "detail/portable_math.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/extrapolation_pair.h"
#include "runtime/estimator_kinds.h"
#include "runtime/likelihood_kernels.h"

namespace pyrocam {

// Weighted least squares of the band signals against the modelled locus with a free scale
// (unknown emissivity, exposure and geometry): chi2(T) = sum w (S - a m(T))^2, a profiled out.
// The locus is sampled every 1 degC; chi2 is scanned every kCoarse samples keeping every local
// minimum (with few valid bands the locus can pass the same ratios twice, and a reading that
// fits two temperatures is no reading), each minimum is refined to the 1 degC sample within
// kCoarse of it, and a parabola through the best sample and its neighbours gives the answer.
// This base holds what both implementations share: the weights, the exact chi2 and the decision.
class LikelihoodFit : public TemperatureEstimator {
 public:
  // Two minima closer than this in chi2 (about 3 sigma) make the reading ambiguous.
  static constexpr double kAmbiguityChi2 = 9.0;
  static constexpr Eigen::Index kCoarse = 20;

  explicit LikelihoodFit(std::shared_ptr<const ThermalModel> model)
      : TemperatureEstimator(std::move(model)),
        locus_(
            make_locus(model_->camera, model_->min_temperature_c, model_->max_temperature_c, 1.0)),
        width_(padded_bands(bands_)),
        rates_(static_cast<std::size_t>(locus_.size() * width_)),
        squares_(static_cast<std::size_t>(locus_.size() * width_)) {
    for (Eigen::Index i = 0; i < locus_.size(); ++i)
      for (int b = 0; b < bands_; ++b) {
        const double m = locus_.rates(i, b);
        rates_[static_cast<std::size_t>(i * width_ + b)] = m;
        squares_[static_cast<std::size_t>(i * width_ + b)] = m * m;
      }
    set_noise(1.0);
    // Bands between the no-signal level and the dim threshold are weighed by their noise (see
    // weigh_dim_dn_).
    std::vector<SignalNoise> noise;
    for (int b = 0; b < bands_; ++b) noise.push_back(signal_noise(model_->profile(), b));
    weigh_dim_dn_ = std::min(dim_dn_, no_signal_level_dn(noise));
    // A ratio that turns over (rises, then falls) fits two temperatures: only pairs whose ratio
    // keeps one direction over the whole range read a pixel alone.
    monotonic_.assign(static_cast<std::size_t>(bands_ * bands_), 0);
    for (int i = 0; i < bands_; ++i)
      for (int j = i + 1; j < bands_; ++j) {
        int rising = 0, falling = 0;
        bool positive = true;
        double previous = NAN;
        for (Eigen::Index k = 0; k < locus_.size() && positive; ++k) {
          const double a = locus_.rates(k, i), b = locus_.rates(k, j);
          positive = a > 0 && b > 0;
          const double r = a / b;
          if (k > 0) rising += r > previous, falling += r < previous;
          previous = r;
        }
        const bool one_way = positive && (rising == 0 || falling == 0);
        monotonic_[static_cast<std::size_t>(i * bands_ + j)] = one_way;
        monotonic_[static_cast<std::size_t>(j * bands_ + i)] = one_way;
      }
    pair_ =
        extrapolation_pair(model_->camera, locus_, model_->calibrated_up_to_c, model_->pair_top_c);
  }

  // In chunks of pixels: those with fewer bands that read than the fit needs (the cold
  // background, most of a melt pool's frame) get no reading from a count over the band planes,
  // without the per-pixel weights (which cost about as much again as the count of all bands).
  // A chunk whose probes (eight pixels at each of four places spread over it) all have enough
  // bands, as on a plate, is not counted: there the count is the weights' own work done twice
  // (6-8 % of the 5x5 chain on a plate over 90 % of the frame). A thin hot line across the rows
  // (a filament) meets at most one probe of a chunk, so its chunks are still counted; one along a
  // row may fill a chunk, which is then weighed whole, as it should be. The weights decide the same
  // (enough_bands needs at least `needed` bands), so the readings are the same either way.
  void estimate(const float* const* planes, std::size_t n, float* out) const override {
    constexpr std::size_t kChunk = 256, kProbe = 8;
    alignas(64) std::int32_t reading[kChunk];
    auto dim_f = static_cast<float>(weigh_dim_dn_);
    if (static_cast<double>(dim_f) < weigh_dim_dn_)
      dim_f = std::nextafter(dim_f, std::numeric_limits<float>::infinity());
    const int needed = std::min(min_bands_, bands_);
    for (std::size_t start = 0; start < n; start += kChunk) {
      const std::size_t m = std::min(kChunk, n - start);
      bool count = m < kChunk;
      for (std::size_t probe = 0; probe < 4 && !count; ++probe) {
        count_reading_bands(planes, bands_, start + (2 * probe + 1) * kChunk / 8 - kProbe / 2,
                            kProbe, dim_f, reading);
        count = std::any_of(reading, reading + kProbe, [&](std::int32_t c) { return c < needed; });
      }
      if (count)
        count_reading_bands(planes, bands_, start, m, dim_f, reading);
      else
        std::fill(reading, reading + m, kUncounted);
      read_chunk(planes, start, m, reading, needed, out + start);
    }
  }

 protected:
  // A pixel's count in read_chunk's `reading` where its bands were not counted: at least any
  // `needed`, and never the number of bands.
  static constexpr std::int32_t kUncounted = std::numeric_limits<std::int32_t>::max();

  // The pixels start .. start + m - 1 into out[0 .. m - 1]: no reading where fewer than `needed`
  // bands read (`reading`: their counts, or kUncounted), the others one by one.
  virtual void read_chunk(const float* const* planes, std::size_t start, std::size_t m,
                          const std::int32_t* reading, int needed, float* out) const {
    double s[kMaxBands];
    for (std::size_t k = 0; k < m; ++k) {
      if (reading[k] < needed) {
        out[k] = NAN;
        continue;
      }
      for (int b = 0; b < bands_; ++b) s[b] = planes[b][start + k];
      out[k] = static_cast<float>(temperature_c(s));
    }
  }

  struct Minimum {
    Eigen::Index index;
    double chi2;
    double below, above;  // chi2 at index -1 and +1 when already known, else NaN
  };

  // A pixel's signals as the fit uses them: inverse noise variances w (0 drops a band:
  // saturated, NaN or below weigh_dim_dn_; the rest still fix the temperature), w*s (0 for a
  // dropped band) and sum w s^2; whether every band reads at the dim threshold (complete).
  struct Weighted {
    alignas(32) double w[kMaxBands];
    alignas(32) double ws[kMaxBands];
    double sss;
    bool complete;
    bool faint;   // a band below the dim threshold is weighed
    int weighed;  // bands with a weight
    int bright;   // bands at the dim threshold or above that read
  };

  void set_analogue_gain(double factor) override {
    TemperatureEstimator::set_analogue_gain(factor);
    set_noise(factor);
  }

  // The weights' noise model at an analogue gain factor (noise_model.h).
  void set_noise(double gain) {
    for (int b = 0; b < bands_; ++b) {
      const SignalNoise n = signal_noise(model_->profile(), b, gain);
      shot_gain_[b] = n.shot_gain;
      noise_floor_[b] = n.floor_dn2;
    }
  }

  bool can_read_partial() const override {
    if (partial_ == PartialBands::kOff || bands_ < 3) return false;
    return partial_ == PartialBands::kAny ||
           std::any_of(monotonic_.begin(), monotonic_.end(), [](std::uint8_t m) { return m != 0; });
  }

  // Whether the bands that read are enough: all of them at the dim threshold, or
  // (set_partial_bands) at least two weighed ones, with kSafe among them a pair whose ratio is
  // monotonic over the model's range.
  bool enough_bands(int reading, const Weighted& px) const {
    if (px.complete) return true;
    if (partial_ == PartialBands::kOff || reading < min_bands_) return false;
    if (partial_ != PartialBands::kSafe) return true;
    for (int i = 0; i < bands_; ++i) {
      if (px.w[i] == 0.0) continue;
      for (int j = i + 1; j < bands_; ++j)
        if (px.w[j] != 0.0 && monotonic_[static_cast<std::size_t>(i * bands_ + j)]) return true;
    }
    return false;
  }

  // How many bands the fit weighs (at least weigh_dim_dn_).
  int weigh(const double* s, Weighted& px) const {
    int bright = 0;
    const int reading = weigh_bands(s, bands_, weigh_dim_dn_, dim_dn_, shot_gain_, noise_floor_,
                                    px.w, px.ws, &px.sss, &bright);
    px.complete = bright == bands_;
    px.faint = reading > bright;
    px.bright = bright;
    px.weighed = reading;
    return reading;
  }

  // chi2 at locus sample i.
  double chi2(Eigen::Index i, const Weighted& px) const {
    const std::size_t row = static_cast<std::size_t>(i * width_);
    return profiled_chi2(&rates_[row], &squares_[row], px.ws, px.w, width_, px.sss);
  }

  // The reading from the refined minima: the best one, unless another one far from it fits
  // almost as well (ambiguous) or it sits at an end of the locus (outside the range).
  double decide(const Minimum* minima, std::size_t count, const Weighted& px) const {
    std::size_t best_k = 0;
    double best_chi2 = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < count; ++k)
      if (minima[k].chi2 < best_chi2) best_chi2 = minima[k].chi2, best_k = k;
    const Eigen::Index best = count ? minima[best_k].index : 0;
    for (std::size_t k = 0; k < count; ++k)
      if (std::abs(minima[k].index - best) > 3 * kCoarse &&
          minima[k].chi2 - best_chi2 < kAmbiguityChi2)
        return NAN;
    const Eigen::Index n = locus_.size();
    if (best == 0 || best == n - 1) return NAN;  // at the edge: outside the model's range
    // Parabola through the minimum and its neighbours for sub-step resolution.
    const double cm = std::isnan(minima[best_k].below) ? chi2(best - 1, px) : minima[best_k].below;
    const double cp = std::isnan(minima[best_k].above) ? chi2(best + 1, px) : minima[best_k].above;
    const double denom = cm - 2 * best_chi2 + cp;
    const double offset = denom > 0 ? 0.5 * (cm - cp) / denom : 0.0;
    const double step = locus_.temperature_c[1] - locus_.temperature_c[0];
    // A safe partial reading must also be precise: chi2 rises by 1 at one standard deviation,
    // so with the curvature denom / step^2 the noise alone leaves sqrt(2 / curvature).
    if (partial_ == PartialBands::kSafe && !px.complete &&
        !(denom > 0 &&
          step * std::sqrt(2 / denom) <= max_partial_sigma_c(locus_.temperature_c[best])))
      return NAN;
    const double t = in_range(locus_.temperature_c[best] + std::clamp(offset, -1.0, 1.0) * step);
    return pair_.active() ? above_calibration(t, px) : t;
  }

  // Above the calibration a three-band reading t passes to the pair's (extrapolation_pair.h);
  // a pixel whose pair does not read (a band dropped) keeps t.
  double above_calibration(double t, const Weighted& px) const {
    const int i = pair_.numerator, j = pair_.denominator;
    if (!(t > pair_.from_c) || px.w[i] == 0.0 || px.w[j] == 0.0) return t;
    const double si = px.ws[i] / px.w[i], sj = px.ws[j] / px.w[j];
    if (!(si > 0 && sj > 0)) return t;
    return in_range(pair_.read(t, portable::log(si / sj)));
  }

  Locus locus_;
  // m and m^2: samples x width_, row after row, each row on 32 bytes and zero past the bands
  // (the kernels sum whole lanes of four; weigh_bands zeroes w and ws there too).
  int width_;
  AlignedDoubles rates_, squares_;
  double shot_gain_[kMaxBands] = {}, noise_floor_[kMaxBands] = {};
  // The least signal the fit weighs, DN: the no-signal level (noise_model.h, where the
  // demosaicking marks samples without light), or the dim threshold if that is lower. A pixel
  // whose bands all reach the dim threshold is read as ever; below it a band still holds the
  // temperature, less precisely, and its weight says how much. Dropping it at the dim threshold
  // instead kept a band near the threshold only where its noise was positive: a censoring that
  // read uniform 5x5 plates 2-4 degC high (1300-2000 degC, brightest band at 16-35 % of its
  // range) and dimmer ones not at all. The dim threshold still decides which pixels are
  // complete: the others read only with partial bands, where kSafe asks them to be precise.
  double weigh_dim_dn_ = 0;
  std::vector<std::uint8_t> monotonic_;  // bands x bands: ratio monotonic over the locus
  ExtrapolationPair pair_;               // the ratio read above the calibration, if any
};

}  // namespace pyrocam
