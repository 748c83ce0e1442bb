// The regularised QE solve's models (see RegularisedOptions): a physical model of how a unit
// differs from its datasheet, its residuals and Jacobian against the furnace rates and the
// reference sources, and the same with the discrepancy's shape changes as parameters too. The
// fits that use them are in qe_regularised.cpp.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "calibration/qe_problem.h"
#include "calibration/qe_shape_bases.h"
#include "detail/curve_warp.h"
#include "detail/portable_math.h"
#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam::qe_detail {

// Parameter layout: log gains | per band (tilt, curvature, shift) | common (tilt, lower edge,
// upper edge) | leak bumps | furnace temperature offsets | per reference (log scale, offset).
class RegularisedModel {
 public:
  static constexpr int kPerBand = 3, kCommon = 3;

  RegularisedModel(const CameraProfile& profile, const CalibrationRates& data, const Problem& p,
                   const RegularisedOptions& o)
      : profile_(profile), data_(data), p_(p), o_(o), q0_(profile.system_qe()) {
    nb_ = profile.band_count();
    leak_ = leak_basis(profile, o.leak_spacing_nm, side_);
    nk_ = leak_.cols();
    nt_ = static_cast<Eigen::Index>(data.temperatures_c.size());
    nr_ = static_cast<Eigen::Index>(data.references.size());
    const double lo = profile.filter_pass_band_nm[0], hi = profile.filter_pass_band_nm[1];
    const Eigen::ArrayXd nm = profile.grid.nm().array();
    x_ = (nm - 0.5 * (lo + hi)) / 100.0;
    edge_weight_ = ((nm - lo) / (hi - lo)).min(1.0).max(0.0);
    for (const ReferenceRates& r : data.references) ref_t_.push_back(r.temperature_c);
    gain0_ = least_squares_gains(profile, p, q0_, data);
    set_priors(data);
  }

  Eigen::Index size() const { return common_offset() + kCommon + nk_ + nt_ + 2 * nr_; }
  Eigen::Index common_offset() const { return nb_ + nb_ * kPerBand; }
  Eigen::Index leak_offset() const { return common_offset() + kCommon; }
  Eigen::Index furnace_offset() const { return leak_offset() + nk_; }
  Eigen::Index reference_offset() const { return furnace_offset() + nt_; }
  bool fixed(Eigen::Index k) const { return sigma_[k] == 0; }
  int band_count() const { return nb_; }
  Eigen::Index wavelengths() const { return q0_.cols(); }
  bool bounded(Eigen::Index k) const { return k >= leak_offset() && k < furnace_offset(); }
  // A fixed change of each band's QE beyond the model's parameters (bands x wavelengths), added
  // before the clamp: the discrepancy part of the joint fit (fit_qe_regularised).
  void set_shape_change(const Eigen::MatrixXd& change) { shape_change_ = change; }

  Eigen::VectorXd start() const {
    Eigen::VectorXd th = Eigen::VectorXd::Zero(size());
    const Eigen::MatrixXd rad = radiance_rows(profile_, ref_t_);
    for (Eigen::Index r = 0; r < nr_; ++r) {  // each reference's scale from the datasheet
      double measured = 0, modelled = 0;
      for (int b = 0; b < nb_; ++b)
        if (usable(data_.references[r].rates[b]))
          measured += data_.references[r].rates[b],
              modelled += gain0_[b] * g(b) * rad.row(r).dot(q0_.row(b));
      th[reference_offset() + 2 * r] = portable::log(measured / modelled);
    }
    return th;
  }

  // The optics with moved pass-band edges, and its derivatives by the two edge shifts.
  Eigen::VectorXd optics(const Eigen::VectorXd& th, Eigen::MatrixXd* d = nullptr) const {
    const double d_lo = th[common_offset() + 1], d_hi = th[common_offset() + 2];
    const auto warp = [&](double a, double b) {
      return detail::warp_curve(
          profile_.optics_transmission, profile_.grid,
          profile_.grid.nm().array() - (a * (1 - edge_weight_) + b * edge_weight_));
    };
    if (d) {
      const double eps = 0.5 * profile_.grid.step_nm();
      d->resize(profile_.grid.size(), 2);
      d->col(0) = (warp(d_lo + eps, d_hi) - warp(d_lo - eps, d_hi)) / (2 * eps);
      d->col(1) = (warp(d_lo, d_hi + eps) - warp(d_lo, d_hi - eps)) / (2 * eps);
    }
    return d_lo == 0 && d_hi == 0 ? Eigen::VectorXd(profile_.optics_transmission)
                                  : warp(d_lo, d_hi);
  }

