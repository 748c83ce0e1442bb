#include "pyrocam/calibration/extrapolation_study.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "detail/random.h"
#include "pyrocam/runtime/estimators.h"

namespace pyrocam {
namespace {

// Whether a sweep puts at least two exposures of a band between the dim and saturation
// thresholds, as rate extraction needs.
bool sweep_usable(const CameraProfile& profile, double rate_dn_per_s,
                  const std::vector<double>& exposures_us) {
  const double dim = profile.thresholds.calibration_dim_dn;
  const double full = profile.thresholds.calibration_saturation_dn - profile.dark_offset_dn;
  int points = 0;
  for (double e : exposures_us) {
    const double dn = rate_dn_per_s * e * 1e-6;
    points += dn >= dim && dn <= full;
  }
  return points >= 2;
}

std::vector<double> sweep(double first_us, double factor, int count) {
  std::vector<double> e;
  for (int k = 0; k < count; ++k) e.push_back(first_us * std::pow(factor, k));
  return e;
}

}  // namespace

CalibrationRates simulate_calibration_rates(const CameraProfile& profile,
                                            const Eigen::MatrixXd& true_qe, const RateCampaign& c) {
  const bool colour = profile.band_count() <= 4;
  std::vector<double> temps = c.temperatures_c;
  if (temps.empty())
    for (double t = colour ? 700 : 800; t <= 1100 + 1e-9; t += 10) temps.push_back(t);
  const std::vector<double> exposures =
      sweep(c.first_exposure_us > 0 ? c.first_exposure_us : (colour ? 100 : 10000),
            c.exposure_factor, c.exposure_count);
  Random rng(mix(c.seed ^ 0x2A7E5ull));
  CalibrationRates data{
      temps, Eigen::MatrixXd(profile.band_count(), static_cast<Eigen::Index>(temps.size())), {}};
  for (std::size_t i = 0; i < temps.size(); ++i) {
    const double truth = temps[i] + c.furnace_error_sigma_c * rng.normal();
    const Eigen::VectorXd r = signal_rates(profile, true_qe, celsius_to_kelvin(truth));
    for (int b = 0; b < profile.band_count(); ++b)
      data.rates(b, static_cast<Eigen::Index>(i)) =
          sweep_usable(profile, r[b], exposures) ? r[b] * (1 + c.relative_noise * rng.normal())
                                                 : NAN;
  }
  for (double t : c.reference_temperatures_c) {
    const double truth = t + c.reference_uncertainty_c * rng.normal();
    const double scale = rng.uniform(0.05, 0.5);  // aperture, distance: unknown to the fit
    const Eigen::VectorXd r = scale * signal_rates(profile, true_qe, celsius_to_kelvin(truth));
    // Its own sweep, starting where the brightest band is near the dim threshold.
    const double first_us =
        1e6 * profile.thresholds.calibration_dim_dn / std::max(r.maxCoeff(), 1e-300);
    const std::vector<double> own = sweep(first_us, c.exposure_factor, c.exposure_count);
    ReferenceRates ref;
    ref.name = "reference " + std::to_string(static_cast<int>(std::lround(t))) + " degC";
    ref.temperature_c = t;
    ref.temperature_uncertainty_c = c.reference_uncertainty_c;
    ref.rates.resize(profile.band_count());
    for (int b = 0; b < profile.band_count(); ++b)
      ref.rates[b] =
          sweep_usable(profile, r[b], own) ? r[b] * (1 + c.relative_noise * rng.normal()) : NAN;
    data.references.push_back(ref);
  }
  return data;
}

std::vector<double> extrapolation_errors(const CameraProfile& profile,
                                         const Eigen::MatrixXd& true_qe, const CameraModel& fitted,
                                         const std::vector<double>& temperatures_c,
                                         double calibrated_up_to_c) {
  auto model = std::make_shared<ThermalModel>();
  model->camera = fitted;
  model->datasheet_qe = profile.system_qe();
  model->min_temperature_c = 400;
  model->max_temperature_c = 3600;
  model->calibrated_up_to_c = calibrated_up_to_c;
  const auto estimator = make_estimator(model, Method::kLikelihood);
  std::vector<double> errors;
  for (double t : temperatures_c) {
    Eigen::VectorXd s = signal_rates(profile, true_qe, celsius_to_kelvin(t));
    s *= 150.0 / s.maxCoeff();  // a well exposed frame, DN
    errors.push_back(estimator->temperature_c(s.data()) - t);
  }
  return errors;
}

double hottest_calibrated_c(const CalibrationRates& data) {
  double hottest = -std::numeric_limits<double>::infinity();
  for (double t : data.temperatures_c) hottest = std::max(hottest, t);
  for (const ReferenceRates& r : data.references) hottest = std::max(hottest, r.temperature_c);
  return std::isfinite(hottest) ? hottest : NAN;
}

}  // namespace pyrocam
