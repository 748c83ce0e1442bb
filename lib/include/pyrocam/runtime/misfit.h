// Band-consistency (misfit) check after any estimator (METHOD.md section 5): a pixel's band
// signals must be those of a graybody at the temperature read from them. Pixels whose bands come
// from different temperatures (mixed pixels at sharp edges after demosaicking, reflections)
// still give every estimator some temperature, often far off; the check drops those readings.
//
// For signals s_b (DN, dark subtracted) and an estimate T, the best graybody at T is a m_b(T)
// with m_b the model camera's locus rates and the scale a profiled out:
//   chi2 = sum_b w_b (s_b - a m_b(T))^2,  a = sum w s m / sum w m^2,
//   1 / w_b = signal_variance_dn2(profile, b, s_b) + (model_error * s_b)^2.
// The model-error term keeps bright pixels (tiny relative noise) from being dropped for the
// model's own imperfection (calibration residuals of about 1 %, demosaicking of smooth
// gradients): kDefaultMisfitModelError = 2 % of the signal per band, independent between bands.
// The estimate need not be the chi2 minimum (the network and its table read noisy pixels a little
// off the fit): chi2 is taken at the best temperature within kMisfitWindow (1 %) of the
// estimate's absolute temperature, by one Gauss-Newton step along the locus from it, so the
// false-rejection probability holds for every method; a reading further than that from any
// graybody that fits is dropped.
// Bands without a reading (dim, saturated, NaN) do not count. With v counted bands the statistic
// has v - 2 degrees of freedom (temperature and scale fitted): a colour camera has 1, a 5x5
// camera 23; with fewer than 3 counted bands nothing can be checked and the reading stays. A
// reading is dropped when chi2 exceeds the chi-squared quantile of the chosen false-rejection
// probability (the chance that a graybody pixel with noise as modelled is dropped).
#pragma once

#include <cstddef>
#include <memory>
#include <vector>

#include "pyrocam/runtime/model.h"

namespace pyrocam {

// A false-rejection probability for when the check is on (the check is off by default: see
// docs/elements.md, ratiotemp misfit-probability, for what it can and cannot catch).
inline constexpr double kTypicalMisfitProbability = 1e-6;
inline constexpr double kDefaultMisfitModelError = 0.02;
inline constexpr double kMisfitWindow = 0.01;  // of the absolute temperature

// Upper-tail chi-squared quantile: x with P(chi2_dof > x) = probability (0 < probability < 1,
// dof >= 1). Throws InputError outside those ranges.
double chi2_upper_quantile(int dof, double probability);
// P(chi2_dof > x), the regularised upper incomplete gamma Q(dof/2, x/2).
double chi2_upper_tail(int dof, double x);

class MisfitCheck {
 public:
  // probability 0 disables the check; otherwise 0 < probability < 1 (InputError outside).
  // model_error: relative, >= 0. Shares the model; throws InputError without one.
  explicit MisfitCheck(std::shared_ptr<const ThermalModel> model,
                       double probability = kTypicalMisfitProbability,
                       double model_error = kDefaultMisfitModelError);

  void set_probability(double probability);
  double probability() const { return probability_; }
  bool enabled() const { return probability_ > 0; }
  double model_error() const { return model_error_; }
  // The signals' noise at an analogue gain factor (TemperatureEstimator::set_analogue_gain);
  // 1 by default. Not while a check runs. Throws InputError unless positive.
  void set_analogue_gain(double factor);
  double analogue_gain() const { return analogue_gain_; }

  // chi2 of one pixel at the best temperature within the window around t_c (double precision,
  // the definition); *counted = bands that count; *rate_scale = the scale a of the graybody
  // that fits at t_c, s_b ~ a r_b(T) with r_b the model's rates (DN/s at emissivity 1): the
  // emissivity times the exposure in seconds times the analogue gain factor.
  // NaN for t_c outside the model's range or no counted band.
  double chi2(const double* signals, double t_c, int* counted = nullptr,
              double* rate_scale = nullptr) const;
  // The rejection threshold for `counted` bands (+inf below 3 bands or when disabled).
  double threshold(int counted) const;

  // Band-planar batch (planes[b][i], i < n, DN): sets t_c[i] to NaN where the bands do not fit
  // the reading. NaN readings stay NaN. Does nothing when disabled.
  void apply(const float* const* planes, std::size_t n, float* t_c) const;

 private:
  std::shared_ptr<const ThermalModel> model_;  // never null
  int bands_;
  double probability_ = 0, model_error_;
  double analogue_gain_ = 1.0;
  float dim_dn_;
  double t0_c_, step_c_;
  int samples_;
  std::vector<float> table_;  // bands x samples, each sample's rates scaled to unit length
  std::vector<double> table_d_;
  std::vector<double> norm_;         // per sample, the length table_ divided its rates by
  std::vector<float> gain_, floor_;  // variance = gain s + floor + (model_error s)^2
  std::vector<float> thresholds_f_;  // by counted bands, 0 .. bands
  std::vector<double> thresholds_;
};

}  // namespace pyrocam
