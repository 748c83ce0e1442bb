#include "pyrocam/calibration/calibration_uncertainty.h"

#include <algorithm>
#include <cmath>

#include "calibration/stage_support.h"
#include "detail/random.h"
#include "pyrocam/calibration/baselines.h"
#include "pyrocam/calibration/qe_fit.h"
#include "pyrocam/runtime/estimators.h"

namespace pyrocam {

using calibration_detail::report_stage;

namespace {

// The brightest band of a well exposed pixel, DN (as extrapolation_errors exposes).
constexpr double kWellExposedDn = 150;

// What a prior fit's reading change is worth as a term: it changes sign where the fit's curve
// crosses the nominal one, and an accident of that crossing is no knowledge. So the term never
// shrinks going away from the temperature where it is least (the furnace range, where the data
// hold every fit; sought at or below `hottest`, the furnace's top, where any is): at each
// temperature the largest value between there and it. NaN (no reading there) neither counts
// nor changes.
void outward_envelope(const std::vector<double>& temperatures_c, std::vector<double>& term,
                      double hottest) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < term.size(); ++i)
    if (std::isfinite(term[i])) order.push_back(i);
  if (order.empty()) return;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return temperatures_c[a] < temperatures_c[b]; });
  // Sorted: the candidates are a prefix.
  auto end = std::find_if(order.begin(), order.end(),
                          [&](std::size_t i) { return temperatures_c[i] > hottest; });
  if (end == order.begin()) end = order.end();
  const auto least =
      std::min_element(order.begin(), end,
                       [&](std::size_t a, std::size_t b) { return term[a] < term[b]; }) -
      order.begin();
  for (std::ptrdiff_t k = least + 1; k < static_cast<std::ptrdiff_t>(order.size()); ++k)
    term[order[k]] = std::max(term[order[k]], term[order[k - 1]]);
  for (std::ptrdiff_t k = least - 1; k >= 0; --k)
    term[order[k]] = std::max(term[order[k]], term[order[k + 1]]);
}

}  // namespace

std::vector<double> qe_model_uncertainty(const CameraModel& fitted,
                                         const std::vector<QeSample>& posterior,
                                         const std::vector<double>& temperatures_c,
                                         const std::vector<QeSample>& prior_fits,
                                         double hottest_calibrated_c, double calibrated_up_to_c,
                                         double range_top_c) {
  std::vector<double> u;
  if (posterior.size() < 2) return u;
  const double lo = *std::min_element(temperatures_c.begin(), temperatures_c.end());
  const double hi = *std::max_element(temperatures_c.begin(), temperatures_c.end());
  // Read as the live chain reads: the likelihood fit of a well exposed pixel, so that a band too
  // dim to be read at a temperature does not count there (nor does its uncertainty).
  auto model = std::make_shared<ThermalModel>();
  model->camera = fitted;
  model->datasheet_qe = fitted.profile.system_qe();
  model->min_temperature_c = lo - 300;
  model->max_temperature_c = hi + 300;
  model->calibrated_up_to_c = calibrated_up_to_c;
  model->pair_top_c = range_top_c;
  const auto reader = make_estimator(model, Method::kLikelihood);
  const auto read = [&](const CameraModel& camera, double t) {
    Eigen::VectorXd s = camera.rates(t);
    s *= kWellExposedDn / s.maxCoeff();
    return reader->temperature_c(s.data());
  };
  std::vector<double> spread, prior;
  for (double t : temperatures_c) {
    const double nominal = read(fitted, t);
    double sum = 0, sum2 = 0;
    int n = 0;
    for (const QeSample& s : posterior) {
      const double d = read(CameraModel{fitted.profile, s.system_qe, s.gains}, t) - nominal;
      if (!std::isfinite(d)) continue;
      sum += d, sum2 += d * d, ++n;
    }
    const double mean = n > 0 ? sum / n : 0;
    spread.push_back(n > 1 ? std::sqrt(std::max(0.0, (sum2 - n * mean * mean) / (n - 1))) : NAN);
    prior.push_back(std::isfinite(nominal) ? 0.0 : NAN);
    for (const QeSample& s : prior_fits) {
      const double d = read(CameraModel{fitted.profile, s.system_qe, s.gains}, t) - nominal;
      if (std::isfinite(d)) prior.back() = std::max(prior.back(), std::abs(d));
    }
  }
  outward_envelope(temperatures_c, prior, hottest_calibrated_c);
  for (std::size_t i = 0; i < spread.size(); ++i) u.push_back(std::hypot(spread[i], prior[i]));
  // The samples' readings pivot too, about as the furnace's top holds them (hostile colour
  // unit 1: a spread of 1.08 degC at 1100 degC, 0.86 at 1200), and a pivot is no knowledge.
  outward_envelope(temperatures_c, u, hottest_calibrated_c);
  // Where no sample reads (the cold end of a 5x5 model's range, where some band is dim even in
  // a well exposed pixel) the nearest temperature's value: a model holds a number at every
  // temperature of its table (a NaN would make it unreadable), and pixels read there from
  // their other bands still have this term. None at all: no term.
  std::vector<double> filled = u;
  bool any = false;
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (std::isfinite(u[i])) {
      any = true;
      continue;
    }
    for (std::size_t d = 1; d < u.size(); ++d) {
      const double below = i >= d ? u[i - d] : NAN, above = i + d < u.size() ? u[i + d] : NAN;
      if (std::isfinite(below) || std::isfinite(above)) {
        filled[i] = std::isfinite(below) && std::isfinite(above) ? std::max(below, above)
                    : std::isfinite(below)                       ? below
                                                                 : above;
        break;
      }
    }
  }
  return any ? filled : std::vector<double>{};
}

