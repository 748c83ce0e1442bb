// The two QE solvers (the paper's and the regularised one), which share the residual, Jacobian
// and line-search code here; how well a fit predicts rates it did not see is in qe_validation.cpp.
#include "pyrocam/calibration/qe_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "detail/portable_math.h"

namespace pyrocam {
namespace {

using Clock = std::chrono::steady_clock;

bool usable(double rate) { return std::isfinite(rate) && rate > 0; }

// What both solvers need: photon radiance per temperature and, per band, its usable rates and the
// hottest usable temperature (the normalisation point).
struct Problem {
  Eigen::MatrixXd radiance;  // temperatures x wavelengths: etendue * weighted photon radiance
  std::vector<std::vector<Eigen::Index>> valid;  // per band, usable temperature indices
  std::vector<Eigen::Index> reference;           // per band, hottest usable temperature index
};

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
  return p;
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
  r.diagnostics.wall_time_s = std::chrono::duration<double>(Clock::now() - start).count();
}

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

// ---- The regularised solve -------------------------------------------------------------------

// Linear interpolation of curve at (lambda - shift), as the simulator shifts bands.
Eigen::VectorXd shifted(const Eigen::VectorXd& curve, const WavelengthGrid& grid, double shift) {
  Eigen::VectorXd out(curve.size());
  const double last = static_cast<double>(curve.size() - 1);
  for (Eigen::Index i = 0; i < curve.size(); ++i) {
    const double pos =
        std::clamp((grid.nm()[i] - shift - grid.start_nm()) / grid.step_nm(), 0.0, last);
    const auto i0 = static_cast<Eigen::Index>(std::floor(pos));
    const auto i1 = std::min<Eigen::Index>(i0 + 1, curve.size() - 1);
    const double f = pos - static_cast<double>(i0);
    out[i] = curve[i0] * (1 - f) + curve[i1] * f;
  }
  return out;
}

// Leak bumps: raised cosines of half width `spacing` stepping away from the pass band edges,
// zero inside the pass band (a leak is what the filter lets through where it should block).
// `side` marks which blocking region each bump is in, for the smoothness penalty.
Eigen::MatrixXd leak_basis(const CameraProfile& profile, double spacing, std::vector<int>& side) {
  const auto& nm = profile.grid.nm();
  const double lo = profile.filter_pass_band_nm[0], hi = profile.filter_pass_band_nm[1];
  std::vector<Eigen::VectorXd> cols;
  side.clear();
  auto add = [&](double centre, int s) {
    Eigen::VectorXd c = Eigen::VectorXd::Zero(nm.size());
    for (Eigen::Index j = 0; j < nm.size(); ++j) {
      const double x = (nm[j] - centre) / spacing;
      if (std::abs(x) < 1 && (nm[j] < lo || nm[j] > hi)) c[j] = 0.5 + 0.5 * portable::cos(M_PI * x);
    }
    if (c.maxCoeff() > 0) cols.push_back(c), side.push_back(s);
  };
  if (spacing > 0) {
    for (double c = lo; c + spacing > profile.grid.start_nm(); c -= spacing) add(c, -1);
    for (double c = hi; c - spacing < profile.grid.stop_nm(); c += spacing) add(c, +1);
  }
  Eigen::MatrixXd basis(nm.size(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t k = 0; k < cols.size(); ++k) basis.col(static_cast<Eigen::Index>(k)) = cols[k];
  return basis;
}

class RegularisedModel {
 public:
  RegularisedModel(const CameraProfile& profile, const CalibrationRates& data, const Problem& p,
                   const RegularisedOptions& o)
      : profile_(profile), data_(data), p_(p), o_(o), q0_(profile.system_qe()) {
    nb_ = profile.band_count();
    leak_ = leak_basis(profile, o.leak_spacing_nm, side_);
    nk_ = leak_.cols();
    const double centre = 0.5 * (profile.filter_pass_band_nm[0] + profile.filter_pass_band_nm[1]);
    x_ = (profile.grid.nm().array() - centre) / 100.0;
    use_ = radiance_rows(profile, o.use_temperatures_c);
    gain0_.resize(nb_);
    rho0_.resize(nb_, use_.rows());
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd q = q0_.row(b).transpose();
      const Eigen::VectorXd sim = rates(b, q);
      double num = 0, den = 0;  // least-squares gain for relative residuals
      for (Eigen::Index i : p_.valid[b]) {
        const double a = sim[i] / data_.rates(b, i);
        num += a, den += a * a;
      }
      gain0_[b] = num / den;
      const double ref = p_.radiance.row(p_.reference[b]).dot(q);
      for (Eigen::Index e = 0; e < use_.rows(); ++e) rho0_(b, e) = use_.row(e).dot(q) / ref;
    }
    // Prior sigmas, one per parameter (0 = fixed). Shift only for narrow bands.
    sigma_ = Eigen::VectorXd::Zero(size());
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd q = q0_.row(b).transpose();
      const double fwhm =
          static_cast<double>((q.array() >= 0.5 * q.maxCoeff()).count()) * profile.grid.step_nm();
      const Eigen::Index off = nb_ + b * kPerBand;
      sigma_[b] = std::numeric_limits<double>::infinity();  // gains: free, no prior
      sigma_[off] = o.tilt_sigma;
      sigma_[off + 1] = o.curvature_sigma;
      sigma_[off + 2] = fwhm < o.narrow_band_fwhm_nm ? o.shift_sigma_nm : 0.0;
    }
    // Leak bumps: sigma divided by their leverage on the high range (see the options).
    Eigen::Index hottest_use = 0;
    for (Eigen::Index e = 0; e < use_.rows(); ++e)
      if (o.use_temperatures_c[e] > o.use_temperatures_c[hottest_use]) hottest_use = e;
    const Eigen::Index hot_cal = *std::max_element(
        p_.reference.begin(), p_.reference.end(),
        [&](auto a, auto c) { return data.temperatures_c[a] < data.temperatures_c[c]; });
    for (Eigen::Index k = 0; k < nk_; ++k) {
      double leverage = 1;
      for (int b = 0; b < nb_ && use_.rows() > 0; ++b) {
        const Eigen::VectorXd bump =
            profile.sensor_qe.row(b).transpose().cwiseProduct(leak_.col(k));
        const Eigen::VectorXd q = q0_.row(b).transpose();
        const double cal = p_.radiance.row(hot_cal).dot(bump) / p_.radiance.row(hot_cal).dot(q);
        const double use = use_.row(hottest_use).dot(bump) / use_.row(hottest_use).dot(q);
        if (cal > 0) leverage = std::max(leverage, use / cal);
      }
      sigma_[leak_offset() + k] = o.leak_sigma / leverage;
    }
  }

