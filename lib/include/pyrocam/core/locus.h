// The synthetic Planckian locus of a camera (METHOD.md section 5): modelled band signals and
// their normalised ratios from T_min to T_max.
#pragma once

#include <Eigen/Core>

#include "pyrocam/core/profile.h"

namespace pyrocam {

// A camera as the calibration knows it: profile, system QE and the per-band scale k_b that
// maps modelled onto measured rates.
struct CameraModel {
  CameraProfile profile;
  Eigen::MatrixXd system_qe;   // bands x wavelengths
  Eigen::VectorXd band_scale;  // k_b (1 = the profile's gains are exact)

  // Modelled dark-subtracted signal rate per band, DN/s, for a graybody.
  Eigen::VectorXd rates(double temperature_c, double emissivity = 1.0) const;
};

struct Locus {
  Eigen::VectorXd temperature_c;  // ascending
  Eigen::MatrixXd rates;          // samples x bands, DN/s at emissivity 1
  Eigen::MatrixXd ratios;         // samples x normalisation numerators

  Eigen::Index size() const { return temperature_c.size(); }
};

Locus make_locus(const CameraModel& camera, double min_c = 500, double max_c = 3500,
                 double step_c = 1);

}  // namespace pyrocam
