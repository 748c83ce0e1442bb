// The demosaicking blur's bias on a gradient. A matched kernel (demosaic.h) averages each band's
// signal over its footprint with the same second moment for every band, so a curved temperature
// field reads as the field seen through one blur. But a band's signal is close to exponential in
// temperature, so across a gradient the mean signal of a footprint is that of a hotter surface
// than its mean temperature: the reading is biased up by about
//   0.5 * kappa(T) * v * |grad T|^2,
// v the kernel's variance along each axis (1 pixel^2 for Bayer, 0.25 cell^2 for snapshot
// mosaics) and kappa(T) = cov_b(k_b, c_b) / var_b(k_b) over the bands, with k_b = d ln m_b / dT
// and c_b = m_b'' / m_b of the model's locus m_b(T): the slope of the band log signals that a
// free scale cannot absorb, regressed on their slopes, as a fit in log signals would read it.
// On the steep side of a melt pool (150 degC a pixel at 1400 degC, kappa about 0.016 / degC)
// that is +180 degC. The correction subtracts it, the gradient taken from the readings
// themselves (a Sobel difference over the pixels that read), so a corrected pixel reads the
// kernel-weighted mean temperature of its footprint. It leaves the curvature's share (half the
// Laplacian times v, the blur of the temperature field itself) as it is. On a uniform surface
// the readings' own noise makes a gradient too: about 0.19 kappa sigma^2 lower (sigma the
// per-pixel noise; 0.3 degC for 10 degC of noise at 1500 degC).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/runtime/demosaic.h"

namespace pyrocam {

struct ThermalModel;

class BlurBiasCorrection {
 public:
  // For the planes `method` gives on the model's mosaic; throws InputError unless it is matched
  // demosaicking (the other methods blur each band differently).
  BlurBiasCorrection(const ThermalModel& model, DemosaicMethod method);

  double kappa_per_c(double t_c) const;  // 1 / degC
  double variance_px2() const { return variance_px2_; }
  // The bias of a reading at t_c with the gradient (gx, gy), degC per output pixel.
  double bias_c(double t_c, double gx, double gy) const {
    return 0.5 * kappa_per_c(t_c) * variance_px2_ * (gx * gx + gy * gy);
  }

  // In place: CV_32F degC (NaN: no reading), or CV_16U 0.1 K codes (0: no reading). A reading
  // whose neighbours on one axis do not read takes no correction along it.
  void apply(cv::Mat& temperature_c) const;
  void apply_codes(cv::Mat& codes) const;

 private:
  template <class LoadRow, class StoreRow>
  void correct_rows(int rows, int cols, LoadRow load, StoreRow store) const;

  double min_c_ = 0, step_c_ = 1;
  std::vector<double> kappa_;     // per locus sample
  std::vector<float> row_kappa_;  // the same in single precision, and the last one again
  double variance_px2_ = 1;
};

}  // namespace pyrocam
