// The paper's comparison estimators (METHOD.md section 6): Ohno-style triangular interpolation
// on the modelled locus, and two-colour ratio pyrometry with blue subtraction.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "pyrocam/core/locus.h"

namespace pyrocam {

// Nearest locus sample in chromaticity (s_b / sum s), refined between its neighbours. Distances
// over all chromaticities but the last (which the others fix): (r, g) for a colour camera, as
// the paper's; with b as well the two directions would weigh differently.
class OhnoEstimator {
 public:
  explicit OhnoEstimator(const Locus& locus);
  // degC, NaN when the signals are not all finite and positive in sum.
  double temperature_c(const Eigen::VectorXd& signals) const;

 private:
  Eigen::VectorXd t_;
  Eigen::MatrixXd chroma_;  // samples x bands
};

struct TwoColourParams {
  double lambda_r_nm = 620;  // equivalent wavelengths (paper's starting values)
  double lambda_g_nm = 500;
  double gain = 1;                  // g in T = c2 (1/lr - 1/lg) / (5 ln(lg/lr) - ln(g R'/G'))
  double band_gain[3] = {1, 1, 1};  // R, G, B: measured -> datasheet-simulated scale
};

class TwoColourEstimator {
 public:
  TwoColourEstimator(TwoColourParams params, int r, int g, int b)
      : p_(params), r_(r), g_(g), b_(b) {}
  // R' = gR R - gB B, G' = gG G - gB B (blue taken as the near-infrared leak); NaN when R' or
  // G' is not positive.
  double temperature_c(const Eigen::VectorXd& signals) const;
  const TwoColourParams& params() const { return p_; }

  // The paper's two steps (section 2.10): band gains from measured vs datasheet-simulated
  // signals (line through the origin), the gain ratio g from the blue-subtracted ratios, then
  // both equivalent wavelengths by minimising the rms temperature error.
  static TwoColourEstimator fit(const std::vector<Eigen::VectorXd>& measured,
                                const std::vector<Eigen::VectorXd>& simulated,
                                const std::vector<double>& temperatures_c, int r, int g, int b);

 private:
  TwoColourParams p_;
  int r_, g_, b_;
};

// Minimises f from x0 by Nelder-Mead (simple, derivative-free; for a handful of parameters).
Eigen::VectorXd nelder_mead(const std::function<double(const Eigen::VectorXd&)>& f,
                            Eigen::VectorXd x0, const Eigen::VectorXd& step, int iterations = 2000);

}  // namespace pyrocam
