// The regularised QE solve (see RegularisedOptions): the model of qe_regularised_model.h fitted
// by Levenberg-Marquardt to the furnace rates and the reference sources, with and without its
// leak terms, and the posterior samples around the fit.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "calibration/levenberg_marquardt.h"
#include "calibration/qe_problem.h"
#include "calibration/qe_regularised_model.h"
#include "calibration/qe_shape_bases.h"
#include "detail/chi2.h"
#include "detail/portable_math.h"
#include "detail/random.h"
#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

using namespace qe_detail;

// The joint problem linearised at x = (theta, delta): its free parameters and the Cholesky
// factor of their normal matrix. Leak bumps held at their bound (the model's and the
// discrepancy's additive ones) stay there: sampling them and clamping would break the
// correlations that keep a sample on the data, and sampling them without a clamp gives
// negative transmissions.
struct JointLinearisation {
  std::vector<Eigen::Index> free;
  Eigen::LLT<Eigen::MatrixXd> llt;
  Eigen::VectorXd residual;
  Eigen::MatrixXd jacobian;  // of every parameter, free or not
  bool ok = false;
};

JointLinearisation linearise(const JointModel& joint, const Eigen::VectorXd& x) {
  JointLinearisation l;
  joint.evaluate(x, l.residual, &l.jacobian);
  for (Eigen::Index k = 0; k < joint.size(); ++k)
    if (!joint.fixed(k) && !(joint.bounded(k) && x[k] <= 0)) l.free.push_back(k);
  const Eigen::MatrixXd ja = l.jacobian(Eigen::all, l.free);
  Eigen::MatrixXd h = ja.transpose() * ja;
  h.diagonal().array() += 1e-9 * (h.diagonal().array() + 1e-12);
  l.llt.compute(h);
  l.ok = l.llt.info() == Eigen::Success;
  return l;
}

// log p(data | priors) by the Laplace approximation at the fit l was linearised at, up to a
// constant: the data rows' misfit and noise, and the Occam factor det(prior precision) /
// det(posterior precision) over the free parameters with a proper prior (the gains' and
// scales' flat priors are the same for every choice of widths).
double log_evidence(const JointLinearisation& l, std::size_t data_rows, double relative_noise) {
  if (!l.ok) return NAN;
  const auto nd = static_cast<Eigen::Index>(data_rows);
  const Eigen::MatrixXd prior = l.jacobian.bottomRows(l.jacobian.rows() - nd)(Eigen::all, l.free);
  std::vector<Eigen::Index> proper;
  for (Eigen::Index c = 0; c < prior.cols(); ++c)
    if (prior.col(c).squaredNorm() > 0) proper.push_back(c);
  const Eigen::MatrixXd pp = prior(Eigen::all, proper);
  Eigen::LLT<Eigen::MatrixXd> prior_llt(pp.transpose() * pp);
  if (prior_llt.info() != Eigen::Success) return NAN;
  double log_det_posterior = 0, log_det_prior = 0;
  for (Eigen::Index k = 0; k < l.llt.matrixLLT().rows(); ++k)
    log_det_posterior += 2 * portable::log(l.llt.matrixLLT()(k, k));
  for (Eigen::Index k = 0; k < prior_llt.matrixLLT().rows(); ++k)
    log_det_prior += 2 * portable::log(prior_llt.matrixLLT()(k, k));
  return -0.5 * l.residual.squaredNorm() - static_cast<double>(nd) * portable::log(relative_noise) +
         0.5 * (log_det_prior - log_det_posterior);
}

