// Low-rank factors of the likelihood fit's normalised locus (likelihood_estimator.cpp): made once
// when the estimator is, read by its scan.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace pyrocam {

// Where the factors go: the locus's samples rows `stride` apart (padded), every `coarse_step`-th
// of them (coarse_count) for the coarse scan, `coarse_stride` apart; a refinement window's
// samples `window_room` apart. Factors are grown until the rows they leave are off by at most
// `tolerance` (the coarse ones: `coarse_tolerance`).
struct FactorLayout {
  Eigen::Index stride, coarse_count, coarse_stride, coarse_step, window_room;
  double coarse_tolerance, tolerance;
};

// Low-rank factors of a samples x bands matrix A ~ (A V) V^T, V orthonormal: across (bands x
// kMaxRank, V zero padded), along (rank x stride, A V rank after rank, zero padded) for the
// windows and coarse_along (coarse rank x coarse_stride, every coarse_step-th sample, single
// precision) for the coarse scan. V is grown greedily from the row A leaves least explained
// (pivoted Gram-Schmidt), so its first columns are the coarse factors.
// residual: the largest row error left by the coarse factors and by all of them.
void factor_locus(const Eigen::MatrixXd& a, const FactorLayout& layout, std::vector<double>& across,
                  int& rank, int& coarse_rank, std::vector<double>& along,
                  std::vector<float>& coarse_along, double* residual);

// A refinement window's rows of the factors (`along`, rank wide, coarse_step samples either side
// of a coarse sample, of `samples`) change smoothly over its 41 degC: they span few directions (5
// on the test model, where all factors take 11 or 12). Per window, an orthonormal basis of them
// grown as in factor_locus (basis: kMaxRank x kMaxWindowRank, zero padded, as to_window_basis
// reads it) and the rows' coordinates in it (coordinates: window_rank x window_room), so that a
// window's sums cost window_rank multiply-adds per sample instead of rank. residual: the largest
// row error the bases leave (on top of the factors' own); with a projection p = V^T (w s),
// |p| <= |w s|, the sums are off by at most |w s| times it. A model that needed more than
// kMaxWindowRank directions would only get looser bounds.
void factor_windows(const std::vector<double>& along, int rank, Eigen::Index samples,
                    const FactorLayout& layout, int& window_rank, std::vector<double>& basis,
                    std::vector<double>& coordinates, double& residual);

}  // namespace pyrocam