  // Q_b(theta) and its derivatives: wavelengths x [per band, common, leak bumps].
  Eigen::VectorXd qe(int b, const Eigen::VectorXd& th, const Eigen::VectorXd& opt,
                     const Eigen::MatrixXd* dopt, Eigen::MatrixXd* dq = nullptr) const {
    const double* pb = th.data() + nb_ + b * kPerBand;
    const double tau = th[common_offset()];
    const Eigen::VectorXd sensor = profile_.sensor_qe.row(b).transpose();
    const Eigen::ArrayXd s_shifted =
        (pb[2] != 0 ? detail::shift_curve(sensor, profile_.grid, pb[2]) : sensor).array();
    const Eigen::ArrayXd band = 1.0 + pb[0] * x_ + pb[1] * x_.square();
    const Eigen::ArrayXd common = 1.0 + tau * x_;
    const Eigen::ArrayXd s = s_shifted * opt.array();
    const Eigen::VectorXd leak = leak_ * th.segment(leak_offset(), nk_);
    Eigen::VectorXd q = (s * band * common).matrix() + sensor.cwiseProduct(leak);
    if (shape_change_.rows() > 0) q += shape_change_.row(b).transpose();
    const Eigen::ArrayXd positive = (q.array() > 0).cast<double>();  // Q >= 0 by clamping
    q = q.cwiseMax(0.0);
    if (dq) {
      dq->resize(q.size(), kPerBand + kCommon + nk_);
      dq->col(0) = (s * x_ * common * positive).matrix();
      dq->col(1) = (s * x_.square() * common * positive).matrix();
      const double eps = 0.5 * profile_.grid.step_nm();
      dq->col(2) = ((detail::shift_curve(sensor, profile_.grid, pb[2] + eps) -
                     detail::shift_curve(sensor, profile_.grid, pb[2] - eps))
                        .array() /
                    (2 * eps) * opt.array() * band * common * positive)
                       .matrix();
      dq->col(3) = (s * band * x_ * positive).matrix();
      for (int e = 0; e < 2; ++e)
        dq->col(4 + e) = (s_shifted * dopt->col(e).array() * band * common * positive).matrix();
      dq->rightCols(nk_) = (leak_.array().colwise() * (sensor.array() * positive)).matrix();
    }
    return q;
  }

  Eigen::VectorXd qe(int b, const Eigen::VectorXd& th) const {
    return qe(b, th, optics(th), nullptr);
  }

