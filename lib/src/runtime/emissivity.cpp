#include "pyrocam/runtime/emissivity.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>

#include "pyrocam/core/error.h"
#include "pyrocam/core/physics.h"
#include "runtime/estimator_kinds.h"

namespace pyrocam {
namespace {

// A slope per 100 nm as the user gives it, %/100 nm.
std::string percent(double alpha) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", alpha * 100);
  return buf;
}

// The step of the table of the method's readings of grey surfaces, degC: a network's error
// changes by up to 1.5 degC over a few degrees.
constexpr double kGreyStepC = 2;
// The central-difference step of dT/d alpha (per 100 nm).
constexpr double kSensitivityStep = 0.005;
// The first guess's locus: its step, degC, and the coarse search's stride in steps.
constexpr double kGuessStepC = 10;
constexpr std::size_t kGuessStride = 5;

}  // namespace

double emissivity_slope_centre_nm(const CameraProfile& p) {
  return 0.5 * (p.filter_pass_band_nm[0] + p.filter_pass_band_nm[1]);
}

void check_emissivity_slope(const CameraProfile& p, double alpha, const char* what) {
  if (!std::isfinite(alpha))
    throw InputError(std::string(what) + " must be a finite number of %/100 nm");
  if (std::abs(alpha) > kMaxEmissivitySlope)
    throw InputError(std::string(what) + " " + percent(alpha) + " %/100 nm is outside -" +
                     percent(kMaxEmissivitySlope) + ".." + percent(kMaxEmissivitySlope));
  const double centre = emissivity_slope_centre_nm(p);
  for (double nm : p.filter_pass_band_nm)
    if (!(1 + alpha * (nm - centre) / 100.0 > 0))
      throw InputError(std::string(what) + " " + percent(alpha) +
                       " %/100 nm makes the emissivity zero or negative within the " + p.name +
                       " filter pass band (" + std::to_string(p.filter_pass_band_nm[0]) + ".." +
                       std::to_string(p.filter_pass_band_nm[1]) + " nm)");
}

Eigen::MatrixXd with_emissivity_slope(const CameraProfile& p, const Eigen::MatrixXd& q,
                                      double alpha) {
  const double centre = emissivity_slope_centre_nm(p);
  Eigen::MatrixXd out = q;
  for (Eigen::Index i = 0; i < p.grid.size(); ++i)
    out.col(i) *= std::max(0.0, 1 + alpha * (p.grid.nm()[i] - centre) / 100.0);
  return out;
}

SpectralEmissivity::SpectralEmissivity(const CameraModel& camera, double alpha, double min_c,
                                       double max_c, double step_c)
    : alpha_(alpha), min_c_(min_c), step_c_(step_c) {
  check_emissivity_slope(camera.profile, alpha);
  if (!(min_c < max_c) || !(step_c > 0) || (max_c - min_c) / step_c > 1e6)
    throw InputError("emissivity factors: the temperature grid must be min < max, step > 0");
  const auto n = static_cast<Eigen::Index>(std::ceil((max_c - min_c) / step_c - 1e-9)) + 1;
  const Eigen::MatrixXd& q = camera.system_qe;
  const Eigen::MatrixXd tilted = with_emissivity_slope(camera.profile, q, alpha);
  factors_.resize(n, q.rows());
  for (Eigen::Index i = 0; i < n; ++i) {
    const double t = std::min(max_c, min_c + static_cast<double>(i) * step_c);
    const Eigen::VectorXd l = weighted_photon_radiance(camera.profile.grid, celsius_to_kelvin(t));
    const Eigen::VectorXd grey = q * l, sloped = tilted * l;
    double largest = 0;
    for (Eigen::Index b = 0; b < q.rows(); ++b) {
      factors_(i, b) = grey[b] > 0 ? sloped[b] / grey[b] : 1.0;
      largest = std::max(largest, factors_(i, b));
    }
    if (largest > 0) factors_.row(i) /= largest;
  }
}

