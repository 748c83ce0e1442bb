// Surfaces that are not grey: a linear spectral emissivity slope (what two-colour pyrometers call
// e-slope) that the band ratios do not cancel, and reading such a surface with any estimator.
//
// eps(lambda) = 1 + alpha (lambda - centre) / 100 nm, centre the middle of the profile's filter
// pass band; alpha = 0.01 is a slope of 1 % per 100 nm, positive when the emissivity rises with
// wavelength. A grey surface (alpha = 0) reads exactly as without this file.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <vector>

#include "pyrocam/core/locus.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

// The steepest slope accepted, per 100 nm (50 %/100 nm).
inline constexpr double kMaxEmissivitySlope = 0.5;
// The corrected reading stops when a pass moves it by at most this, degC ...
inline constexpr double kEmissivitySlopeToleranceC = 1e-3;
// ... or after this many readings of the inner estimator (the first included).
inline constexpr int kEmissivitySlopeMaxPasses = 12;
// ... when it did not settle, the reading whose corrected signals read closest to it, if that is
// within this, degC; else the first guess (below).
inline constexpr double kEmissivitySlopeAcceptC = 0.5;
// A settled reading further than this from the first guess (degC at kEmissivityGuessReferenceK,
// growing as the square of the absolute temperature, as a ratio reading's noise does) is not
// trusted, and the first guess is the reading.
inline constexpr double kEmissivityGuessAgreeC = 15;
inline constexpr double kEmissivityGuessReferenceK = 1500;

// The wavelength the slope pivots on: the middle of the profile's filter pass band, nm.
double emissivity_slope_centre_nm(const CameraProfile& p);

// Throws InputError unless alpha is finite, |alpha| <= kMaxEmissivitySlope and the emissivity
// stays positive over the profile's filter pass band (the light the camera sees; outside it
// with_emissivity_slope clamps at 0). `what` names the setting in the message.
void check_emissivity_slope(const CameraProfile& p, double alpha, const char* what = "e-slope");

// The spectral emissivity folded into a system QE (bands x wavelengths on p's grid): every
// column times max(0, 1 + alpha (lambda - centre) / 100 nm). Not checked.
Eigen::MatrixXd with_emissivity_slope(const CameraProfile& p, const Eigen::MatrixXd& q,
                                      double alpha);

// Per band, the factor a slope multiplies a graybody's signal by, eps_eff_b(T) = integral(Q_b eps
// L(T)) / integral(Q_b L(T)), on a temperature grid (precomputed from the camera's system QE),
// divided by the largest band's at each temperature: the estimators fit or cancel the scale, and
// a signal divided by its factor is never smaller (a band above the dim threshold stays above).
class SpectralEmissivity {
 public:
  // Every step_c degC from min_c to max_c (and max_c). Throws InputError for a slope
  // check_emissivity_slope refuses, or a grid that is not min_c < max_c, step_c > 0.
  SpectralEmissivity(const CameraModel& camera, double alpha, double min_c, double max_c,
                     double step_c = 2);
  double alpha() const { return alpha_; }
  int bands() const { return static_cast<int>(factors_.cols()); }
  // The factors at t_c (linear between grid samples, the end samples outside), bands() values.
  void factors(double t_c, double* out) const;
  std::size_t memory_bytes() const {
    return static_cast<std::size_t>(factors_.size()) * sizeof(double);
  }

 private:
  double alpha_, min_c_, step_c_;
  Eigen::MatrixXd factors_;  // grid samples x bands
};

