#include "pyrocam/core/locus.h"

#include <cmath>

#include "detail/two_halves.h"

namespace pyrocam {

Eigen::VectorXd CameraModel::rates(double temperature_c, double emissivity) const {
  return signal_rates(profile, system_qe, celsius_to_kelvin(temperature_c), emissivity)
      .cwiseProduct(band_scale);
}

Locus make_locus(const CameraModel& camera, double min_c, double max_c, double step_c) {
  const auto n = static_cast<Eigen::Index>(std::floor((max_c - min_c) / step_c + 1e-9)) + 1;
  Locus l;
  l.temperature_c.resize(n);
  l.rates.resize(n, camera.profile.band_count());
  l.ratios.resize(n, static_cast<Eigen::Index>(camera.profile.normalisation.numerators.size()));
  const auto rows = [&](Eigen::Index from, Eigen::Index to) {
    for (Eigen::Index i = from; i < to; ++i) {
      l.temperature_c[i] = min_c + static_cast<double>(i) * step_c;
      const Eigen::VectorXd r = camera.rates(l.temperature_c[i]);
      l.rates.row(i) = r.transpose();
      l.ratios.row(i) = normalised_ratios(camera.profile.normalisation, r).transpose();
    }
  };
  // The estimators build a locus of thousands of rows when an element starts.
  detail::in_two_halves(n, Eigen::Index{512}, rows);
  return l;
}

}  // namespace pyrocam