  bool fixed(Eigen::Index k) const { return sigma_[k] == 0; }

  Eigen::Index size() const { return nb_ + nb_ * kPerBand + nk_; }
  Eigen::Index leak_offset() const { return nb_ + nb_ * kPerBand; }

  // Q_b(theta) and its derivatives (wavelengths x [per-band params, leak bumps]).
  Eigen::VectorXd qe(int b, const Eigen::VectorXd& th, Eigen::MatrixXd* dq = nullptr) const {
    const double* pb = th.data() + nb_ + b * kPerBand;
    const double h = pb[2];
    // The band's own filter shifts (sensor QE); lens and optical filters stay where they are.
    const Eigen::VectorXd sensor = profile_.sensor_qe.row(b).transpose();
    const Eigen::ArrayXd optics = profile_.optics_transmission.array();
    const Eigen::VectorXd s = h != 0 ? (shifted(sensor, profile_.grid, h).array() * optics).matrix()
                                     : Eigen::VectorXd(q0_.row(b).transpose());
    const Eigen::ArrayXd factor = 1.0 + pb[0] * x_ + pb[1] * x_.square();
    const Eigen::VectorXd leak = leak_ * th.tail(nk_);
    Eigen::VectorXd q = (s.array() * factor).matrix() + sensor.cwiseProduct(leak);
    const Eigen::ArrayXd positive = (q.array() > 0).cast<double>();  // Q >= 0 by clamping
    q = q.cwiseMax(0.0);
    if (dq) {
      dq->resize(q.size(), kPerBand + nk_);
      dq->col(0) = (s.array() * x_ * positive).matrix();
      dq->col(1) = (s.array() * x_.square() * positive).matrix();
      const double eps = 0.5 * profile_.grid.step_nm();
      dq->col(2) =
          ((shifted(sensor, profile_.grid, h + eps) - shifted(sensor, profile_.grid, h - eps))
               .array() /
           (2 * eps) * optics * factor * positive)
              .matrix();
      dq->rightCols(nk_) = (leak_.array().colwise() * (sensor.array() * positive)).matrix();
    }
    return q;
  }