void SpectralEmissivity::factors(double t_c, double* out) const {
  const Eigen::Index last = factors_.rows() - 1;
  const double x = std::isfinite(t_c) ? (t_c - min_c_) / step_c_ : 0.0;
  if (!(x > 0) || last == 0) {
    for (Eigen::Index b = 0; b < factors_.cols(); ++b) out[b] = factors_(0, b);
    return;
  }
  if (x >= static_cast<double>(last)) {
    for (Eigen::Index b = 0; b < factors_.cols(); ++b) out[b] = factors_(last, b);
    return;
  }
  const auto i = static_cast<Eigen::Index>(x);
  const double f = x - static_cast<double>(i);
  for (Eigen::Index b = 0; b < factors_.cols(); ++b)
    out[b] = factors_(i, b) + f * (factors_(i + 1, b) - factors_(i, b));
}

EmissivitySlopeEstimator::EmissivitySlopeEstimator(
    std::shared_ptr<const TemperatureEstimator> inner, double alpha, double alpha_u)
    : TemperatureEstimator(inner ? inner->shared_model() : nullptr),
      inner_(std::move(inner)),
      emissivity_(model_->camera, alpha, model_->min_temperature_c, model_->max_temperature_c),
      alpha_u_(alpha_u),
      reference_c_(0.5 * (model_->min_temperature_c + model_->max_temperature_c)),
      systematic_(model_->uncertainty) {
  const UncertaintyModel& u = model_->uncertainty;
  if (std::isnan(alpha_u) || alpha_u > 1)
    throw InputError("e-slope-uncertainty " + percent(alpha_u) +
                     " %/100 nm is outside 0..100 (or negative for the model's)");
  if (alpha_u_ < 0) alpha_u_ = u.emissivity_slope_u;
  std::vector<double>& table = systematic_.u_emissivity_c;
  if (alpha == 0 && u.emissivity_slope_u > 0 && table.size() == u.temperature_c.size()) {
    for (double& v : table) v *= alpha_u_ / u.emissivity_slope_u;
    return;
  }
  // dT/d alpha at this slope: corrected readings of surfaces with alpha +- h.
  const CameraModel& cam = model_->camera;
  const CameraModel up{cam.profile,
                       with_emissivity_slope(cam.profile, cam.system_qe, alpha + kSensitivityStep),
                       cam.band_scale},
      down{cam.profile, with_emissivity_slope(cam.profile, cam.system_qe, alpha - kSensitivityStep),
           cam.band_scale};
  // Noise-free signals, the dimmest band well above the dim threshold.
  const auto signals = [&](const CameraModel& c, double t) {
    Eigen::VectorXd s = c.rates(t);
    const double dimmest = s.minCoeff();
    if (!(dimmest > 0)) return Eigen::VectorXd();
    return Eigen::VectorXd(s * (100 * std::max(dim_dn_, 1.0) / dimmest));
  };
  make_guess_locus(CameraModel{
      cam.profile, with_emissivity_slope(cam.profile, cam.system_qe, alpha), cam.band_scale});
  // The method's own readings of grey surfaces across the range.
  for (double t = model_->min_temperature_c; t <= model_->max_temperature_c; t += kGreyStepC) {
    const Eigen::VectorXd s = signals(cam, t);
    const double r = s.size() ? inner_->temperature_c(s.data()) : static_cast<double>(NAN);
    if (!std::isfinite(r)) continue;
    if (!grey_read_c_.empty() && !(r > grey_read_c_.back())) {
      grey_c_.clear(), grey_read_c_.clear();  // not monotonic: readings as they are
      break;
    }
    grey_c_.push_back(t);
    grey_read_c_.push_back(r);
  }
  const auto read = [&](const CameraModel& c, double t) {
    const Eigen::VectorXd s = signals(c, t);
    return s.size() ? temperature_c(s.data()) : static_cast<double>(NAN);
  };
  table.assign(u.temperature_c.size(), 0.0);
  for (std::size_t i = 0; i < table.size(); ++i) {
    const double t = u.temperature_c[i];
    const double hi = read(up, t), lo = read(down, t);
    double slope = NAN;
    if (std::isfinite(hi) && std::isfinite(lo)) slope = (hi - lo) / (2 * kSensitivityStep);
    // At the range ends one side may read outside the range: the other side and the truth.
    else if (std::isfinite(hi))
      slope = (hi - t) / kSensitivityStep;
    else if (std::isfinite(lo))
      slope = (t - lo) / kSensitivityStep;
    table[i] = std::isfinite(slope) ? std::abs(slope) * alpha_u_ : 0.0;
  }
}

