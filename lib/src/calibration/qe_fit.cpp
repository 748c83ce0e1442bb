// The two QE solvers (the paper's and the regularised one), which share the residual, Jacobian
// and line-search code here; how well a fit predicts rates it did not see is in qe_validation.cpp.
#include "pyrocam/calibration/qe_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <string>

#include "calibration/qe_problem.h"
#include "detail/portable_math.h"

namespace pyrocam {
namespace qe_detail {

bool usable(double rate) { return std::isfinite(rate) && rate > 0; }

Eigen::MatrixXd radiance_rows(const CameraProfile& profile, const std::vector<double>& temps_c) {
  Eigen::MatrixXd w(static_cast<Eigen::Index>(temps_c.size()), profile.grid.size());
  for (std::size_t i = 0; i < temps_c.size(); ++i)
    w.row(static_cast<Eigen::Index>(i)) =
        profile.etendue_m2_sr *
        weighted_photon_radiance(profile.grid, celsius_to_kelvin(temps_c[i])).transpose();
  return w;
}

Problem prepare(const CameraProfile& profile, const CalibrationRates& data) {
  const auto n_t = static_cast<Eigen::Index>(data.temperatures_c.size());
  if (data.rates.rows() != profile.band_count() || data.rates.cols() != n_t)
    throw InputError("QE fit: rates are " + std::to_string(data.rates.rows()) + " x " +
                     std::to_string(data.rates.cols()) + ", expected " +
                     std::to_string(profile.band_count()) + " bands x " + std::to_string(n_t) +
                     " temperatures for profile " + profile.name);
  for (double t : data.temperatures_c)
    if (!std::isfinite(t) || t <= -kZeroCelsius)
      throw InputError("QE fit: calibration temperature " + std::to_string(t) + " degC is invalid");
  Problem p;
  p.radiance = radiance_rows(profile, data.temperatures_c);
  for (int b = 0; b < profile.band_count(); ++b) {
    std::vector<Eigen::Index> v;
    for (Eigen::Index i = 0; i < n_t; ++i)
      if (usable(data.rates(b, i))) v.push_back(i);
    if (v.size() < 2)
      throw InputError("QE fit: band '" + profile.band_names[b] + "' has " +
                       std::to_string(v.size()) +
                       " usable calibration rates (at least 2 needed; NaN = no usable points)");
    p.reference.push_back(*std::max_element(v.begin(), v.end(), [&](auto a, auto c) {
      return data.temperatures_c[a] < data.temperatures_c[c];
    }));
    p.valid.push_back(std::move(v));
  }
  for (const ReferenceRates& r : data.references) {
    const std::string what = "QE fit: " + r.name + ": ";
    if (r.rates.size() != profile.band_count())
      throw InputError(what + std::to_string(r.rates.size()) + " band rates, expected " +
                       std::to_string(profile.band_count()));
    if (!std::isfinite(r.temperature_c) || r.temperature_c <= -kZeroCelsius)
      throw InputError(what + "temperature " + std::to_string(r.temperature_c) +
                       " degC is invalid");
    if (!std::isfinite(r.temperature_uncertainty_c) || !(r.temperature_uncertainty_c > 0))
      throw InputError(what + "temperature uncertainty must be a number > 0 degC");
    int bands = 0;
    for (Eigen::Index b = 0; b < r.rates.size(); ++b) bands += usable(r.rates[b]);
    if (bands < 2)
      throw InputError(what + std::to_string(bands) +
                       " usable band rates (a reference constrains ratios: at least 2 needed)");
  }
  return p;
}

Eigen::VectorXd least_squares_gains(const CameraProfile& profile, const Problem& p,
                                    const Eigen::MatrixXd& qe, const CalibrationRates& data) {
  Eigen::VectorXd k(qe.rows());
  for (Eigen::Index b = 0; b < qe.rows(); ++b) {
    const Eigen::VectorXd sim = profile.dn_per_electron()[b] * (p.radiance * qe.row(b).transpose());
    double num = 0, den = 0;
    for (Eigen::Index i : p.valid[b]) {
      const double a = sim[i] / data.rates(b, i);
      num += a, den += a * a;
    }
    k[b] = num / den;
  }
  return k;
}

// rms over usable temperatures of (sim/sim_ref) / (meas/meas_ref) - 1 for one band.
double normalised_residual(const Eigen::VectorXd& sim, const Eigen::VectorXd& meas,
                           const std::vector<Eigen::Index>& valid, Eigen::Index ref) {
  double ss = 0;
  for (Eigen::Index i : valid) {
    const double e = (sim[i] / sim[ref]) / (meas[i] / meas[ref]) - 1;
    ss += e * e;
  }
  return std::sqrt(ss / static_cast<double>(valid.size()));
}

Eigen::VectorXd residuals_for(const Problem& p, const Eigen::MatrixXd& qe,
                              const CalibrationRates& data) {
  Eigen::VectorXd out(qe.rows());
  for (Eigen::Index b = 0; b < qe.rows(); ++b)
    out[b] = normalised_residual(p.radiance * qe.row(b).transpose(), data.rates.row(b).transpose(),
                                 p.valid[b], p.reference[b]);
  return out;
}

void finish(const CameraProfile& profile, const Problem& p, const CalibrationRates& data,
            Clock::time_point start, QeFitResult& r) {
  const Eigen::MatrixXd q0 = profile.system_qe();
  r.diagnostics.residual_before = residuals_for(p, q0, data);
  r.diagnostics.residual_after = residuals_for(p, r.system_qe, data);
  r.diagnostics.qe_change_rms =
      ((r.system_qe - q0).rowwise().squaredNorm() / static_cast<double>(q0.cols())).cwiseSqrt();
  const Eigen::VectorXd k0 = least_squares_gains(profile, p, q0, data);
  r.diagnostics.reference_error_before_c.clear();
  r.diagnostics.reference_error_after_c.clear();
  for (const ReferenceRates& ref : data.references) {
    r.diagnostics.reference_error_before_c.push_back(
        reference_reading_c(profile, q0, k0, ref.rates) - ref.temperature_c);
    r.diagnostics.reference_error_after_c.push_back(
        reference_reading_c(profile, r.system_qe, r.gains, ref.rates) - ref.temperature_c);
  }
  r.diagnostics.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
}

RegularisedOptions with_prior_widths(RegularisedOptions o, double factor) {
  for (double* sigma :
       {&o.tilt_sigma, &o.curvature_sigma, &o.shift_sigma_nm, &o.common_tilt_sigma,
        &o.edge_shift_sigma_nm, &o.leak_sigma, &o.discrepancy_sigma, &o.discrepancy_leak})
    *sigma *= factor;
  return o;
}

}  // namespace qe_detail

namespace {

using namespace qe_detail;

// ---- The paper's search ----------------------------------------------------------------------

// Step weight per wavelength: step_in_band in the pass band, falling log-linearly to
// step_out_of_band over taper_nm outside it ("decreasing gradually", paper section 2.7).
Eigen::VectorXd step_weights(const CameraProfile& profile, const PaperSearchOptions& o) {
  const auto& nm = profile.grid.nm();
  const double lo = profile.filter_pass_band_nm[0], hi = profile.filter_pass_band_nm[1];
  Eigen::VectorXd w(nm.size());
  for (Eigen::Index j = 0; j < nm.size(); ++j) {
    const double d = std::max({0.0, lo - nm[j], nm[j] - hi});
    const double f = o.taper_nm > 0 ? std::min(1.0, d / o.taper_nm) : (d > 0 ? 1.0 : 0.0);
    w[j] = o.step_in_band * portable::pow(o.step_out_of_band / o.step_in_band, f);
  }
  return w;
}

// One band of the paper's search. The simulated rates are linear in Q, so changing one sample
// updates them with one radiance column: O(#T) per trial instead of a full integration.
Eigen::VectorXd paper_search_band(const Eigen::MatrixXd& radiance_valid, Eigen::Index ref,
                                  const Eigen::VectorXd& meas_norm, const Eigen::VectorXd& q0,
                                  const Eigen::VectorXd& weights, const PaperSearchOptions& o) {
  const Eigen::Index n_t = radiance_valid.rows(), n_l = radiance_valid.cols();
  const double inv_nt = 1.0 / static_cast<double>(n_t), inv_nl = 1.0 / static_cast<double>(n_l);
  Eigen::VectorXd q = q0;
  Eigen::VectorXd r = radiance_valid * q;
  double ssd = 0;  // sum of (q - q0)^2

  // Loss of the rates r + d * column j (d = 0: current).
  auto loss = [&](Eigen::Index j, double d, double ssd_new) {
    const double* col = radiance_valid.col(j).data();
    const double inv_ref = 1.0 / (r[ref] + d * col[ref]);
    double sum = 0;
    for (Eigen::Index i = 0; i < n_t; ++i)
      sum += std::abs((r[i] + d * col[i]) * inv_ref / meas_norm[i] - 1.0);
    return sum * inv_nt + std::sqrt(ssd_new * inv_nl);
  };

  double current = loss(0, 0.0, ssd);
  for (int sweep = 0; sweep < o.sweeps; ++sweep) {
    const double decade = portable::pow(10.0, -(sweep / std::max(1, o.sweeps_per_decade)));
    for (Eigen::Index j = 0; j < n_l; ++j) {
      const double step = weights[j] * decade;
      double best = current, best_d = 0, best_ssd = ssd;
      for (double sign : {+1.0, -1.0}) {
        const double qn = std::clamp(q[j] + sign * step, 0.0, 1.0);
        const double d = qn - q[j];
        if (d == 0) continue;
        const double ssd_new = ssd - (q[j] - q0[j]) * (q[j] - q0[j]) + (qn - q0[j]) * (qn - q0[j]);
        const double l = loss(j, d, ssd_new);
        if (l < best) best = l, best_d = d, best_ssd = std::max(0.0, ssd_new);
      }
      if (best_d != 0) {
        q[j] += best_d;
        r += best_d * radiance_valid.col(j);
        ssd = best_ssd;
        current = best;
      }
    }
    // Refresh the running sums so rounding cannot accumulate over sweeps.
    r = radiance_valid * q;
    ssd = (q - q0).squaredNorm();
    current = loss(0, 0.0, ssd);
  }
  return q;
}

}  // namespace

const char* to_string(QeSolver solver) {
  return solver == QeSolver::kPaper ? "paper" : "regularised";
}

QeFitResult fit_qe_paper(const CameraProfile& profile, const CalibrationRates& data,
                         const PaperSearchOptions& options) {
  const auto start = Clock::now();
  const Problem p = prepare(profile, data);
  const Eigen::MatrixXd q0 = profile.system_qe();
  const Eigen::VectorXd weights = step_weights(profile, options);
  QeFitResult r;
  r.solver = QeSolver::kPaper;
  r.system_qe = q0;
  r.gains.resize(profile.band_count());
  for (int b = 0; b < profile.band_count(); ++b) {
    const auto& v = p.valid[b];
    const auto n = static_cast<Eigen::Index>(v.size());
    Eigen::MatrixXd rad(n, q0.cols());
    Eigen::VectorXd meas(n);
    Eigen::Index ref = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      rad.row(i) = p.radiance.row(v[i]);
      meas[i] = data.rates(b, v[i]) / data.rates(b, p.reference[b]);
      if (v[i] == p.reference[b]) ref = i;
    }
    r.system_qe.row(b) =
        paper_search_band(rad, ref, meas, q0.row(b).transpose(), weights, options).transpose();
    // Gain: measured over simulated at the hottest usable temperature (paper).
    const double sim =
        profile.dn_per_electron()[b] * p.radiance.row(p.reference[b]).dot(r.system_qe.row(b));
    r.gains[b] = data.rates(b, p.reference[b]) / sim;
  }
  r.diagnostics.iterations = options.sweeps;
  finish(profile, p, data, start, r);
  return r;
}

