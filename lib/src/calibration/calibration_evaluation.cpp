#include "pyrocam/calibration/calibration_evaluation.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "pyrocam/calibration/baselines.h"
#include "pyrocam/runtime/estimators.h"

namespace pyrocam {

std::vector<std::size_t> evaluable_settings(const RateTable& rt, const CameraProfile& p) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < rt.settings.size(); ++i) {
    const SettingMeans& s = rt.settings[i];
    bool ok = true;
    for (int b = 0; b < p.band_count(); ++b)
      ok &= s.raw_mean_dn[b] <= p.thresholds.inference_saturation_dn &&
            s.net_mean_dn[b] >= p.thresholds.inference_dim_dn && s.saturated_fraction[b] < 1e-3;
    if (ok) out.push_back(i);
  }
  return out;
}

EstimatorScore score_estimator(const std::string& name, const RateTable& rt,
                               const std::vector<std::size_t>& settings,
                               const std::function<double(const Eigen::VectorXd&)>& estimate) {
  EstimatorScore s;
  s.name = name;
  for (std::size_t i : settings) {
    const double t = estimate(rt.settings[i].net_mean_dn);
    if (!std::isfinite(t)) {
      ++s.missing;
      continue;
    }
    s.true_c.push_back(rt.settings[i].temperature_c);
    s.estimate_c.push_back(t);
  }
  const auto n = static_cast<double>(s.true_c.size());
  if (n == 0) return s;
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < s.true_c.size(); ++i) {
    const double e = s.estimate_c[i] - s.true_c[i];
    sum += e;
    sum2 += e * e;
  }
  s.mean = sum / n;
  s.rms = std::sqrt(sum2 / n);
  s.std = std::sqrt(std::max(0.0, sum2 / n - s.mean * s.mean));
  // Spread across exposures at each temperature, averaged over temperatures.
  double spread_sum = 0;
  int spread_n = 0;
  for (double t : rt.temperatures_c) {
    std::vector<double> e;
    for (std::size_t i = 0; i < s.true_c.size(); ++i)
      if (s.true_c[i] == t) e.push_back(s.estimate_c[i]);
    if (e.size() < 2) continue;
    double m = 0, v = 0;
    for (double x : e) m += x;
    m /= static_cast<double>(e.size());
    for (double x : e) v += (x - m) * (x - m);
    spread_sum += std::sqrt(v / static_cast<double>(e.size() - 1));
    ++spread_n;
  }
  if (spread_n) s.exposure_spread = spread_sum / spread_n;
  return s;
}

std::vector<EstimatorScore> evaluate_estimators(const ThermalModel& m, const RateTable& rates,
                                                const Locus& locus, const CameraModel& sheet_camera,
                                                double locus_step_c) {
  // Table 4: every estimator on the calibration settings' ROI means.
  const CameraProfile& profile = m.profile();
  std::vector<EstimatorScore> table4;
  const auto settings = evaluable_settings(rates, profile);
  const auto evaluated = std::make_shared<const ThermalModel>(m);  // a copy the estimators share
  const auto mlp_est = make_estimator(evaluated, Method::kMlp);
  const auto ml_est = make_estimator(evaluated, Method::kLikelihood);
  auto call = [](const TemperatureEstimator& e) {
    return [&e](const Eigen::VectorXd& s) { return e.temperature_c(s.data()); };
  };
  table4.push_back(score_estimator("MLP", rates, settings, call(*mlp_est)));
  table4.push_back(score_estimator("likelihood fit", rates, settings, call(*ml_est)));
  const OhnoEstimator ohno(locus);
  table4.push_back(
      score_estimator("Ohno, optimised QE", rates, settings,
                      [&](const Eigen::VectorXd& s) { return ohno.temperature_c(s); }));
  const OhnoEstimator ohno_sheet(
      make_locus(sheet_camera, m.min_temperature_c, m.max_temperature_c, locus_step_c));
  table4.push_back(
      score_estimator("Ohno, datasheet QE", rates, settings,
                      [&](const Eigen::VectorXd& s) { return ohno_sheet.temperature_c(s); }));
  const int r = profile.band_index("R"), g = profile.band_index("G"), b = profile.band_index("B");
  if (r >= 0 && g >= 0 && b >= 0 && !settings.empty()) {
    std::vector<Eigen::VectorXd> sig, sim;
    std::vector<double> tt;
    for (std::size_t i : settings) {
      const SettingMeans& st = rates.settings[i];
      sig.push_back(st.net_mean_dn);
      sim.push_back(signal_rates(profile, m.datasheet_qe, celsius_to_kelvin(st.temperature_c)) *
                    st.exposure_us * 1e-6);
      tt.push_back(st.temperature_c);
    }
    const TwoColourEstimator two = TwoColourEstimator::fit(sig, sim, tt, r, g, b);
    table4.push_back(score_estimator("two-colour", rates, settings, [&](const Eigen::VectorXd& s) {
      return two.temperature_c(s);
    }));
  }
  return table4;
}

}  // namespace pyrocam
