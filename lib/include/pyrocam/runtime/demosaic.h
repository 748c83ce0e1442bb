// From a dark-subtracted mosaic (CV_32F, one value per sensor pixel) to band planes.
//
// Marks propagate by IEEE arithmetic: a band value computed from any +INF (saturated) input is
// +INF, from any NaN input NaN (NaN wins over +INF), because every output is a mean of inputs
// with positive weights.
#pragma once

#include <limits>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pyrocam/core/mosaic.h"

namespace pyrocam {

enum class DemosaicMethod {
  // Bayer only: full resolution; the missing bands at each pixel are the mean of the nearest
  // pixels of that band (2 horizontal or vertical, or 4 diagonal for R/B; 4 cross neighbours
  // for G). Borders are mirrored without repeating the edge pixel, which keeps the pattern.
  kBilinear,
  // One reading per mosaic period (macro-pixel): each band is the mean of the pixels of that
  // band in the cell. Bayer: half resolution, R, mean of both G, B per 2x2 cell. 5x5 snapshot
  // mosaics always use it (one reading per 5x5 macro-pixel, as the paper).
  kBinCells,
  // Bayer only: full resolution; every band of every pixel from a symmetric kernel of the same
  // second moment (1 pixel^2 along each axis; 5x5 footprint), so that on a curved signal (a hot
  // spot) the bands' interpolation errors cancel in their ratio instead of adding a colour
  // shift (see demosaic_matched.cpp). Marks spread over the larger footprint.
  kMatched,
};

DemosaicMethod parse_demosaic_method(const std::string& name);  // "bilinear", "bin2x2", "matched"

// Output plane size: the input size for bilinear, else floor(input / period) (pixels of an
// incomplete trailing cell are dropped).
cv::Size demosaic_output_size(const MosaicLayout& layout, DemosaicMethod method, cv::Size input);

// Fills one CV_32F plane per band (plane index = the layout's band index: R, G, B for Bayer).
// `planes` may wrap a caller's buffer: planes of the right size and type are written in place,
// others are (re)allocated. Snapshot layouts are always binned. Throws InputError if the mosaic
// is not CV_32F or is smaller than one period.
// kMatched only: a finite band value computed from any sample below `no_signal_dn` (see
// no_signal_level_dn) is 0, so it reads as dim: at an edge to a cold background its kernel
// mixes lit and unlit samples into a ratio of no temperature.
void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes,
              float no_signal_dn = -std::numeric_limits<float>::infinity());

// The mosaic samples (offsets from the pixel) that kMatched draws band `band` from at a pixel
// of column parity px and row parity py: its footprint, for the mixed-pixel check.
std::vector<cv::Point> matched_footprint(const MosaicLayout& layout, int band, int px, int py);

// kMatched for a Bayer layout, into planes of the mosaic's size (no checks: see demosaic).
void demosaic_matched_bayer(const cv::Mat& mosaic, const MosaicLayout& layout, float dim_dn,
                            std::vector<cv::Mat>& planes);

}  // namespace pyrocam