QeFitResult fit_qe(const CameraProfile& profile, const CalibrationRates& data,
                   const QeFitOptions& options) {
  return options.solver == QeSolver::kPaper
             ? fit_qe_paper(profile, data, options.paper)
             : fit_qe_regularised(profile, data, options.regularised);
}

QeFitChoices held_fit_choices(const QeFitResult& fit) {
  QeFitChoices c;
  if (fit.solver == QeSolver::kRegularised) {
    c.leak_terms = fit.diagnostics.leak_terms ? LeakTerms::kKeep : LeakTerms::kDrop;
    c.prior_scales = {fit.diagnostics.prior_scale};
  }
  return c;
}

QeFitOptions with_fit_choices(QeFitOptions options, const QeFitChoices& choices) {
  options.regularised.leak_terms = choices.leak_terms;
  options.regularised.prior_scales = choices.prior_scales;
  return options;
}

QeFitOptions holding_fit_choices(QeFitOptions options, const QeFitResult& fit) {
  return fit.solver == QeSolver::kRegularised ? with_fit_choices(options, held_fit_choices(fit))
                                              : options;
}

std::string prior_widths_summary(const QeFitResult& fit) {
  if (fit.solver != QeSolver::kRegularised) return "";
  const QeFitDiagnostics& d = fit.diagnostics;
  char text[64];
  std::snprintf(text, sizeof text, "%g x nominal", d.prior_scale);
  std::string out = text;
  if (d.prior_scales_tried.size() > 1 && d.log_evidence.size() == d.prior_scales_tried.size()) {
    out += " (log evidence";
    for (std::size_t k = 0; k < d.log_evidence.size(); ++k) {
      std::snprintf(text, sizeof text, "%s %.1f at %g x", k ? "," : "", d.log_evidence[k],
                    d.prior_scales_tried[k]);
      out += text;
    }
    out += ")";
  }
  return out;
}