// Draws theta ~ N(theta*, (J^T J)^-1) over the free parameters, jointly with the
// discrepancy's shape changes (around delta, already in the model's QE).
// l: the joint problem linearised at (th, delta).
std::vector<QeSample> posterior_samples(RegularisedModel& model, const JointLinearisation& l,
                                        const Eigen::VectorXd& th, const Discrepancy& shape,
                                        const Eigen::VectorXd& delta, const RegularisedOptions& o) {
  std::vector<QeSample> out;
  if (o.posterior_samples <= 0 || !l.ok) return out;
  const JointModel joint(model, shape);
  const int bands = model.band_count();
  Eigen::MatrixXd fitted(bands, model.wavelengths());
  for (int b = 0; b < bands; ++b) fitted.row(b) = model.qe(b, th).transpose();
  std::vector<Eigen::MatrixXd> dq_dtheta;
  for (int b = 0; b < bands; ++b) dq_dtheta.push_back(model.qe_jacobian(b, th));
  const auto nf = static_cast<Eigen::Index>(l.free.size()), nd = delta.size();
  Random rng(mix(o.posterior_seed));
  for (int s = 0; s < o.posterior_samples; ++s) {
    Eigen::VectorXd z(nf);
    for (Eigen::Index c = 0; c < nf; ++c) z[c] = rng.normal();
    const Eigen::VectorXd free_step = l.llt.matrixU().solve(z);  // covariance (U^T U)^-1
    Eigen::VectorXd joint_step = Eigen::VectorXd::Zero(joint.size());
    joint_step(l.free) = free_step;
    const Eigen::VectorXd step = joint_step.head(model.size());
    // The sample is taken to first order, as the approximation is: the parameters and the
    // shape changes trade against each other along directions the data hold, and the model's
    // own nonlinearity (clamps, warps) would break that balance and leave samples off the data.
    QeSample q;
    q.system_qe.resize(bands, model.wavelengths());
    q.gains.resize(bands);
    for (int b = 0; b < bands; ++b) {
      Eigen::VectorXd qb = fitted.row(b).transpose() +
                           dq_dtheta[static_cast<std::size_t>(b)] * model.qe_parameters(b, step);
      if (nd > 0) qb += shape.dq[static_cast<std::size_t>(b)] * joint_step.tail(nd);
      q.system_qe.row(b) = qb.transpose();
      q.gains[b] = model.gain(b, th) * (1 + step[b]);
    }
    out.push_back(std::move(q));
  }
  return out;
}

// One fit of the model `options` describe, with what its posterior needs.
struct ModelFit {
  RegularisedOptions weighted;  // the options with the data's weight the reweighting reached
  Eigen::VectorXd th, delta;
  Discrepancy shape;
  int iterations = 0;
  double data_ss = 0;       // sum of squared relative misfits of furnace and reference rates
  std::size_t data_n = 0;   // and their count
  int leak_amplitudes = 0;  // free leak bumps and, fitted jointly, additive leaks
};