// Reads a surface whose emissivity has the slope alpha with any estimator: reads the signals
// divided by the factors at a first guess, then divided by the factors at that reading, and so
// on (secant steps on the reading's change) until the reading of the signals corrected at a
// temperature is that temperature within kEmissivitySlopeToleranceC (at most
// kEmissivitySlopeMaxPasses readings, then kEmissivitySlopeAcceptC). The answer is a fixed point,
// and there may be others where the inner estimator reads signals far off its locus (a network
// reads them as anything): the first guess is the temperature of the nearest point of the locus
// of surfaces with this slope (tabulated; the bands that read, in logs, the scale free). Started
// at the middle of the range, the colour test model's likelihood fit at -50 %/100 nm settled at
// 1262 degC for a 520 degC surface, its network at -40 %/100 nm at 669 degC, and readings near
// the range's ends were lost, their first pass reading outside it. (A band pair's ratio cannot
// serve: on a colour camera with near-infrared leaks none is monotonic.) Noisy signals can still
// settle on a wrong fixed point: a colour camera at -30 %/100 nm, 1200 degC, 1 DN of noise on
// 150 DN, read from 168 degC low to 96 degC high (10th-90th percentile; the likelihood fit),
// where the first guess, itself a fit to the sloped surfaces' locus (refined between the table's
// samples), reads within about 20 degC, and a third of the pixels found no settled reading. So
// a settled reading further from the guess than kEmissivityGuessAgreeC (scaled), or none, gives
// way to the guess where the method reads the signals corrected at it: there -18 to +19 degC,
// every pixel read; where the two agree, as on every noise-free surface, the reading is the
// method's.
// Bands below the dim threshold, saturated or without a reading pass as they are, so the no-reading
// decisions are the inner estimator's (allow-partial included: set it on the inner estimator). With
// alpha = 0 the readings are the inner estimator's, bit for bit.
//
// The systematic uncertainty (expanded_uncertainty_c) then has the emissivity term |dT/d alpha|
// u(alpha) at the chosen slope: alpha_u (per 100 nm), or with alpha_u < 0 the model's
// UncertaintyModel::emissivity_slope_u. At alpha = 0 that is the model's own table (scaled by
// alpha_u / emissivity_slope_u); elsewhere dT/d alpha is a central difference (alpha +-
// 0.005) of corrected readings of noise-free graybody signals of the model's camera at every
// temperature of the model's table.
class EmissivitySlopeEstimator final : public TemperatureEstimator {
 public:
  // Throws InputError for a slope check_emissivity_slope refuses, or alpha_u above 1 or NaN.
  EmissivitySlopeEstimator(std::shared_ptr<const TemperatureEstimator> inner, double alpha,
                           double alpha_u = -1);

  double temperature_c(const double* signals) const override;
  // alpha = 0: the inner estimator's batch, bit for bit.
  void estimate(const float* const* planes, std::size_t n, float* out_c) const override;
  // The same, and how many readings of the inner estimator it took (`passes`, may be null).
  double corrected_temperature_c(const double* signals, int* passes) const;
  // The signals a grey surface at t_c would give: each band that reads divided by its factor.
  void corrected_signals(const double* signals, double t_c, double* out) const;
  // Calibration and emissivity terms at t_c, standard uncertainty, degC.
  double systematic_u_c(double t_c) const override;
  // The emissivity term alone, |dT/d alpha| u(alpha), degC.
  double emissivity_u_c(double t_c) const;

  double alpha() const { return emissivity_.alpha(); }
  double alpha_u() const { return alpha_u_; }
  const TemperatureEstimator& inner() const { return *inner_; }
  std::size_t memory_bytes() const override {
    return inner_->memory_bytes() + emissivity_.memory_bytes();
  }

 private:
  std::shared_ptr<const TemperatureEstimator> inner_;
  SpectralEmissivity emissivity_;
  double alpha_u_;
  // The locus of surfaces with this slope: temperatures and, per temperature, the log of each
  // band's signal (scale free), every kGuessStepC.
  void make_guess_locus(const CameraModel& sloped);
  // The first guess: the temperature of the point of that locus nearest to the signals (their
  // bands that read; logs weighted by the signal, as shot noise; a coarse search, then a fine one
  // about its best, then the vertex of a parabola through it and its neighbours); reference_c_
  // where fewer than two bands read.
  double first_guess_c(const double* signals) const;
  double reference_c_;  // the middle of the model's range
  std::vector<double> guess_c_, guess_log_rates_;
  // The inner method's readings of noise-free grey surfaces (grey_read_c_) at temperatures
  // grey_c_ across the model's range, rising (else empty). The signals corrected at the true
  // temperature are a grey surface's, and the answer is the fixed point of reading them: where
  // the factors change fast with temperature (the colour camera's blue, cold) it multiplies the
  // method's own error (a network's 0.5 degC at 1100 degC read 7 degC off at -30 %/100 nm). Each
  // reading of corrected signals is therefore taken as the grey surface's that reads so.
  std::vector<double> grey_c_, grey_read_c_;
  double as_grey_c(double read_c) const;
  UncertaintyModel systematic_;  // the model's, with the emissivity term at this slope
};

}  // namespace pyrocam