void EmissivitySlopeEstimator::corrected_signals(const double* s, double t_c, double* out) const {
  double f[kMaxBands];
  emissivity_.factors(t_c, f);
  for (int b = 0; b < bands_; ++b) out[b] = std::isfinite(s[b]) && s[b] > 0 ? s[b] / f[b] : s[b];
}

double EmissivitySlopeEstimator::as_grey_c(double read_c) const {
  if (grey_c_.size() < 2 || !std::isfinite(read_c)) return read_c;
  const auto above = std::upper_bound(grey_read_c_.begin(), grey_read_c_.end(), read_c);
  const std::size_t i = std::clamp<std::size_t>(
      static_cast<std::size_t>(above - grey_read_c_.begin()), 1, grey_c_.size() - 1);
  if (above == grey_read_c_.begin() || above == grey_read_c_.end()) {
    // Beyond the table: the error at its end.
    const std::size_t end = above == grey_read_c_.begin() ? 0 : grey_c_.size() - 1;
    return read_c - (grey_read_c_[end] - grey_c_[end]);
  }
  const double f = (read_c - grey_read_c_[i - 1]) / (grey_read_c_[i] - grey_read_c_[i - 1]);
  return grey_c_[i - 1] + f * (grey_c_[i] - grey_c_[i - 1]);
}

void EmissivitySlopeEstimator::make_guess_locus(const CameraModel& sloped) {
  const double lo = model_->min_temperature_c, hi = model_->max_temperature_c;
  for (double t = lo; t < hi + kGuessStepC; t += kGuessStepC) {
    guess_c_.push_back(std::min(t, hi));
    const Eigen::VectorXd r = sloped.rates(guess_c_.back());
    for (int b = 0; b < bands_; ++b) guess_log_rates_.push_back(r[b] > 0 ? std::log(r[b]) : NAN);
  }
}

double EmissivitySlopeEstimator::first_guess_c(const double* s) const {
  double x[kMaxBands], w[kMaxBands];
  int used[kMaxBands], n = 0;
  for (int b = 0; b < bands_; ++b)
    if (std::isfinite(s[b]) && s[b] > 0) {
      x[n] = std::log(s[b]);
      // Shot noise: a band's log has a variance about inverse to its signal.
      w[n] = std::max(s[b], std::max(dim_dn_, 1.0));
      used[n++] = b;
    }
  if (n < 2) return reference_c_;
  // The weighted spread of the log differences about their mean (the scale is free).
  const auto distance = [&](std::size_t i) {
    const double* l = &guess_log_rates_[i * static_cast<std::size_t>(bands_)];
    double sw = 0, swd = 0, swdd = 0;
    for (int k = 0; k < n; ++k) {
      const double d = x[k] - l[used[k]];
      sw += w[k];
      swd += w[k] * d;
      swdd += w[k] * d * d;
    }
    const double spread = swdd - swd * swd / sw;
    return std::isfinite(spread) ? spread : INFINITY;
  };
  const std::size_t count = guess_c_.size();
  std::size_t best = count;
  double best_distance = INFINITY;
  const auto consider = [&](std::size_t i) {
    const double d = distance(i);
    if (d < best_distance) {
      best = i;
      best_distance = d;
    }
  };
  for (std::size_t i = 0; i < count; i += kGuessStride) consider(i);
  consider(count - 1);
  if (best == count) return reference_c_;
  const std::size_t coarse = best;
  for (std::size_t i = coarse > kGuessStride ? coarse - kGuessStride : 0;
       i <= std::min(count - 1, coarse + kGuessStride); ++i)
    consider(i);
  // Between the table's samples: the vertex of the parabola through the best and its neighbours.
  if (best == 0 || best + 1 >= count) return guess_c_[best];
  const double below = distance(best - 1), above = distance(best + 1);
  const double curvature = below - 2 * best_distance + above;
  if (!(curvature > 0)) return guess_c_[best];
  const double offset = std::clamp(0.5 * (below - above) / curvature, -1.0, 1.0);
  return guess_c_[best] + offset * (guess_c_[best + 1] - guess_c_[best]);
}