std::string leak_terms_summary(const QeFitResult& fit) {
  if (fit.solver != QeSolver::kRegularised) return "";
  const QeFitDiagnostics& d = fit.diagnostics;
  std::string text = d.leak_terms ? "kept" : "dropped";
  char bumps[64] = "";
  if (d.leak_terms && std::isfinite(d.leak_spacing_nm))
    std::snprintf(bumps, sizeof bumps, "bumps every %.0f nm", d.leak_spacing_nm);
  if (std::isfinite(d.leak_chi2_gain)) {
    char figures[200];
    std::snprintf(figures, sizeof figures, " (chi2 gain %.1f %s %.1f, %d amplitudes%s%s)",
                  d.leak_chi2_gain, d.leak_terms ? ">" : "<=", d.leak_chi2_threshold,
                  d.leak_amplitudes, *bumps ? "; fitted with " : "", bumps);
    text += figures;
  } else if (*bumps) {
    text += std::string(" (") + bumps + ")";
  }
  return text;
}

std::vector<QeSample> PriorSensitivity::counted_fits() const {
  std::vector<QeSample> out;
  for (std::size_t k = 0; k < fits.size(); ++k)
    if (counted[k]) out.push_back(fits[k].fit);
  return out;
}

PriorSensitivity prior_sensitivity(const CameraProfile& profile, const CalibrationRates& data,
                                   const QeFitOptions& options, const QeFitResult& fit,
                                   double factor, double occam_odds) {
  if (!(occam_odds >= 1))
    throw InputError("prior sensitivity: the Occam window's odds must be 1 or more");
  PriorSensitivity out;
  out.occam_odds = occam_odds;
  if (options.solver != QeSolver::kRegularised) return out;
  const RegularisedOptions held = holding_fit_choices(options, fit).regularised;
  // Around the widths the fit chose, else the nominal ones.
  const double base = held.prior_scales.size() == 1 ? held.prior_scales.front() : 1.0;
  for (const double f : {factor, 1 / factor}) {
    const double scale = base * f;
    const auto made =
        std::find_if(fit.other_widths.begin(), fit.other_widths.end(), [&](const PriorWidthFit& w) {
          return std::abs(w.prior_scale / scale - 1) < 1e-12 &&
                 w.leak_terms == fit.diagnostics.leak_terms;
        });
    if (made != fit.other_widths.end()) {
      out.fits.push_back(*made);
      continue;
    }
    RegularisedOptions o = held;
    o.posterior_samples = 0;
    o.prior_scales = {scale};
    const QeFitResult refit = fit_qe_regularised(profile, data, o);
    out.fits.push_back({scale, refit.diagnostics.log_evidence.front(), refit.diagnostics.leak_terms,
                        QeSample{refit.system_qe, refit.gains}});
  }
  // The kept fit's evidence: that of its factor among those it tried.
  const QeFitDiagnostics& d = fit.diagnostics;
  for (std::size_t k = 0; k < d.prior_scales_tried.size() && k < d.log_evidence.size(); ++k)
    if (d.prior_scales_tried[k] == d.prior_scale) out.best_log_evidence = d.log_evidence[k];
  for (const PriorWidthFit& w : out.fits)
    out.best_log_evidence = std::fmax(out.best_log_evidence, w.log_evidence);
  const double window = std::isinf(occam_odds) ? INFINITY : portable::log(occam_odds);
  for (const PriorWidthFit& w : out.fits)
    out.counted.push_back(!(w.log_evidence < out.best_log_evidence - window));
  return out;
}

