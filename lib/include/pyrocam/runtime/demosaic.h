// From a dark-subtracted mosaic (CV_32F, one value per sensor pixel) to band planes.
//
// Marks propagate by IEEE arithmetic: a band value computed from any +INF (saturated) input is
// +INF, from any NaN input NaN (NaN wins over +INF), because every output is a mean of inputs
// with positive weights.
#pragma once

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
};

DemosaicMethod parse_demosaic_method(const std::string& name);  // "bilinear", "bin2x2"

// Output plane size: the input size for bilinear, else floor(input / period) (pixels of an
// incomplete trailing cell are dropped).
cv::Size demosaic_output_size(const MosaicLayout& layout, DemosaicMethod method, cv::Size input);

// Fills one CV_32F plane per band (plane index = the layout's band index: R, G, B for Bayer).
// `planes` may wrap a caller's buffer: planes of the right size and type are written in place,
// others are (re)allocated. Snapshot layouts are always binned. Throws InputError if the mosaic
// is not CV_32F or is smaller than one period.
void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes);

}  // namespace pyrocam
