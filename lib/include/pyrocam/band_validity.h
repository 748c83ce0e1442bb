// Which pixels of band planes are complete readings: every band finite (not saturated +INF, not
// NaN) and at least the dim threshold. The estimators decide per method which bands they need
// (the likelihood fit can do without some); this mask holds every method to all bands.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace pyrocam {

// CV_8U of the planes' size: 255 where every plane (CV_32F, equal sizes) holds a finite value
// >= dim_dn, 0 elsewhere. Throws InputError for no planes or planes of other types or sizes.
cv::Mat complete_band_mask(const std::vector<cv::Mat>& planes, double dim_dn);

}  // namespace pyrocam