  // d Q_b / d theta at theta over the parameters that shape Q_b (qe_parameters picks them).
  Eigen::MatrixXd qe_jacobian(int b, const Eigen::VectorXd& th) const {
    Eigen::MatrixXd dopt, dq;
    qe(b, th, optics(th, &dopt), &dopt, &dq);
    return dq;
  }
  Eigen::VectorXd qe_parameters(int b, const Eigen::VectorXd& th) const {
    Eigen::VectorXd p(kPerBand + kCommon + nk_);
    p << th.segment(nb_ + b * kPerBand, kPerBand), th.segment(common_offset(), kCommon),
        th.segment(leak_offset(), nk_);
    return p;
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
    Eigen::MatrixXd rad, drad, rrad, drrad, dopt, dq;
    data_radiance(th, rad, drad, rrad, drrad);
    const Eigen::VectorXd opt = optics(th, jac ? &dopt : nullptr);
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd q = qe(b, th, opt, &dopt, jac ? &dq : nullptr);
      const double kg = gain(b, th) * g(b);
      const Eigen::Index off = nb_ + b * kPerBand;
      // Every radiance row times the QE's derivatives at once (wdq.row(i) = w_i dq).
      Eigen::MatrixXd rad_dq, rrad_dq;
      if (jac) rad_dq.noalias() = rad * dq, rrad_dq.noalias() = rrad * dq;
      // One observation: value = kg * scale * w.q against `measured`, in units of its noise.
      const auto observe = [&](const Eigen::RowVectorXd& w, const Eigen::RowVectorXd& dw,
                               const Eigen::MatrixXd& wdq, Eigen::Index w_row, double scale,
                               double measured, Eigen::Index t_param, Eigen::Index scale_param) {
        const double value = kg * scale * w.dot(q), unit = 1.0 / (o_.relative_noise * measured);
        Eigen::RowVectorXd j;
        if (jac) {
          j = Eigen::RowVectorXd::Zero(n);
          const Eigen::RowVectorXd d = kg * scale * unit * wdq.row(w_row);
          j[b] = value * unit;
          j.segment(off, kPerBand) = d.head(kPerBand);
          j.segment(common_offset(), kCommon) = d.segment(kPerBand, kCommon);
          j.segment(leak_offset(), nk_) = d.tail(nk_);
          j[t_param] = kg * scale * unit * dw.dot(q);
          if (scale_param >= 0) j[scale_param] = value * unit;
        }
        row((value - measured) * unit, std::move(j));
      };
      for (Eigen::Index i : p_.valid[b])
        observe(rad.row(i), drad.row(i), rad_dq, i, 1.0, data_.rates(b, i), furnace_offset() + i,
                -1);
      for (Eigen::Index r = 0; r < nr_; ++r) {
        const double m = data_.references[r].rates[b];
        if (!usable(m)) continue;
        const Eigen::Index c = reference_offset() + 2 * r;
        observe(rrad.row(r), drrad.row(r), rrad_dq, r, portable::exp(th[c]), m, c + 1, c);
      }
    }
    priors(th, n, jac != nullptr, row);
    res = Eigen::Map<Eigen::VectorXd>(rv.data(), static_cast<Eigen::Index>(rv.size()));
    if (jac) {
      jac->resize(static_cast<Eigen::Index>(jr.size()), n);
      for (std::size_t r = 0; r < jr.size(); ++r) jac->row(static_cast<Eigen::Index>(r)) = jr[r];
    }
  }

  double gain(int b, const Eigen::VectorXd& th) const { return gain0_[b] * portable::exp(th[b]); }

  // evaluate()'s data rows (furnace, then references, band by band, before the priors)
  // differentiated by linear changes of the QE: dq[b] holds d Q_b / d delta, wavelengths x m.
  Eigen::MatrixXd data_jacobian(const Eigen::VectorXd& th, const Discrepancy& shape) const {
    Eigen::MatrixXd rad, drad, rrad, drrad;
    data_radiance(th, rad, drad, rrad, drrad);
    const Eigen::VectorXd opt = optics(th);
    Eigen::Index count = 0;
    for (int b = 0; b < nb_; ++b) {
      count += static_cast<Eigen::Index>(p_.valid[b].size());
      for (Eigen::Index r = 0; r < nr_; ++r) count += usable(data_.references[r].rates[b]);
    }
    Eigen::MatrixXd j = Eigen::MatrixXd::Zero(count, shape.sigma.size());
    Eigen::Index row = 0;
    for (int b = 0; b < nb_; ++b) {
      const double kg = gain(b, th) * g(b);
      // Each data row's radiance in its own units; where the QE is clamped at 0 a small change
      // of it changes nothing.
      Eigen::MatrixXd w(static_cast<Eigen::Index>(p_.valid[b].size()) + nr_, rad.cols());
      Eigen::Index rows = 0;
      for (Eigen::Index i : p_.valid[b])
        w.row(rows++) = kg / (o_.relative_noise * data_.rates(b, i)) * rad.row(i);
      for (Eigen::Index r = 0; r < nr_; ++r) {
        const double m = data_.references[r].rates[b];
        if (!usable(m)) continue;
        const double scale = portable::exp(th[reference_offset() + 2 * r]);
        w.row(rows++) = kg * scale / (o_.relative_noise * m) * rrad.row(r);
      }
      const Eigen::VectorXd positive = (qe(b, th, opt, nullptr).array() > 0).cast<double>();
      const auto k = static_cast<std::size_t>(b);
      j(Eigen::seqN(row, rows), shape.used[k]) =
          (w.topRows(rows) * positive.asDiagonal()) * shape.dq_used[k];
      row += rows;
    }
    return j;
  }

  // Squared relative misfits of the furnace rates and of the reference rates (each reference at
  // its fitted scale and temperature), summed, and their counts.
  struct DataMisfit {
    double furnace_ss = 0, reference_ss = 0;
    std::size_t furnace_n = 0, reference_n = 0;
  };
  DataMisfit data_misfit(const Eigen::VectorXd& th) const {
    Eigen::MatrixXd rad, drad, rrad, drrad;
    data_radiance(th, rad, drad, rrad, drrad);
    const Eigen::VectorXd opt = optics(th);
    DataMisfit m;
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd q = qe(b, th, opt, nullptr);
      const double kg = gain(b, th) * g(b);
      const Eigen::VectorXd sim = kg * (rad * q), ref_sim = kg * (rrad * q);
      for (Eigen::Index i : p_.valid[b]) {
        const double e = sim[i] / data_.rates(b, i) - 1;
        m.furnace_ss += e * e, ++m.furnace_n;
      }
      for (Eigen::Index r = 0; r < nr_; ++r) {
        const double measured = data_.references[r].rates[b];
        if (!usable(measured)) continue;
        const double e = portable::exp(th[reference_offset() + 2 * r]) * ref_sim[r] / measured - 1;
        m.reference_ss += e * e, ++m.reference_n;
      }
    }
    return m;
  }

  // The leak bumps the priors leave free.
  int free_leak_bumps() const {
    int n = 0;
    for (Eigen::Index k = leak_offset(); k < furnace_offset(); ++k) n += !fixed(k);
    return n;
  }

  // rms relative misfit of the furnace rates.
  double data_rms(const Eigen::VectorXd& th) const {
    const DataMisfit m = data_misfit(th);
    return std::sqrt(m.furnace_ss / static_cast<double>(m.furnace_n));
  }

 private:
  double g(int b) const { return profile_.dn_per_electron()[b]; }

  // Radiance rows of the furnace steps and of the references at their fitted temperatures.
  void data_radiance(const Eigen::VectorXd& th, Eigen::MatrixXd& rad, Eigen::MatrixXd& drad,
                     Eigen::MatrixXd& rrad, Eigen::MatrixXd& drrad) const {
    radiance(data_.temperatures_c, th.segment(furnace_offset(), nt_), rad, drad);
    Eigen::VectorXd ref_offsets(nr_);
    for (Eigen::Index r = 0; r < nr_; ++r) ref_offsets[r] = th[reference_offset() + 2 * r + 1];
    radiance(ref_t_, ref_offsets, rrad, drrad);
  }

  // Radiance rows at nominal + offset temperatures, and their derivatives per degC.
  void radiance(const std::vector<double>& nominal_c, const Eigen::VectorXd& offset_c,
                Eigen::MatrixXd& rad, Eigen::MatrixXd& drad) const {
    std::vector<double> t(nominal_c), up(nominal_c), down(nominal_c);
    for (std::size_t i = 0; i < t.size(); ++i) {
      t[i] += offset_c[static_cast<Eigen::Index>(i)];
      up[i] = t[i] + 0.05, down[i] = t[i] - 0.05;
    }
    rad = radiance_rows(profile_, t);
    drad = (radiance_rows(profile_, up) - radiance_rows(profile_, down)) / 0.1;
  }

  void set_priors(const CalibrationRates& data) {
    // Prior sigmas, one per parameter (0 = fixed, infinity = free). Shift only for narrow bands.
    sigma_ = Eigen::VectorXd::Zero(size());
    for (int b = 0; b < nb_; ++b) {
      const Eigen::VectorXd q = q0_.row(b).transpose();
      const double fwhm =
          static_cast<double>((q.array() >= 0.5 * q.maxCoeff()).count()) * profile_.grid.step_nm();
      const Eigen::Index off = nb_ + b * kPerBand;
      sigma_[b] = std::numeric_limits<double>::infinity();  // gains: free, no prior
      sigma_[off] = o_.tilt_sigma;
      sigma_[off + 1] = o_.curvature_sigma;
      sigma_[off + 2] = fwhm < o_.narrow_band_fwhm_nm ? o_.shift_sigma_nm : 0.0;
    }
    sigma_[common_offset()] = o_.common_tilt_sigma;
    sigma_[common_offset() + 1] = sigma_[common_offset() + 2] = o_.edge_shift_sigma_nm;
    // Leak bumps: sigma divided by their leverage on the high range (see the options).
    const Eigen::MatrixXd use = radiance_rows(profile_, o_.use_temperatures_c);
    Eigen::Index hottest_use = 0;
    for (Eigen::Index e = 0; e < use.rows(); ++e)
      if (o_.use_temperatures_c[e] > o_.use_temperatures_c[hottest_use]) hottest_use = e;
    const Eigen::Index hot_cal = *std::max_element(
        p_.reference.begin(), p_.reference.end(),
        [&](auto a, auto c) { return data.temperatures_c[a] < data.temperatures_c[c]; });
    for (Eigen::Index k = 0; k < nk_; ++k) {
      double leverage = 1;
      for (int b = 0; b < nb_ && use.rows() > 0; ++b) {
        const Eigen::VectorXd bump =
            profile_.sensor_qe.row(b).transpose().cwiseProduct(leak_.col(k));
        const Eigen::VectorXd q = q0_.row(b).transpose();
        const double cal = p_.radiance.row(hot_cal).dot(bump) / p_.radiance.row(hot_cal).dot(q);
        const double u = use.row(hottest_use).dot(bump) / use.row(hottest_use).dot(q);
        if (cal > 0) leverage = std::max(leverage, u / cal);
      }
      sigma_[leak_offset() + k] = o_.leak_sigma / leverage;
    }
    // Each step's offset on its own, with no hold on their mean or trend: a thermocouple's
    // scale is known no better than the steps' scatter (class 1: +-4.4 degC at 1100 degC), and
    // the band ratios tell an offset too. Held at zero (to 0.05 degC), the chance trend of the
    // scatter went into the QE and bent the extrapolation (units like the datasheet, each step
    // 1 degC off, noise-free rates: 17 degC rms at 1800-2600 degC, colour; 1 without the hold).
    sigma_.segment(furnace_offset(), nt_).setConstant(o_.furnace_temperature_sigma_c);
    for (Eigen::Index r = 0; r < nr_; ++r) {
      sigma_[reference_offset() + 2 * r] = std::numeric_limits<double>::infinity();
      sigma_[reference_offset() + 2 * r + 1] = data.references[r].temperature_uncertainty_c;
    }
  }

  template <class Row>
  void priors(const Eigen::VectorXd& th, Eigen::Index n, bool with_jacobian, Row& row) const {
    // Gaussian priors on everything but the free gains and scales.
    for (Eigen::Index k = nb_; k < n; ++k) {
      if (fixed(k) || !std::isfinite(sigma_[k])) continue;
      Eigen::RowVectorXd j;
      if (with_jacobian) j = Eigen::RowVectorXd::Zero(n), j[k] = 1 / sigma_[k];
      row(th[k] / sigma_[k], std::move(j));
    }
    // Leaks are smooth along each blocking region.
    const Eigen::Index lo = leak_offset();
    for (Eigen::Index k = 1; k + 1 < nk_; ++k) {
      if (side_[k - 1] != side_[k] || side_[k + 1] != side_[k]) continue;
      const double s = 1 / o_.leak_curvature_sigma;
      Eigen::RowVectorXd j;
      if (with_jacobian) {
        j = Eigen::RowVectorXd::Zero(n);
        j[lo + k - 1] = s, j[lo + k] = -2 * s, j[lo + k + 1] = s;
      }
      row((th[lo + k - 1] - 2 * th[lo + k] + th[lo + k + 1]) * s, std::move(j));
    }
  }

  const CameraProfile& profile_;
  const CalibrationRates& data_;
  const Problem& p_;
  const RegularisedOptions& o_;
  Eigen::MatrixXd q0_, leak_, shape_change_;
  Eigen::ArrayXd x_, edge_weight_;
  Eigen::VectorXd gain0_, sigma_;
  std::vector<double> ref_t_;
  std::vector<int> side_;
  int nb_ = 0;
  Eigen::Index nk_ = 0, nt_ = 0, nr_ = 0;
};

