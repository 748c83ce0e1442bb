// The likelihood fit's definition (make_exhaustive_likelihood_estimator): the scan of every
// sample, against which the fast fit (likelihood_estimator.cpp) is tested.
#include <algorithm>
#include <cmath>
#include <memory>
#include <utility>
#include <vector>

#include "runtime/estimator_kinds.h"
#include "runtime/likelihood_fit.h"

namespace pyrocam {
namespace {

// The definition: every coarse sample and every 1 degC sample of each refinement window.
class ExhaustiveLikelihoodEstimator : public LikelihoodFit {
 public:
  using LikelihoodFit::LikelihoodFit;

  double temperature_c(const double* s) const override {
    Weighted px;
    if (!enough_bands(weigh(s, px), px)) return NAN;
    const Eigen::Index n = locus_.size();
    std::vector<double> c;
    for (Eigen::Index i = 0; i < n; i += kCoarse) c.push_back(chi2(i, px));
    std::vector<Minimum> refined;
    for (std::size_t k = 0; k < c.size(); ++k) {
      if (!((k == 0 || c[k] <= c[k - 1]) && (k + 1 == c.size() || c[k] <= c[k + 1]))) continue;
      const Eigen::Index around = static_cast<Eigen::Index>(k) * kCoarse;
      Minimum best{around, chi2(around, px), NAN, NAN};
      const Eigen::Index lo = std::max<Eigen::Index>(0, around - kCoarse);
      const Eigen::Index hi = std::min<Eigen::Index>(n - 1, around + kCoarse);
      for (Eigen::Index i = lo; i <= hi; ++i) {
        const double v = chi2(i, px);
        if (v < best.chi2) best = {i, v, NAN, NAN};
      }
      refined.push_back(best);
    }
    return decide(refined.data(), refined.size(), px);
  }
};

}  // namespace

std::unique_ptr<TemperatureEstimator> make_exhaustive_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model) {
  return std::make_unique<ExhaustiveLikelihoodEstimator>(std::move(model));
}

}  // namespace pyrocam