std::vector<double> emissivity_uncertainty(const ThermalModel& m, const UncertaintyModel& u) {
  const CameraProfile& profile = m.profile();
  // Both signs of the slope: at an end of the range the reading one of them implies lies
  // outside it, where the network cannot follow, and that shift alone would read as none.
  std::vector<CameraModel> tilted;
  for (double slope : {u.emissivity_slope_u, -u.emissivity_slope_u})
    tilted.push_back(CameraModel{profile, with_emissivity_slope(profile, m.camera.system_qe, slope),
                                 m.camera.band_scale});
  std::vector<double> u_emissivity_c;
  for (double t : u.temperature_c) {
    // Against the network's reading of the grey body, not t: the network's own error on the
    // locus (the calibration summary's locus_rms_error_c) is no emissivity effect; counted here
    // it widened the term by its full size over the two signs, |A| + |f|.
    const Eigen::VectorXd grey = normalised_ratios(profile.normalisation, m.camera.rates(t));
    const double grey_c = m.mlp.predict(grey.data());
    double largest = 0;
    for (const CameraModel& camera : tilted) {
      const Eigen::VectorXd x = normalised_ratios(profile.normalisation, camera.rates(t));
      largest = std::max(largest, std::abs(m.mlp.predict(x.data()) - grey_c));
    }
    u_emissivity_c.push_back(largest);
  }
  return u_emissivity_c;
}