// The regularised model with the discrepancy's amplitudes as parameters too, x = (theta, delta),
// each amplitude held by its prior: the joint fit (fit_qe_regularised). The additive leaks are
// bounded below by zero, as the model's own leaks: a transmission added where the filter should
// block (a band's QE falls through the relative shape changes). Negative ones only met the
// clamp at Q = 0, where the fit stalled.
class JointModel {
 public:
  JointModel(RegularisedModel& model, const Discrepancy& shape)
      : model_(model), shape_(shape), nt_(model.size()), nd_(shape.sigma.size()) {}

  Eigen::Index size() const { return nt_ + nd_; }
  bool fixed(Eigen::Index k) const { return k < nt_ && model_.fixed(k); }
  bool bounded(Eigen::Index k) const {
    return k < nt_ ? model_.bounded(k) : k >= size() - shape_.additive_leaks;
  }

  // Leaves the model with x's shape change.
  void evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& res, Eigen::MatrixXd* jac) const {
    const Eigen::VectorXd th = x.head(nt_), delta = x.tail(nd_);
    model_.set_shape_change(shape_change(shape_, delta));
    Eigen::VectorXd r;
    Eigen::MatrixXd j;
    model_.evaluate(th, r, jac ? &j : nullptr);
    res.resize(r.size() + nd_);
    res << r, delta.cwiseQuotient(shape_.sigma);
    if (!jac) return;
    jac->setZero(res.size(), size());
    jac->topLeftCorner(j.rows(), nt_) = j;
    if (nd_ == 0) return;
    // The data rows come first in the model's residual vector, its priors after them.
    const Eigen::MatrixXd jd = model_.data_jacobian(th, shape_);
    jac->block(0, nt_, jd.rows(), nd_) = jd;
    jac->bottomRightCorner(nd_, nd_) = shape_.sigma.cwiseInverse().asDiagonal();
  }

 private:
  RegularisedModel& model_;
  const Discrepancy& shape_;
  Eigen::Index nt_, nd_;
};

}  // namespace pyrocam::qe_detail