ModelFit fit_model(const CameraProfile& profile, const CalibrationRates& data, const Problem& p,
                   const RegularisedOptions& options) {
  ModelFit f;
  RegularisedOptions o = options;
  // The model's parameters alone at the starting weight: the fit the discrepancy's shape changes
  // are laid around.
  {
    const RegularisedModel first(profile, data, p, o);
    f.th = first.start();
    f.iterations += levenberg_marquardt(first, f.th, o.max_iterations);
    if (options.fit_discrepancy || options.posterior_samples > 0) {
      Eigen::MatrixXd fitted(profile.band_count(), profile.grid.size());
      for (int b = 0; b < profile.band_count(); ++b) fitted.row(b) = first.qe(b, f.th).transpose();
      f.shape = discrepancy_basis(profile, fitted, options);
    }
  }
  f.delta = Eigen::VectorXd::Zero(f.shape.sigma.size());
  const bool joint = options.fit_discrepancy && f.delta.size() > 0;
  // With the discrepancy's shape changes the fit is joint: fitted with theta alone, what the
  // model cannot shape is pushed into parameters that can (leaks, edges) and extrapolates with
  // them; with the shape free the data are explained as the priors find likeliest.
  // Reweighting: the data's weight against the priors is 1 / relative_noise; refit with the
  // misfit actually reached (noise-free data earn tighter fits, noisy data stronger priors),
  // each fit from the last one, until the weight holds. Carried from the loosest weight to the
  // data's own, the joint fit ends in the same one of its minima for data that differ a little
  // (started at the data's weight it could end in another, tens of degrees apart at 2600 degC).
  const int passes = std::max(1, options.noise_passes);
  for (int pass = 0; pass < passes; ++pass) {
    RegularisedModel m(profile, data, p, o);
    if (joint) {
      const JointModel joint_model(m, f.shape);
      Eigen::VectorXd x(f.th.size() + f.delta.size());
      x << f.th, f.delta;
      f.iterations += levenberg_marquardt(joint_model, x, o.max_iterations);
      f.th = x.head(f.th.size()), f.delta = x.tail(f.delta.size());
      m.set_shape_change(shape_change(f.shape, f.delta));  // not the last trial's
    } else {
      f.iterations += levenberg_marquardt(m, f.th, o.max_iterations);
    }
    const double misfit = std::clamp(m.data_rms(f.th), options.min_relative_noise, 0.05);
    if (pass + 1 == passes || std::abs(portable::log(misfit / o.relative_noise)) < 0.02) break;
    o.relative_noise = misfit;
  }
  f.weighted = o;
  RegularisedModel model(profile, data, p, o);
  if (f.delta.size() > 0) model.set_shape_change(shape_change(f.shape, f.delta));
  const RegularisedModel::DataMisfit misfit = model.data_misfit(f.th);
  f.data_ss = misfit.furnace_ss + misfit.reference_ss;
  f.data_n = misfit.furnace_n + misfit.reference_n;
  f.leak_amplitudes =
      model.free_leak_bumps() + (joint ? static_cast<int>(f.shape.additive_leaks) : 0);
  return f;
}

// The regularised fit at one choice of prior widths, before its posterior is drawn.
struct WidthFit {
  QeFitResult result;  // without posterior samples
  ModelFit fit;
  JointLinearisation linearisation;  // at the fit
};

RegularisedModel model_at(const CameraProfile& profile, const CalibrationRates& data,
                          const Problem& p, const ModelFit& f) {
  RegularisedModel model(profile, data, p, f.weighted);
  if (f.delta.size() > 0) model.set_shape_change(shape_change(f.shape, f.delta));
  return model;
}

// The regularised fit with the priors `options` hold (one width): the leak terms' choice, the
// fit and its evidence.
WidthFit fit_at_widths(const CameraProfile& profile, const CalibrationRates& data, const Problem& p,
                       const RegularisedOptions& options) {
  RegularisedOptions without = options, fine = options;
  without.leak_sigma = 0;
  without.discrepancy_leak = 0;
  if (options.fine_leak_spacing_nm > 0 && options.fine_leak_spacing_nm < options.leak_spacing_nm)
    fine.leak_spacing_nm = options.fine_leak_spacing_nm;
  const bool refine = fine.leak_spacing_nm != options.leak_spacing_nm && options.leak_sigma > 0;
  const bool leaks = options.leak_sigma > 0 || options.discrepancy_leak > 0;
  WidthFit w;
  QeFitResult& r = w.result;
  ModelFit& f = w.fit;
  const RegularisedOptions* chosen = &fine;
  if (!leaks) {
    f = fit_model(profile, data, p, options);
    chosen = &options;
  } else if (options.leak_terms == LeakTerms::kKeep) {
    f = fit_model(profile, data, p, fine);
  } else if (options.leak_terms == LeakTerms::kDrop) {
    f = fit_model(profile, data, p, without);
    chosen = &without;
  } else {
    ModelFit with = fit_model(profile, data, p, options);
    ModelFit plain = fit_model(profile, data, p, without);
    // The chi2 gain at the noise the fit with the leaks reaches (the larger model's estimate).
    const double noise_ss =
        with.data_ss / static_cast<double>(std::max<std::size_t>(1, with.data_n));
    r.diagnostics.leak_chi2_gain = (plain.data_ss - with.data_ss) / std::max(noise_ss, 1e-300);
    r.diagnostics.leak_amplitudes = with.leak_amplitudes;
    r.diagnostics.leak_chi2_threshold =
        detail::chi2_quantile(std::max(1, with.leak_amplitudes), options.leak_test_level);
    const bool keep = r.diagnostics.leak_chi2_gain > r.diagnostics.leak_chi2_threshold;
    int iterations = with.iterations + plain.iterations;
    if (keep && refine) {
      f = fit_model(profile, data, p, fine);
      iterations += f.iterations;
    } else {
      f = keep ? std::move(with) : std::move(plain);
    }
    f.iterations = iterations;
    if (!keep) chosen = &without;
  }
  r.diagnostics.leak_terms = chosen != &without && leaks;
  if (r.diagnostics.leak_terms && chosen->leak_sigma > 0)
    r.diagnostics.leak_spacing_nm = chosen->leak_spacing_nm;
  RegularisedModel model = model_at(profile, data, p, f);
  r.solver = QeSolver::kRegularised;
  r.system_qe.resize(profile.band_count(), profile.grid.size());
  r.gains.resize(profile.band_count());
  for (int b = 0; b < profile.band_count(); ++b) {
    r.system_qe.row(b) = model.qe(b, f.th).cwiseMin(1.0).transpose();
    r.gains[b] = model.gain(b, f.th);
  }
  r.diagnostics.iterations = f.iterations;
  const JointModel joint(model, f.shape);
  Eigen::VectorXd x(joint.size());
  x << f.th, f.delta;
  w.linearisation = linearise(joint, x);
  r.diagnostics.log_evidence = {log_evidence(w.linearisation, f.data_n, f.weighted.relative_noise)};
  return w;
}

}  // namespace