double EmissivitySlopeEstimator::corrected_temperature_c(const double* s, int* passes) const {
  if (passes) *passes = 1;
  if (alpha() == 0) return inner_->temperature_c(s);
  double c[kMaxBands];
  int n = 0;
  const double start = first_guess_c(s);
  // g(t): the reading of the signals corrected with the factors at t; the answer is g's fixed
  // point. Where the factors change fast with temperature (a colour camera's blue with its
  // near-infrared leak, cold) plain iteration oscillates: the secant method on g(t) - t.
  const auto g = [&](double t) {
    corrected_signals(s, t, c);
    ++n;
    if (passes) *passes = n;
    return as_grey_c(inner_->temperature_c(c));
  };
  double x0 = g(start);
  if (!std::isfinite(x0)) return NAN;  // no reading at the guess: the method's decision
  // A self-consistent reading far from the first guess is a wrong one, and where the method finds
  // none the guess reads too (the method reads the pixel: its bands are not dim or saturated).
  const double kelvin_ratio = celsius_to_kelvin(start) / kEmissivityGuessReferenceK;
  const double agree_c = kEmissivityGuessAgreeC * kelvin_ratio * kelvin_ratio;
  const double guess = in_range(start);
  double g0 = g(x0);
  double x1 = g0;
  double best = g0, best_h = std::abs(g0 - x0);  // the most self-consistent reading so far
  while (std::isfinite(g0) && std::abs(g0 - x0) > kEmissivitySlopeToleranceC) {
    if (std::abs(g0 - x0) < best_h) {
      best = g0;
      best_h = std::abs(g0 - x0);
    }
    // No settled reading (a network's kinks can leave g(t) - t short of 0): the best one when
    // it is consistent to kEmissivitySlopeAcceptC, else the guess.
    if (n >= kEmissivitySlopeMaxPasses) {
      if (!(best_h <= kEmissivitySlopeAcceptC)) return guess;
      g0 = best;
      break;
    }
    const double g1 = g(x1);
    if (!std::isfinite(g1)) return guess;
    const double h0 = g0 - x0, h1 = g1 - x1;
    const double x2 = h1 != h0 ? x1 - h1 * (x1 - x0) / (h1 - h0) : g1;
    x0 = x1;
    g0 = g1;
    // A step off the model's range (where the factors stop changing) falls back to g.
    const bool usable = std::isfinite(x2) && x2 >= model_->min_temperature_c - 100 &&
                        x2 <= model_->max_temperature_c + 100;
    x1 = usable ? x2 : g1;
  }
  if (!std::isfinite(g0) || !(std::abs(g0 - start) <= agree_c)) return guess;
  return g0;
}

double EmissivitySlopeEstimator::temperature_c(const double* s) const {
  return corrected_temperature_c(s, nullptr);
}

void EmissivitySlopeEstimator::estimate(const float* const* planes, std::size_t n,
                                        float* out) const {
  if (alpha() == 0)
    inner_->estimate(planes, n, out);
  else
    TemperatureEstimator::estimate(planes, n, out);
}

double EmissivitySlopeEstimator::systematic_u_c(double t_c) const {
  return systematic_.systematic_u_c(t_c);
}

double EmissivitySlopeEstimator::emissivity_u_c(double t_c) const {
  UncertaintyModel only = systematic_;
  only.u_calibration_c.assign(only.u_calibration_c.size(), 0.0);
  only.u_qe_model_c.clear();
  return only.systematic_u_c(t_c);
}

}  // namespace pyrocam
