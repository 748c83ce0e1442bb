#include "pyrocam/runtime/estimator_check.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "pyrocam/core/locus.h"

namespace pyrocam {
namespace {

// An estimator's readings of the locus's noise-free graybody signals, the brightest band at
// peak_dn. Band-planar, all samples at once: the estimators' batch paths, as the elements call
// them (one sample at a time the network took a third of a second for a model's start).
std::vector<float> read_locus(const TemperatureEstimator& e, const Locus& locus, double peak_dn) {
  const auto bands = static_cast<std::size_t>(locus.rates.cols());
  const auto n = static_cast<std::size_t>(locus.size());
  std::vector<std::vector<float>> planes(bands, std::vector<float>(n));
  for (std::size_t i = 0; i < n; ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const double scale = peak_dn / locus.rates.row(row).maxCoeff();
    for (std::size_t k = 0; k < bands; ++k)
      planes[k][i] = static_cast<float>(locus.rates(row, static_cast<Eigen::Index>(k)) * scale);
  }
  std::vector<const float*> plane_ptrs;
  for (const auto& p : planes) plane_ptrs.push_back(p.data());
  std::vector<float> t(n);
  e.estimate(plane_ptrs.data(), n, t.data());
  return t;
}

}  // namespace

LocusAgreement compare_on_locus(const ThermalModel& model, const TemperatureEstimator& a,
                                const TemperatureEstimator& b, double step_c, double peak_dn) {
  const Locus locus =
      make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, step_c);
  const auto n = static_cast<std::size_t>(locus.size());
  const std::vector<float> ta = read_locus(a, locus, peak_dn), tb = read_locus(b, locus, peak_dn);
  LocusAgreement r;
  for (std::size_t i = 0; i < n; ++i) {
    ++r.samples;
    if (std::isfinite(ta[i]) != std::isfinite(tb[i])) ++r.validity_differs;
    if (!std::isfinite(ta[i]) || !std::isfinite(tb[i])) continue;
    ++r.both_valid;
    const double d = std::abs(static_cast<double>(ta[i]) - tb[i]);
    if (d > r.max_difference_c || r.both_valid == 1) {
      r.max_difference_c = d;
      r.worst_temperature_c = locus.temperature_c[static_cast<Eigen::Index>(i)];
    }
  }
  return r;
}

AboveRangeFold fold_above_range(const ThermalModel& model, const TemperatureEstimator& e,
                                double span_c, double step_c, double peak_dn) {
  AboveRangeFold r;
  const double first = model.max_temperature_c + step_c;
  const double last = std::min(model.max_temperature_c + span_c, 6000.0);
  if (!(first <= last) || !(step_c > 0)) return r;
  const Locus locus = make_locus(model.camera, first, last, step_c);
  const auto n = static_cast<std::size_t>(locus.size());
  const std::vector<float> t = read_locus(e, locus, peak_dn);
  double worst = 0;
  for (std::size_t i = 0; i < n; ++i) {
    ++r.samples;
    const double truth = locus.temperature_c[static_cast<Eigen::Index>(i)];
    if (!std::isfinite(t[i]) || truth - t[i] <= AboveRangeFold::kFoldToleranceC) continue;
    ++r.read_inside;
    if (truth - t[i] > worst) {
      worst = truth - t[i];
      r.worst_true_c = truth;
      r.worst_read_c = t[i];
    }
  }
  return r;
}

}  // namespace pyrocam
