// Mixed pixels: at a sharp edge the mosaic pixels that demosaicking combines into one output
// pixel see different temperatures, and their bands make a ratio that belongs to no single
// temperature, often one that looks plausible (a 735 degC plate's edge read 500..2300 degC). A
// pixel whose footprint is not uniform, band by band, within the noise model and a smooth
// gradient's allowance, gets no reading.
#pragma once

#include <cstddef>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/mosaic.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/demosaic.h"

namespace pyrocam {

// The suggested allowed spread (max - min) of one band's samples in a footprint, relative to
// their largest (the check is off unless asked for):
// an edge between a hot object and its cold background changes a band's signal by factors of
// 10 to 1000, a gradient across 2 pixels by less. Interpolating a band whose two samples differ
// by a factor g errs by about (ln g)^2 / 8 of its value where the other band is not
// interpolated in the same direction: 0.5 (g = 2) is 6 %, what noise alone does to one sample
// of a band at the readings' dim threshold (the colour camera at 20 DN: green 6.4 %, red 4.6,
// blue 9.5), so a gradient makes no reading worse than the dimmest readable band may be. 0.2
// (g = 1.25, 0.6 %) gave the same on plates but took the steep sides of small melt pools (114
// of 735 readings left on the simulator's, 658 with 0.5; mixed-pixel-targets).
inline constexpr double kDefaultFootprintSpread = 0.5;

struct FootprintCheck {
  double relative_spread = kDefaultFootprintSpread;
  double k_sigma = 5;              // plus this many noise standard deviations of the difference
  std::vector<SignalNoise> noise;  // per band (signal_noise of the profile)
  // Footprints whose samples are all below this are not tested: every band interpolated from
  // them is below it too, so with the readings' dim threshold here the pixel has no reading
  // anyway (a cold background, most of a melt-pool frame, costs almost nothing).
  float skip_below_dn = -std::numeric_limits<float>::infinity();
};
inline constexpr double kMaxRelativeSpread = 10;

// The footprint: for bilinear Bayer the 3x3 mosaic pixels around each output pixel (mirrored at
// the borders, as demosaic does), for matched Bayer each band's kernel samples
// (matched_footprint, one pixel at a time: several times the bilinear pass's cost), for binned
// Bayer the 2x2 cell. Snapshot mosaics (one sample
// of each band per cell) have nothing to compare and are left alone: the band-consistency check
// (misfit.h) catches their mixed pixels. Samples that are not finite (saturated or no reading)
// are left out of the comparison (the planes already carry their marks where they are used).
// Sets every plane to NaN at each mixed pixel and returns how many there were. Throws
// InputError when the mosaic is not CV_32F, the planes do not match demosaic's output or the
// noise model has fewer entries than bands.
std::size_t mark_mixed_pixels(const cv::Mat& mosaic, const MosaicLayout& layout,
                              DemosaicMethod method, const FootprintCheck& check,
                              std::vector<cv::Mat>& planes);

// demosaic, then mark_mixed_pixels, with the same results; for bilinear Bayer in one pass: each
// block of rows is checked as soon as it is demosaicked, while its mosaic rows are in cache
// (the separate pass read the whole mosaic from memory again).
std::size_t demosaic_marking_mixed(const cv::Mat& mosaic, const MosaicLayout& layout,
                                   DemosaicMethod method, const FootprintCheck& check,
                                   std::vector<cv::Mat>& planes, float no_signal_dn);

}  // namespace pyrocam
