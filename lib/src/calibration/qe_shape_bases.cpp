// Wavelength bases of the regularised QE solve (see qe_shape_bases.h).
#include "calibration/qe_shape_bases.h"

#include <cmath>

#include "detail/portable_math.h"

namespace pyrocam::qe_detail {

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

Discrepancy discrepancy_basis(const CameraProfile& profile, const Eigen::MatrixXd& qe,
                              const RegularisedOptions& o) {
  Discrepancy d;
  const auto bands = qe.rows();
  const double spacing = o.discrepancy_spacing_nm;
  if (o.discrepancy_sigma <= 0 || spacing <= 0) return d;
  const Eigen::ArrayXd nm = profile.grid.nm().array();
  std::vector<std::pair<Eigen::Index, Eigen::VectorXd>> columns;  // band, d Q_b
  for (double c = profile.grid.start_nm(); c <= profile.grid.stop_nm() + 1e-9; c += spacing) {
    const Eigen::ArrayXd x = ((nm - c) / spacing).abs();
    // portable::cos, not Eigen's: the fit must give the same bits on every machine.
    const Eigen::ArrayXd bump =
        x.unaryExpr([](double v) { return v < 1 ? 0.5 + 0.5 * portable::cos(M_PI * v) : 0.0; });
    for (Eigen::Index b = 0; b < bands; ++b) {
      const Eigen::VectorXd change = (qe.row(b).transpose().array() * bump).matrix();
      if (change.maxCoeff() > 1e-3 * qe.row(b).maxCoeff()) columns.emplace_back(b, change);
    }
  }
  const auto m = static_cast<Eigen::Index>(columns.size());
  // Leaks of any shape outside the pass band, common to all bands (additive transmission).
  std::vector<int> side;
  const Eigen::MatrixXd leak = o.discrepancy_leak > 0
                                   ? leak_basis(profile, o.discrepancy_leak_spacing_nm, side)
                                   : Eigen::MatrixXd(qe.cols(), 0);
  d.dq.assign(static_cast<std::size_t>(bands), Eigen::MatrixXd::Zero(qe.cols(), m + leak.cols()));
  for (Eigen::Index k = 0; k < m; ++k)
    d.dq[static_cast<std::size_t>(columns[k].first)].col(k) = columns[k].second;
  for (Eigen::Index b = 0; b < bands; ++b)
    d.dq[static_cast<std::size_t>(b)].rightCols(leak.cols()) =
        leak.array().colwise() * profile.sensor_qe.row(b).transpose().array();
  d.sigma.resize(m + leak.cols());
  d.sigma.head(m).setConstant(o.discrepancy_sigma);
  d.sigma.tail(leak.cols()).setConstant(o.discrepancy_leak);
  d.additive_leaks = leak.cols();
  for (const Eigen::MatrixXd& dq_b : d.dq) {
    std::vector<Eigen::Index> used;
    for (Eigen::Index c = 0; c < dq_b.cols(); ++c)
      if (!dq_b.col(c).isZero(0)) used.push_back(c);
    d.dq_used.push_back(dq_b(Eigen::all, used));
    d.used.push_back(std::move(used));
  }
  return d;
}

Eigen::MatrixXd shape_change(const Discrepancy& shape, const Eigen::VectorXd& delta) {
  Eigen::MatrixXd change(static_cast<Eigen::Index>(shape.dq.size()),
                         shape.dq.empty() ? 0 : shape.dq[0].rows());
  for (std::size_t b = 0; b < shape.dq.size(); ++b)
    change.row(static_cast<Eigen::Index>(b)) =
        (shape.dq_used[b] * delta(shape.used[b])).transpose();
  return change;
}

}  // namespace pyrocam::qe_detail
