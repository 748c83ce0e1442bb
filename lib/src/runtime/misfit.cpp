#include "pyrocam/runtime/misfit.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "detail/portable_math.h"
#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/physics.h"
#include "runtime/shared_model.h"

namespace pyrocam {
namespace {

constexpr int kMaxBands = 64;

// chi2 after one Gauss-Newton step in temperature from the reading, at most `window` times its
// absolute temperature: a = the profiled scale, sd and md the weighted products of the signals
// and of the locus rates with the rates' temperature derivative, curvature the weighted square
// of that derivative across the rates. Never above the chi2 at the reading, never below 0.
// Branch-free, so that the float batch vectorises; the double definition uses it too.
template <class Real>
inline Real chi2_after_step(Real chi2, Real a, Real sd, Real md, Real curvature, Real temperature_c,
                            Real window) {
  const Real zero = 0, half = 0.5;
  const Real slope = -2 * a * (sd - a * md);
  const Real hessian = 2 * a * a * curvature;
  const Real limit = window * (temperature_c + static_cast<Real>(kZeroCelsius));
  Real step = hessian > zero ? -slope / hessian : zero;
  step = step < limit ? step : limit;
  step = step > -limit ? step : -limit;
  const Real reduced = chi2 + slope * step + half * hessian * step * step;
  return reduced < chi2 ? (reduced > zero ? reduced : zero) : chi2;
}

// ln Gamma(a) for a = dof / 2 (a whole or half number): exact recursion from Gamma(1) = 1 and
// Gamma(1/2) = sqrt(pi), no global state (std::lgamma may write signgam).
double log_gamma_half_integer(int twice_a) {
  double log_g = twice_a % 2 ? 0.5 * portable::log(3.14159265358979323846) : 0.0;
  for (int k = twice_a % 2 ? 1 : 2; k + 2 <= twice_a; k += 2) log_g += portable::log(k / 2.0);
  return log_g;
}

// Regularised upper incomplete gamma Q(a, x), a = twice_a / 2: series for P below a + 1,
// continued fraction (modified Lentz) above.
double upper_gamma_q(int twice_a, double x) {
  const double a = twice_a / 2.0;
  if (!(x > 0)) return 1.0;
  const double log_prefactor = -x + a * portable::log(x) - log_gamma_half_integer(twice_a);
  constexpr double kEps = 1e-15, kTiny = 1e-300;
  if (x < a + 1) {
    double term = 1.0 / a, sum = term, ap = a;
    for (int i = 0; i < 10000; ++i) {
      ap += 1;
      term *= x / ap;
      sum += term;
      if (std::abs(term) < std::abs(sum) * kEps) break;
    }
    return std::max(0.0, 1.0 - sum * portable::exp(log_prefactor));
  }
  double b = x + 1 - a, c = 1 / kTiny, d = 1 / b, h = d;
  for (int i = 1; i < 10000; ++i) {
    const double an = -i * (i - a);
    b += 2;
    d = an * d + b;
    if (std::abs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::abs(c) < kTiny) c = kTiny;
    d = 1 / d;
    const double delta = d * c;
    h *= delta;
    if (std::abs(delta - 1) < kEps) break;
  }
  return portable::exp(log_prefactor) * h;
}

// The pixel loop: bands fixed at compile time (kFixedBands > 0, unrolled and vectorised across
// pixels) or at run time (kFixedBands == 0).
template <int kFixedBands>
[[gnu::always_inline]] inline void apply_misfit_impl(
    const float* const* planes, int runtime_bands, std::size_t n, float* __restrict t,
    const float* __restrict table, int samples, float t0, float inv_step, float dim,
    const float* __restrict gain, const float* __restrict floor, float error2, float window,
    const float* __restrict thresholds) {
  const int bands = kFixedBands > 0 ? kFixedBands : runtime_bands;
  constexpr int kArray = kFixedBands > 0 ? kFixedBands : kMaxBands;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const float last = static_cast<float>(samples - 1);
  const float* p[kArray];
  for (int b = 0; b < bands; ++b) p[b] = planes[b];
  for (std::size_t k = 0; k < n; ++k) {
    const float temperature = t[k];
    float u = (temperature - t0) * inv_step;  // NaN for no reading
    u = u >= 0.f ? u : 0.f;
    u = u <= last ? u : last;
    int i = static_cast<int>(u);
    i = i < samples - 2 ? i : samples - 2;
    const float f = u - static_cast<float>(i);
    float w[kArray], s[kArray], m[kArray], d[kArray];
    float sm = 0, mm = 0, sd = 0, md = 0;
    int counted = 0;
    for (int b = 0; b < bands; ++b) {
      const float v = p[b][k];
      const bool reads = v >= dim && v < kInf;  // NaN fails both
      s[b] = reads ? v : 0.f;
      const float variance = gain[b] * s[b] + floor[b] + error2 * s[b] * s[b];
      w[b] = reads ? 1.f / variance : 0.f;
      const float* row = table + static_cast<std::ptrdiff_t>(b) * samples;
      d[b] = (row[i + 1] - row[i]) * inv_step;
      m[b] = row[i] + f * (row[i + 1] - row[i]);
      sm += w[b] * s[b] * m[b];
      mm += w[b] * m[b] * m[b];
      sd += w[b] * s[b] * d[b];
      md += w[b] * m[b] * d[b];
      counted += reads ? 1 : 0;
    }
    const float a = sm / mm, along = md / mm;
    float chi2 = 0, curvature = 0;
    for (int b = 0; b < bands; ++b) {
      const float r = s[b] - a * m[b];
      chi2 += w[b] * r * r;
      const float across = d[b] - along * m[b];
      curvature += w[b] * across * across;
    }
    chi2 = chi2_after_step(chi2, a, sd, md, curvature, temperature, window);
    // NaN chi2 (no counted band) fails the comparison: the reading (if any) stays.
    t[k] = chi2 > thresholds[counted] ? std::numeric_limits<float>::quiet_NaN() : temperature;
  }
}

// Three bands (colour cameras), in chunks of pixels and passes that vectorise: the locus
// positions, the table reads, then the arithmetic of every pixel (branch-free). A chunk without
// a reading (background) stops after the first pass. The same arithmetic as apply_misfit_impl;
// with fewer than three bands reading there is nothing to check.
PYROCAM_VECTOR_CLONES
void apply_misfit_3(const float* const* planes, std::size_t n, float* t, const float* table,
                    int samples, float t0, float inv_step, float dim, const float* gain,
                    const float* floor, float error2, float window, const float* thresholds) {
  constexpr std::size_t kChunk = 256;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  alignas(64) float fraction[kChunk], m0[3][kChunk], dm[3][kChunk];
  alignas(64) std::int32_t index[kChunk];
  const float threshold = thresholds[3];
  const float last = static_cast<float>(samples - 1);
  const std::int32_t top = samples - 2;
  const float g0 = gain[0], g1 = gain[1], g2 = gain[2];
  const float f0 = floor[0], f1 = floor[1], f2 = floor[2];
  for (std::size_t start = 0; start < n; start += kChunk) {
    const std::size_t count = std::min(kChunk, n - start);
    float* __restrict tc = t + start;
    int readings = 0;
    for (std::size_t k = 0; k < count; ++k) readings += tc[k] == tc[k] ? 1 : 0;
    if (!readings) continue;
    for (std::size_t k = 0; k < count; ++k) {
      float u = (tc[k] - t0) * inv_step;  // NaN for no reading
      u = u >= 0.f ? u : 0.f;
      u = u <= last ? u : last;
      std::int32_t i = static_cast<std::int32_t>(u);
      i = i < top ? i : top;
      index[k] = i;
      fraction[k] = u - static_cast<float>(i);
    }
    for (int b = 0; b < 3; ++b) {
      const float* __restrict row = table + static_cast<std::ptrdiff_t>(b) * samples;
      for (std::size_t k = 0; k < count; ++k) {
        const float below = row[index[k]], above = row[index[k] + 1];
        m0[b][k] = below;
        dm[b][k] = above - below;
      }
    }
    const float* __restrict p0 = planes[0] + start;
    const float* __restrict p1 = planes[1] + start;
    const float* __restrict p2 = planes[2] + start;
    for (std::size_t k = 0; k < count; ++k) {
      const float v0 = p0[k], v1 = p1[k], v2 = p2[k];
      const bool all_read =
          v0 >= dim && v0 < kInf && v1 >= dim && v1 < kInf && v2 >= dim && v2 < kInf;  // NaN fails
      const float s0 = all_read ? v0 : 0.f, s1 = all_read ? v1 : 0.f, s2 = all_read ? v2 : 0.f;
      const float w0 = 1.f / (g0 * s0 + f0 + error2 * s0 * s0);
      const float w1 = 1.f / (g1 * s1 + f1 + error2 * s1 * s1);
      const float w2 = 1.f / (g2 * s2 + f2 + error2 * s2 * s2);
      const float fr = fraction[k];
      const float m_0 = m0[0][k] + fr * dm[0][k], m_1 = m0[1][k] + fr * dm[1][k],
                  m_2 = m0[2][k] + fr * dm[2][k];
      const float d0 = dm[0][k] * inv_step, d1 = dm[1][k] * inv_step, d2 = dm[2][k] * inv_step;
      const float sm = w0 * s0 * m_0 + w1 * s1 * m_1 + w2 * s2 * m_2;
      const float mm = w0 * m_0 * m_0 + w1 * m_1 * m_1 + w2 * m_2 * m_2;
      const float sd = w0 * s0 * d0 + w1 * s1 * d1 + w2 * s2 * d2;
      const float md = w0 * m_0 * d0 + w1 * m_1 * d1 + w2 * m_2 * d2;
      const float a = sm / mm, along = md / mm;
      const float r0 = s0 - a * m_0, r1 = s1 - a * m_1, r2 = s2 - a * m_2;
      float chi2 = w0 * r0 * r0 + w1 * r1 * r1 + w2 * r2 * r2;
      const float c0 = d0 - along * m_0, c1 = d1 - along * m_1, c2 = d2 - along * m_2;
      const float curvature = w0 * c0 * c0 + w1 * c1 * c1 + w2 * c2 * c2;
      const float temperature = tc[k];
      chi2 = chi2_after_step(chi2, a, sd, md, curvature, temperature, window);
      const bool drop = all_read && chi2 > threshold;  // NaN (no reading) fails
      tc[k] = drop ? std::numeric_limits<float>::quiet_NaN() : temperature;
    }
  }
}

PYROCAM_VECTOR_CLONES
void apply_misfit_any(const float* const* planes, int bands, std::size_t n, float* t,
                      const float* table, int samples, float t0, float inv_step, float dim,
                      const float* gain, const float* floor, float error2, float window,
                      const float* thresholds) {
  apply_misfit_impl<0>(planes, bands, n, t, table, samples, t0, inv_step, dim, gain, floor, error2,
                       window, thresholds);
}

}  // namespace

double chi2_upper_tail(int dof, double x) {
  if (dof < 1) throw InputError("chi-squared: degrees of freedom must be at least 1");
  return upper_gamma_q(dof, x / 2);
}

double chi2_upper_quantile(int dof, double probability) {
  if (dof < 1) throw InputError("chi-squared: degrees of freedom must be at least 1");
  if (!(probability > 0 && probability < 1))
    throw InputError("chi-squared quantile: probability must be in (0, 1), not " +
                     std::to_string(probability));
  // The tail falls with x: bracket, then bisect to double precision.
  double lo = 0, hi = std::max(1.0, static_cast<double>(dof));
  while (chi2_upper_tail(dof, hi) > probability) {
    lo = hi;
    hi *= 2;
  }
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (chi2_upper_tail(dof, mid) > probability ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

MisfitCheck::MisfitCheck(std::shared_ptr<const ThermalModel> shared_model, double probability,
                         double model_error)
    : model_(std::move(shared_model)),
      bands_(require_model(model_, "misfit check").profile().band_count()),
      model_error_(model_error),
      dim_dn_(static_cast<float>(model_->profile().thresholds.inference_dim_dn)) {
  const ThermalModel& model = *model_;
  if (bands_ > kMaxBands) throw InputError("at most 64 bands are supported");
  if (!(model_error >= 0) || !std::isfinite(model_error))
    throw InputError("misfit check: the model error must be a finite fraction >= 0");
  const Locus locus =
      make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, 1.0);
  samples_ = static_cast<int>(locus.size());
  if (samples_ < 2) throw InputError("misfit check: the model's temperature range is empty");
  t0_c_ = locus.temperature_c[0];
  step_c_ = locus.temperature_c[1] - locus.temperature_c[0];
  table_.resize(static_cast<std::size_t>(bands_) * static_cast<std::size_t>(samples_));
  table_d_.resize(table_.size());
  norm_.resize(static_cast<std::size_t>(samples_));
  for (int i = 0; i < samples_; ++i) {
    const double norm = locus.rates.row(i).norm();
    norm_[static_cast<std::size_t>(i)] = norm;
    if (!(norm > 0) || !std::isfinite(norm))
      throw InputError("misfit check: the model's locus has no signal at " +
                       std::to_string(locus.temperature_c[i]) + " degC");
    for (int b = 0; b < bands_; ++b) {
      const std::size_t at = static_cast<std::size_t>(b) * static_cast<std::size_t>(samples_) +
                             static_cast<std::size_t>(i);
      table_d_[at] = locus.rates(i, b) / norm;
      table_[at] = static_cast<float>(table_d_[at]);
    }
  }
  set_analogue_gain(1.0);
  set_probability(probability);
}

void MisfitCheck::set_analogue_gain(double factor) {
  if (!(factor > 0) || !std::isfinite(factor))
    throw InputError("misfit check: the analogue gain must be a positive factor");
  analogue_gain_ = factor;
  gain_.clear();
  floor_.clear();
  for (int b = 0; b < bands_; ++b) {
    const SignalNoise n = signal_noise(model_->profile(), b, factor);
    gain_.push_back(static_cast<float>(n.shot_gain));
    floor_.push_back(static_cast<float>(n.floor_dn2));
  }
}

void MisfitCheck::set_probability(double probability) {
  if (!(probability >= 0 && probability < 1))
    throw InputError(
        "misfit check: the false-rejection probability must be 0 (off) or in (0, 1), "
        "not " +
        std::to_string(probability));
  if (probability == probability_ && !thresholds_.empty()) return;
  probability_ = probability;
  thresholds_.assign(static_cast<std::size_t>(bands_) + 1, std::numeric_limits<double>::infinity());
  if (probability > 0)
    for (int counted = 3; counted <= bands_; ++counted)
      thresholds_[static_cast<std::size_t>(counted)] =
          chi2_upper_quantile(counted - 2, probability);
  thresholds_f_.assign(thresholds_.begin(), thresholds_.end());
}

double MisfitCheck::threshold(int counted) const {
  if (counted < 0 || counted > bands_) return std::numeric_limits<double>::infinity();
  return thresholds_[static_cast<std::size_t>(counted)];
}

double MisfitCheck::chi2(const double* s, double t_c, int* counted_out, double* rate_scale) const {
  int counted = 0;
  if (counted_out) *counted_out = 0;
  if (rate_scale) *rate_scale = NAN;
  if (!(t_c >= model_->min_temperature_c && t_c <= model_->max_temperature_c)) return NAN;
  const double u = std::clamp((t_c - t0_c_) / step_c_, 0.0, static_cast<double>(samples_ - 1));
  const int i = std::min(static_cast<int>(u), samples_ - 2);
  const double f = u - i;
  double w[kMaxBands], m[kMaxBands], d[kMaxBands], sm = 0, mm = 0, sd = 0, md = 0;
  for (int b = 0; b < bands_; ++b) {
    const double* row = &table_d_[static_cast<std::size_t>(b) * static_cast<std::size_t>(samples_)];
    m[b] = row[i] + f * (row[i + 1] - row[i]);
    d[b] = (row[i + 1] - row[i]) / step_c_;
    const bool reads = s[b] >= dim_dn_ && std::isfinite(s[b]);
    w[b] = 0;
    if (!reads) continue;
    const double e = model_error_ * s[b];
    w[b] = 1 / (signal_variance_dn2(model_->profile(), b, s[b], 1, analogue_gain_) + e * e);
    sm += w[b] * s[b] * m[b];
    mm += w[b] * m[b] * m[b];
    sd += w[b] * s[b] * d[b];
    md += w[b] * m[b] * d[b];
    ++counted;
  }
  if (counted_out) *counted_out = counted;
  if (!counted) return NAN;
  const double a = sm / mm, along = md / mm;
  if (rate_scale) {
    const auto at = static_cast<std::size_t>(i);
    *rate_scale = a / (norm_[at] + f * (norm_[at + 1] - norm_[at]));
  }
  double chi2 = 0, curvature = 0;
  for (int b = 0; b < bands_; ++b) {
    if (!(w[b] > 0)) continue;
    chi2 += w[b] * (s[b] - a * m[b]) * (s[b] - a * m[b]);
    curvature += w[b] * (d[b] - along * m[b]) * (d[b] - along * m[b]);
  }
  // The best graybody within the window: one Gauss-Newton step in temperature.
  return chi2_after_step(chi2, a, sd, md, curvature, t_c, kMisfitWindow);
}

void MisfitCheck::apply(const float* const* planes, std::size_t n, float* t_c) const {
  if (!enabled()) return;
  const float t0 = static_cast<float>(t0_c_), inv_step = static_cast<float>(1 / step_c_);
  const float error2 = static_cast<float>(model_error_ * model_error_);
  if (bands_ == 3)
    apply_misfit_3(planes, n, t_c, table_.data(), samples_, t0, inv_step, dim_dn_, gain_.data(),
                   floor_.data(), error2, static_cast<float>(kMisfitWindow), thresholds_f_.data());
  else
    apply_misfit_any(planes, bands_, n, t_c, table_.data(), samples_, t0, inv_step, dim_dn_,
                     gain_.data(), floor_.data(), error2, static_cast<float>(kMisfitWindow),
                     thresholds_f_.data());
}

}  // namespace pyrocam
