// GRAY16 codes for temperature differences such as expanded uncertainties: units of 0.1 K,
// 0 = no reading. (Absolute temperatures: encode_decikelvin in measure.h, which adds 273.15.)
#pragma once

#include <opencv2/core.hpp>

namespace pyrocam {

// CV_32F degC differences to CV_16U codes: round(10 * value), at least 1 (a reading is never
// 0) and at most 65535 (6553.5 K); 0 for NaN, infinite or negative values.
cv::Mat encode_decikelvin_difference(const cv::Mat& difference_c);
// Back to CV_32F degC (NaN for 0).
cv::Mat decode_decikelvin_difference(const cv::Mat& codes);

}  // namespace pyrocam