  // Residual vector and Jacobian at theta (gain k_b = gain0_b * exp(theta_b)).
  void evaluate(const Eigen::VectorXd& th, Eigen::VectorXd& res, Eigen::MatrixXd* jac) const {
    std::vector<double> rv;
    std::vector<Eigen::RowVectorXd> jr;
    const Eigen::Index n = size();
    auto row = [&](double value, Eigen::RowVectorXd&& j) {
      rv.push_back(value);
      if (jac) jr.push_back(std::move(j));
    };
    Eigen::MatrixXd dq;
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd q = qe(b, th, &dq);
      const double k = gain0_[b] * portable::exp(th[b]);
      const double g = profile_.dn_per_electron()[b];
      const Eigen::MatrixXd wdq = p_.radiance * dq;  // temperatures x local params
      const Eigen::VectorXd wq = p_.radiance * q;
      const Eigen::Index off = nb_ + b * kPerBand;
      // Data: relative misfit of the absolute rate, in units of the expected noise.
      for (Eigen::Index i : p_.valid[b]) {
        const double scale = 1.0 / (o_.relative_noise * data_.rates(b, i));
        Eigen::RowVectorXd j;
        if (jac) {
          j = Eigen::RowVectorXd::Zero(n);
          j[b] = k * g * wq[i] * scale;
          j.segment(off, kPerBand) = k * g * scale * wdq.row(i).head(kPerBand);
          j.tail(nk_) = k * g * scale * wdq.row(i).tail(nk_);
        }
        row((k * g * wq[i] - data_.rates(b, i)) * scale, std::move(j));
      }
      // Extrapolation: the band's rate at the temperatures of use, relative to its hottest
      // calibration rate, should not move unless the data insist. The furnace barely sees short
      // wavelengths and far skirts; without this, changes there are free and ruin the high range.
      if (o_.use_change_sigma > 0) {
        const Eigen::Index ref = p_.reference[b];
        const double v = wq[ref];
        const Eigen::VectorXd uq = use_ * q;
        const Eigen::MatrixXd udq = use_ * dq;
        for (Eigen::Index e = 0; e < use_.rows(); ++e) {
          const double rho = uq[e] / v;
          const double scale = 1.0 / (rho0_(b, e) * o_.use_change_sigma);
          Eigen::RowVectorXd j;
          if (jac) {
            j = Eigen::RowVectorXd::Zero(n);
            const Eigen::RowVectorXd d = (udq.row(e) - rho * wdq.row(ref)) / v * scale;
            j.segment(off, kPerBand) = d.head(kPerBand);
            j.tail(nk_) = d.tail(nk_);
          }
          row((rho - rho0_(b, e)) * scale, std::move(j));
        }
      }
    }
    // Gaussian priors on the shape parameters and leak bumps.
    for (Eigen::Index k = nb_; k < n; ++k) {
      if (fixed(k)) continue;
      Eigen::RowVectorXd j;
      if (jac) j = Eigen::RowVectorXd::Zero(n), j[k] = 1 / sigma_[k];
      row(th[k] / sigma_[k], std::move(j));
    }
    // Leaks are smooth along each blocking region.
    const Eigen::Index lo = leak_offset();
    for (Eigen::Index k = 1; k + 1 < nk_; ++k) {
      if (side_[k - 1] != side_[k] || side_[k + 1] != side_[k]) continue;
      const double s = 1 / o_.leak_curvature_sigma;
      Eigen::RowVectorXd j;
      if (jac) {
        j = Eigen::RowVectorXd::Zero(n);
        j[lo + k - 1] = s, j[lo + k] = -2 * s, j[lo + k + 1] = s;
      }
      row((th[lo + k - 1] - 2 * th[lo + k] + th[lo + k + 1]) * s, std::move(j));
    }
    res = Eigen::Map<Eigen::VectorXd>(rv.data(), static_cast<Eigen::Index>(rv.size()));
    if (jac) {
      jac->resize(static_cast<Eigen::Index>(jr.size()), n);
      for (std::size_t r = 0; r < jr.size(); ++r) jac->row(static_cast<Eigen::Index>(r)) = jr[r];
    }
  }

  double gain(int b, const Eigen::VectorXd& th) const { return gain0_[b] * portable::exp(th[b]); }

  // rms relative misfit of the absolute rates.
  double data_rms(const Eigen::VectorXd& th) const {
    double ss = 0;
    std::size_t count = 0;
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd sim = gain(b, th) * rates(b, qe(b, th));
      for (Eigen::Index i : p_.valid[b]) {
        const double e = sim[i] / data_.rates(b, i) - 1;
        ss += e * e, ++count;
      }
    }
    return std::sqrt(ss / static_cast<double>(count));
  }

 private:
  Eigen::VectorXd rates(int b, const Eigen::VectorXd& q) const {
    return profile_.dn_per_electron()[b] * (p_.radiance * q);
  }

  const CameraProfile& profile_;
  const CalibrationRates& data_;
  const Problem& p_;
  const RegularisedOptions& o_;
  Eigen::MatrixXd q0_, leak_, use_, rho0_;
  Eigen::ArrayXd x_;
  Eigen::VectorXd gain0_;
  std::vector<int> side_;
  static constexpr int kPerBand = 3;  // tilt, curvature, shift
  Eigen::VectorXd sigma_;
  int nb_ = 0;
  Eigen::Index nk_ = 0;
};

