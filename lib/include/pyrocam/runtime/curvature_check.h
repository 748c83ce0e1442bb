// No reading where the temperature field curves too sharply for matched demosaicking's kernels.
// Each band's kernel averages the samples of a footprint of +-2 pixels with the same second
// moment (demosaic.h), so a reading is that of the field blurred by the kernel: on a curved field
// it is off by half the Laplacian of the temperature times the kernel's variance (blur_bias.h),
// whatever the noise. On a hot spot a few pixels across (a spatter particle, a pool five pixels
// wide) that is hundreds of degrees: its one pixel that reads, the hottest, read 1709 degC where
// the spot was 1981 degC. The pixel's own band's samples at +-2 pixels give the Laplacian of its
// log signal, L = (sum of the four logs - 4 log of its own) / 4 per pixel^2, and L / k_b(T) the
// Laplacian of the temperature (k_b = d ln m_b / dT on the model's locus, at the reading); where
// half of it times the variance exceeds kCurvatureLimitC the pixel gets no reading. Smooth
// fields keep theirs: on the simulator's plates and melt pools nothing is taken.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/mosaic.h"

namespace pyrocam {

struct ThermalModel;

// The curvature's share of a reading beyond which a pixel has none, degC.
inline constexpr double kCurvatureLimitC = 100;

class CurvatureCheck {
 public:
  // For the model's locus on `layout` (the stream's Bayer phase). Throws InputError for a
  // snapshot mosaic (its bands' samples are a period apart, not 2 pixels).
  CurvatureCheck(const ThermalModel& model, const MosaicLayout& layout,
                 double limit_c = kCurvatureLimitC);

  // In place: readings (CV_16U 0.1 K codes, 0: none; or CV_32F degC, NaN: none) whose
  // curvature share exceeds the limit are taken away. `signal`: the dark-subtracted mosaic
  // (CV_32F, +INF saturated, NaN none) of the same size. The float form decides on each
  // reading's code, so that both give the same pixels. Pixels within 2 of the border and
  // pixels whose five samples are not all above 0.5 DN and finite are left as they are.
  void apply_codes(const cv::Mat& signal, cv::Mat& codes) const;
  // The same on the run [x0, x1) of row y, `codes_row` that row's codes (no checks of type).
  void apply_run(const cv::Mat& signal, std::uint16_t* codes_row, int y, int x0, int x1) const;
  void apply(const cv::Mat& signal, cv::Mat& temperature_c) const;

  // The curvature share (degC) of a pixel with code `code` whose own band, `band`, has the
  // log-signal Laplacian `laplacian` (per pixel^2); NaN where the locus has no slope there.
  double share_c(std::uint16_t code, int band, double laplacian) const;

 private:
  MosaicLayout layout_;
  double limit_c_, variance_px2_ = 1;
  double min_code_ = 0, codes_per_step_ = 10;  // the slope table's first code and spacing
  int bands_ = 0;
  std::vector<double> slope_;  // per locus sample and band: d ln m_b / dT, 1 / degC
  // q (the four samples' product over the fourth power of the pixel's) in [lo_, hi_] cannot
  // exceed the limit at any temperature of the table: no logarithm needed.
  float lo_ = 1, hi_ = 1;
};

}  // namespace pyrocam