QeFitResult fit_qe_regularised(const CameraProfile& profile, const CalibrationRates& data,
                               const RegularisedOptions& options) {
  const auto start = Clock::now();
  const Problem p = prepare(profile, data);
  std::vector<double> scales = options.prior_scales;
  if (scales.empty()) scales = {1.0};
  for (double s : scales)
    if (!(s > 0) || !std::isfinite(s))
      throw InputError("QE fit: a prior scale must be a positive number");
  std::vector<WidthFit> fits;
  std::vector<double> evidence;
  int iterations = 0;
  for (double s : scales) {
    fits.push_back(fit_at_widths(profile, data, p, with_prior_widths(options, s)));
    iterations += fits.back().result.diagnostics.iterations;
    evidence.push_back(fits.back().result.diagnostics.log_evidence.front());
  }
  // The largest evidence; where none could be computed, the widths nearest the nominal ones.
  std::size_t kept = 0;
  for (std::size_t k = 1; k < scales.size(); ++k) {
    const bool larger =
        evidence[k] > evidence[kept] || (std::isnan(evidence[kept]) && !std::isnan(evidence[k]));
    const bool nearer = std::isnan(evidence[kept]) && std::isnan(evidence[k]) &&
                        std::abs(portable::log(scales[k])) < std::abs(portable::log(scales[kept]));
    if (larger || nearer) kept = k;
  }
  WidthFit& w = fits[kept];
  // The posterior of the kept fit only: the model is rebuilt as it was fitted.
  RegularisedModel model = model_at(profile, data, p, w.fit);
  QeFitResult best = std::move(w.result);
  best.posterior = posterior_samples(model, w.linearisation, w.fit.th, w.fit.shape, w.fit.delta,
                                     with_prior_widths(options, scales[kept]));
  for (std::size_t k = 0; k < scales.size(); ++k)
    if (k != kept)
      best.other_widths.push_back({scales[k], evidence[k], fits[k].result.diagnostics.leak_terms,
                                   QeSample{fits[k].result.system_qe, fits[k].result.gains}});
  best.diagnostics.prior_scale = scales[kept];
  best.diagnostics.iterations = iterations;
  best.diagnostics.prior_scales_tried = scales;
  best.diagnostics.log_evidence = evidence;
  finish(profile, p, data, start, best);
  return best;
}

}  // namespace pyrocam