std::vector<QeSample> prior_sensitivity_fits(const CameraProfile& profile,
                                             const CalibrationRates& data,
                                             const QeFitOptions& options, const QeFitResult& fit,
                                             double factor, double occam_odds) {
  return prior_sensitivity(profile, data, options, fit, factor, occam_odds).counted_fits();
}

std::string prior_sensitivity_summary(const PriorSensitivity& s) {
  std::string out;
  for (std::size_t k = 0; k < s.fits.size(); ++k) {
    const PriorWidthFit& w = s.fits[k];
    char text[160];
    if (s.counted[k])
      std::snprintf(text, sizeof text, "%s%g x nominal counted", k ? "; " : "", w.prior_scale);
    else
      std::snprintf(text, sizeof text,
                    "%s%g x nominal left out (log evidence %.1f below the best, window %.1f)",
                    k ? "; " : "", w.prior_scale, s.best_log_evidence - w.log_evidence,
                    portable::log(s.occam_odds));
    out += text;
  }
  return out;
}

Eigen::VectorXd fitted_signal_rates(const CameraProfile& profile, const QeFitResult& fit,
                                    double temperature_k, double emissivity) {
  return fit.gains.cwiseProduct(signal_rates(profile, fit.system_qe, temperature_k, emissivity));
}