std::vector<double> thermocouple_uncertainty(const ThermalModel& m, const UncertaintyModel& u,
                                             const std::vector<double>& t_c,
                                             const Eigen::MatrixXd& rates, std::uint64_t seed,
                                             const StageProgress& progress,
                                             const std::vector<ReferenceRates>& references,
                                             const QeFitChoices& fit_choices) {
  std::vector<std::vector<double>> refit_t(u.temperature_c.size());
  Random rng(seed ^ 0x7C0FFEEull);
  Random reference_rng(seed ^ 0x8EFE8E4CEull);
  const auto reference_error = [](Random& r) { return r.normal(); };
  const auto tc_error = [&](Random& r) {
    return r.uniform(-u.thermocouple_tolerance_c, u.thermocouple_tolerance_c);
  };
  // A thermocouple's deviation from its reference function is one smooth curve over the
  // campaign, not a new error at each step (the furnace's own scatter from step to step is what
  // the QE fit's temperature offsets take up): each refit moves the furnace temperatures by a
  // deviation linear in temperature, drawn within the tolerance at the coldest and the hottest.
  const auto [coldest, hottest] = std::minmax_element(t_c.begin(), t_c.end());
  const double t_lo = t_c.empty() ? 0 : *coldest, t_hi = t_c.empty() ? 0 : *hottest;
  for (int k = 0; k < u.monte_carlo_refits; ++k) {
    report_stage(progress, "Monte-Carlo refits", static_cast<std::size_t>(k),
                 static_cast<std::size_t>(u.monte_carlo_refits));
    const double at_lo = tc_error(rng), at_hi = tc_error(rng);
    std::vector<double> t_perturbed = t_c;
    for (double& t : t_perturbed)
      t += t_hi > t_lo ? at_lo + (at_hi - at_lo) * (t - t_lo) / (t_hi - t_lo) : at_lo;
    std::vector<ReferenceRates> references_perturbed = references;
    for (ReferenceRates& r : references_perturbed)
      r.temperature_c += r.temperature_uncertainty_c * reference_error(reference_rng);
    QeFitOptions qo;
    qo.solver = m.qe_solver == "paper" ? QeSolver::kPaper : QeSolver::kRegularised;
    qo = with_fit_choices(qo, fit_choices);
    const QeFitResult fit = fit_qe(
        m.profile(), CalibrationRates{t_perturbed, rates.transpose(), references_perturbed}, qo);
    const CameraModel cam{m.profile(), fit.system_qe, fit.gains};
    const OhnoEstimator inv(
        make_locus(cam, m.min_temperature_c - 100, m.max_temperature_c + 100, 1));
    for (std::size_t i = 0; i < u.temperature_c.size(); ++i)
      refit_t[i].push_back(inv.temperature_c(m.camera.rates(u.temperature_c[i])));
  }
  report_stage(progress, "Monte-Carlo refits", static_cast<std::size_t>(u.monte_carlo_refits),
               static_cast<std::size_t>(u.monte_carlo_refits));
  std::vector<double> u_calibration_c;
  for (std::size_t i = 0; i < u.temperature_c.size(); ++i) {
    double mean = 0, var = 0;
    const auto& v = refit_t[i];
    for (double x : v) mean += x;
    if (!v.empty()) mean /= static_cast<double>(v.size());
    for (double x : v) var += (x - mean) * (x - mean);
    // With no refits the thermocouple's own standard uncertainty is the floor.
    const double floor_u = u.thermocouple_tolerance_c / std::sqrt(3.0);
    u_calibration_c.push_back(v.size() > 1 ? std::max(std::sqrt(var / (v.size() - 1)), 0.0)
                                           : floor_u);
  }
  return u_calibration_c;
}

UncertaintyModel uncertainty_model(const ThermalModel& m, const std::vector<double>& t_c,
                                   const Eigen::MatrixXd& rates, const CalibrationOptions& opt,
                                   const StageProgress& progress,
                                   const std::vector<ReferenceRates>& references,
                                   const QeFitChoices& fit_choices) {
  // Uncertainty model: emissivity slope and thermocouple tolerance as functions of T.
  UncertaintyModel u;
  u.thermocouple_tolerance_c = opt.thermocouple_tolerance_c;
  u.monte_carlo_refits = m.qe_solver == "datasheet" ? 0 : opt.monte_carlo_refits;
  for (double t = opt.min_temperature_c; t <= opt.max_temperature_c + 1e-9; t += 50)
    u.temperature_c.push_back(t);
  // To the range's end, whatever its length (690..1100 degC ended at 1090).
  if (u.temperature_c.back() < opt.max_temperature_c - 1e-6)
    u.temperature_c.push_back(opt.max_temperature_c);
  u.u_emissivity_c = emissivity_uncertainty(m, u);
  u.u_calibration_c =
      thermocouple_uncertainty(m, u, t_c, rates, opt.seed, progress, references, fit_choices);
  return u;
}

}  // namespace pyrocam
