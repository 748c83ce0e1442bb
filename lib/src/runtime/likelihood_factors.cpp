// Low-rank factors of the likelihood fit's locus (see likelihood_factors.h).
#include "runtime/likelihood_factors.h"

#include <algorithm>
#include <cstddef>

#include "runtime/likelihood_kernels.h"

namespace pyrocam {

namespace {

// An orthonormal basis (columns) of the rows of `left`, grown from the row left least explained
// until every row is within `tolerance` or the basis has max_rank columns. norms: the largest
// row error before each column was added, and the last one.
Eigen::MatrixXd row_basis(Eigen::MatrixXd left, int max_rank, double tolerance,
                          std::vector<double>& norms) {
  Eigen::MatrixXd v(left.cols(), 0);
  norms.clear();
  for (int r = 0; r < max_rank; ++r) {
    Eigen::Index worst;
    const double norm = left.rowwise().norm().maxCoeff(&worst);
    norms.push_back(norm);
    if (norm <= tolerance) break;
    Eigen::VectorXd dir = left.row(worst).transpose() / norm;
    for (int pass = 0; pass < 2; ++pass) dir -= v * (v.transpose() * dir);  // stay orthogonal
    dir.normalize();
    left -= (left * dir) * dir.transpose();
    v.conservativeResize(Eigen::NoChange, r + 1);
    v.col(r) = dir;
  }
  return v;
}

}  // namespace

void factor_locus(const Eigen::MatrixXd& a, const FactorLayout& layout, std::vector<double>& across,
                  int& rank, int& coarse_rank, std::vector<double>& along,
                  std::vector<float>& coarse_along, double* residual) {
  std::vector<double> norms;
  const Eigen::MatrixXd v =
      row_basis(a, std::min<int>(kMaxRank, static_cast<int>(a.cols())), layout.tolerance, norms);
  rank = static_cast<int>(v.cols());
  const auto coarse_enough = std::find_if(
      norms.begin(), norms.end(), [&](double norm) { return norm <= layout.coarse_tolerance; });
  coarse_rank = coarse_enough == norms.end() || coarse_enough == norms.begin()
                    ? rank
                    : static_cast<int>(coarse_enough - norms.begin());
  const Eigen::MatrixXd av = a * v;
  // From the stored factors, so that the bounds hold for what the fit computes.
  for (int part = 0; part < 2; ++part) {
    const int r = part == 0 ? coarse_rank : rank;
    const Eigen::MatrixXd off = a - av.leftCols(r) * v.leftCols(r).transpose();
    residual[part] = 2 * off.rowwise().norm().maxCoeff() + 1e-15;
  }
  const auto bands = static_cast<std::size_t>(a.cols());
  const auto stride = static_cast<std::size_t>(layout.stride);
  const auto coarse_stride = static_cast<std::size_t>(layout.coarse_stride);
  across.assign(bands * kMaxRank, 0.0);
  along.assign(static_cast<std::size_t>(rank) * stride, 0.0);
  coarse_along.assign(static_cast<std::size_t>(coarse_rank) * coarse_stride, 0.f);
  for (int r = 0; r < rank; ++r) {
    const auto rr = static_cast<std::size_t>(r);
    for (std::size_t b = 0; b < bands; ++b)
      across[b * kMaxRank + rr] = v(static_cast<Eigen::Index>(b), r);
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      along[rr * stride + static_cast<std::size_t>(i)] = av(i, r);
    if (r >= coarse_rank) continue;
    for (Eigen::Index j = 0; j < layout.coarse_count; ++j)
      coarse_along[rr * coarse_stride + static_cast<std::size_t>(j)] =
          static_cast<float>(av(j * layout.coarse_step, r));
  }
}

void factor_windows(const std::vector<double>& along, int rank, Eigen::Index samples,
                    const FactorLayout& layout, int& window_rank, std::vector<double>& basis,
                    std::vector<double>& coordinates, double& residual) {
  const Eigen::Index step = layout.coarse_step;
  const auto windows = static_cast<std::size_t>(layout.coarse_count);
  const auto room = static_cast<std::size_t>(layout.window_room);
  std::vector<Eigen::MatrixXd> rows(windows), bases(windows);
  std::vector<double> norms;
  window_rank = 1;
  for (std::size_t k = 0; k < windows; ++k) {
    const auto centre = static_cast<Eigen::Index>(k) * step;
    const Eigen::Index lo = std::max<Eigen::Index>(0, centre - step);
    const Eigen::Index hi = std::min<Eigen::Index>(samples - 1, centre + step);
    Eigen::MatrixXd& a = rows[k];
    a.resize(hi - lo + 1, rank);
    for (Eigen::Index i = 0; i < a.rows(); ++i)
      for (int r = 0; r < rank; ++r)
        a(i, r) = along[static_cast<std::size_t>(r * layout.stride + lo + i)];
    bases[k] = row_basis(a, std::min(rank, kMaxWindowRank), layout.tolerance, norms);
    window_rank = std::max(window_rank, static_cast<int>(bases[k].cols()));
  }
  basis.assign(windows * kMaxRank * kMaxWindowRank, 0.0);
  coordinates.assign(windows * static_cast<std::size_t>(window_rank) * room, 0.0);
  residual = 0;
  for (std::size_t k = 0; k < windows; ++k) {
    Eigen::MatrixXd v = Eigen::MatrixXd::Zero(rank, window_rank);
    v.leftCols(bases[k].cols()) = bases[k];
    const Eigen::MatrixXd av = rows[k] * v;
    // From the stored coordinates, so that the bounds hold for what the fit computes.
    const Eigen::MatrixXd off = rows[k] - av * v.transpose();
    residual = std::max(residual, 2 * off.rowwise().norm().maxCoeff() + 1e-15);
    for (int j = 0; j < window_rank; ++j) {
      const auto jj = static_cast<std::size_t>(j);
      for (int r = 0; r < rank; ++r)
        basis[(k * kMaxRank + static_cast<std::size_t>(r)) * kMaxWindowRank + jj] = v(r, j);
      for (Eigen::Index i = 0; i < av.rows(); ++i)
        coordinates[(k * static_cast<std::size_t>(window_rank) + jj) * room +
                    static_cast<std::size_t>(i)] = av(i, j);
    }
  }
}

}  // namespace pyrocam