Eigen::VectorXd normalised_rate_residuals(const CameraProfile& profile,
                                          const Eigen::MatrixXd& system_qe,
                                          const CalibrationRates& data) {
  const Problem p = prepare(profile, data);
  if (system_qe.rows() != profile.band_count() || system_qe.cols() != profile.grid.size())
    throw InputError("QE fit: system QE shape does not match profile " + profile.name);
  return residuals_for(p, system_qe, data);
}

}  // namespace pyrocam

namespace pyrocam {

double reference_reading_c(const CameraProfile& profile, const Eigen::MatrixXd& system_qe,
                           const Eigen::VectorXd& gains, const Eigen::VectorXd& rates) {
  std::vector<Eigen::Index> bands;
  for (Eigen::Index b = 0; b < rates.size(); ++b)
    if (qe_detail::usable(rates[b])) bands.push_back(b);
  if (bands.size() < 2) return NAN;
  // Scale-free misfit of the log rates, the scale profiled out.
  const auto misfit = [&](double t_c) {
    const Eigen::VectorXd m =
        gains.cwiseProduct(signal_rates(profile, system_qe, celsius_to_kelvin(t_c)));
    double mean = 0, ss = 0;
    std::vector<double> d;
    for (Eigen::Index b : bands) d.push_back(portable::log(rates[b] / m[b])), mean += d.back();
    mean /= static_cast<double>(d.size());
    for (double x : d) ss += (x - mean) * (x - mean);
    return ss;
  };
  double best_t = 300, best = INFINITY;
  for (double t = 300; t <= 4000; t += 10)
    if (const double f = misfit(t); f < best) best = f, best_t = t;
  // Golden-section refinement inside the bracket of the coarse minimum.
  double a = best_t - 10, b = best_t + 10;
  constexpr double kGolden = 0.6180339887498949;
  double c = b - kGolden * (b - a), d = a + kGolden * (b - a), fc = misfit(c), fd = misfit(d);
  for (int it = 0; it < 60; ++it) {
    if (fc < fd)
      b = d, d = c, fd = fc, c = b - kGolden * (b - a), fc = misfit(c);
    else
      a = c, c = d, fc = fd, d = a + kGolden * (b - a), fd = misfit(d);
  }
  return 0.5 * (a + b);
}

}  // namespace pyrocam