// Levenberg-Marquardt with the leak bumps bounded below by zero: a bump at its bound whose
// gradient points outwards is held there (active set), and steps are projected. Returns the
// iterations taken.
int levenberg_marquardt(const RegularisedModel& model, Eigen::VectorXd& th, int max_iterations) {
  const Eigen::Index n = model.size(), lo = model.leak_offset();
  Eigen::VectorXd res, res_new;
  Eigen::MatrixXd jac;
  model.evaluate(th, res, &jac);
  double cost = res.squaredNorm(), mu = 1e-3;
  int it = 0;
  bool converged = false;
  for (; it < max_iterations && !converged; ++it) {
    const Eigen::VectorXd grad = jac.transpose() * res;
    std::vector<Eigen::Index> free;
    for (Eigen::Index k = 0; k < n; ++k)
      if (!model.fixed(k) && (k < lo || th[k] > 0 || grad[k] < 0)) free.push_back(k);
    const auto nf = static_cast<Eigen::Index>(free.size());
    Eigen::MatrixXd jf(jac.rows(), nf);
    Eigen::VectorXd gf(nf);
    for (Eigen::Index c = 0; c < nf; ++c) jf.col(c) = jac.col(free[c]), gf[c] = grad[free[c]];
    const Eigen::MatrixXd h = jf.transpose() * jf;
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      Eigen::MatrixXd a = h;
      a.diagonal() += mu * (h.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd step = a.ldlt().solve(-gf);
      Eigen::VectorXd trial = th;
      for (Eigen::Index c = 0; c < nf; ++c) trial[free[c]] += step[c];
      trial.tail(n - lo) = trial.tail(n - lo).cwiseMax(0.0);
      model.evaluate(trial, res_new, nullptr);
      const double c_new = res_new.squaredNorm();
      if (c_new < cost) {
        const double gain = cost - c_new;
        th = trial, mu = std::max(mu / 3, 1e-9);
        improved = true;
        converged = gain < 1e-10 * cost + 1e-14;
        cost = c_new;
        model.evaluate(th, res, &jac);
      } else {
        mu *= 4;
      }
    }
    if (!improved) break;
  }
  return it;
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

QeFitResult fit_qe_regularised(const CameraProfile& profile, const CalibrationRates& data,
                               const RegularisedOptions& options) {
  const auto start = Clock::now();
  const Problem p = prepare(profile, data);
  RegularisedOptions o = options;
  Eigen::VectorXd th;
  int iterations = 0;
  // Reweighting: the data's weight against the priors is 1 / relative_noise; refit with the
  // misfit actually reached (noise-free data earn tighter fits, noisy data stronger priors).
  for (int pass = 0; pass < std::max(1, options.noise_passes); ++pass) {
    const RegularisedModel model(profile, data, p, o);
    if (th.size() == 0) th = Eigen::VectorXd::Zero(model.size());
    iterations += levenberg_marquardt(model, th, o.max_iterations);
    const double misfit = std::clamp(model.data_rms(th), options.min_relative_noise, 0.05);
    if (std::abs(portable::log(misfit / o.relative_noise)) < portable::log(1.5)) break;
    o.relative_noise = misfit;
  }
  const RegularisedModel model(profile, data, p, o);
  QeFitResult r;
  r.solver = QeSolver::kRegularised;
  r.system_qe.resize(profile.band_count(), profile.grid.size());
  r.gains.resize(profile.band_count());
  for (int b = 0; b < profile.band_count(); ++b) {
    r.system_qe.row(b) = model.qe(b, th).cwiseMin(1.0).transpose();
    r.gains[b] = model.gain(b, th);
  }
  r.diagnostics.iterations = iterations;
  finish(profile, p, data, start, r);
  return r;
}

QeFitResult fit_qe(const CameraProfile& profile, const CalibrationRates& data,
                   const QeFitOptions& options) {
  return options.solver == QeSolver::kPaper
             ? fit_qe_paper(profile, data, options.paper)
             : fit_qe_regularised(profile, data, options.regularised);
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
