// Wavelength bases of the regularised QE solve (qe_regularised.cpp): the leak bumps it fits,
// and the shape changes beyond its parameters that it fits jointly, held by their priors.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "pyrocam/calibration/qe_fit.h"

namespace pyrocam::qe_detail {

// Leak bumps: raised cosines of half width `spacing` stepping away from the pass band edges,
// zero inside the pass band (a leak is what the filter lets through where it should block).
// `side` marks which blocking region each bump is in, for the smoothness penalty.
Eigen::MatrixXd leak_basis(const CameraProfile& profile, double spacing, std::vector<int>& side);

// Shape changes the model's parameters cannot make (a filter edge's exact form, a coating's
// ripple, a leak's shape): each band's QE times raised-cosine bumps along the wavelengths, and
// leaks of any shape outside the pass band, each amplitude an independent N(0, sigma^2). The
// data cannot tell them from the parameters in the furnace range; fitted jointly, held by their
// priors, and sampled in the posterior, they are held where the furnace sees them and keep their
// prior spread where it does not: the uncertainty of a reading far above the furnace range.
struct Discrepancy {
  std::vector<Eigen::MatrixXd> dq;  // per band: d Q_b / d delta, wavelengths x parameters
  Eigen::VectorXd sigma;
  Eigen::Index additive_leaks = 0;  // the last amplitudes: leaks, transmission added (>= 0)
  // Per band: the amplitudes that change it (its own shape changes and the leaks), and dq's
  // columns of them side by side.
  std::vector<std::vector<Eigen::Index>> used;
  std::vector<Eigen::MatrixXd> dq_used;
};

// The basis around the QE `qe` (bands x wavelengths); empty when the options turn it off.
Discrepancy discrepancy_basis(const CameraProfile& profile, const Eigen::MatrixXd& qe,
                              const RegularisedOptions& o);

// sum_k dq_b(:, k) delta_k for every band: bands x wavelengths.
Eigen::MatrixXd shape_change(const Discrepancy& shape, const Eigen::VectorXd& delta);

}  // namespace pyrocam::qe_detail
