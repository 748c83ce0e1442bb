// Dark-frame subtraction with saturation marking: the first step from raw camera gray values to
// signals (METHOD.md section 3 and 5). The result is float32 DN; a pixel whose raw value reached
// the saturation level (before subtraction) is +INFINITY, a pixel without a reading NaN.
#pragma once

#include <cstddef>
#include <opencv2/core.hpp>

namespace pyrocam {

// The largest raw value of a bit depth: 2^bits - 1.
int full_scale_dn(int bit_depth);
// The default saturation level: 220/255 of the full scale (the paper's 220 of 255 for 8 bits),
// rounded. Throws InputError for a bit depth outside 1..16.
double default_saturation_level(int bit_depth);

// The samples a subtraction marked saturated: how many, and the smallest rectangle holding them
// (empty when none).
struct SaturatedSamples {
  std::size_t count = 0;
  cv::Rect bounds;
};

// out = raw - dark per pixel as CV_32F, with +INF where raw >= saturation_level. raw is CV_8U or
// CV_16U (any stride), dark CV_32F of the same size (a NaN in the dark gives NaN). out is
// (re)allocated only if its size or type differs, so it may wrap a caller's buffer. Throws
// InputError on a size or type mismatch naming both sizes.
SaturatedSamples subtract_dark(const cv::Mat& raw, const cv::Mat& dark, double saturation_level,
                               cv::Mat& out);

// The same with a constant dark level (no dark frame to read: less memory traffic).
SaturatedSamples subtract_dark_level(const cv::Mat& raw, double level_dn, double saturation_level,
                                     cv::Mat& out);

// The saturated (+INF) samples of a CV_32F dark-subtracted mosaic, e.g. after fusing a bracket.
// Throws InputError for another type.
SaturatedSamples find_saturated(const cv::Mat& signal);

// Converts a dark image read from a file (CV_8U/CV_16U) to the CV_32F dark subtract_dark takes.
cv::Mat dark_from_image(const cv::Mat& image);

// Averages raw frames into a dark frame (lens cap on). All frames must have the size of the first.
class DarkAccumulator {
 public:
  void reset();
  // Adds one CV_8U/CV_16U frame; throws InputError if its size differs from the first frame's.
  void add(const cv::Mat& raw);
  int count() const { return count_; }
  // Mean of the frames added so far as CV_32F; throws InputError when none was added.
  cv::Mat mean() const;

 private:
  cv::Mat sum_;  // CV_64F
  int count_ = 0;
};

}  // namespace pyrocam
