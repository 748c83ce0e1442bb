// Pixels hotter than the model's range. Every estimator reads only inside the model's range
// (min_temperature_c..max_temperature_c) and gives no reading beyond it, which looks the same as
// a cold pixel or a mixed one: a melt pool hotter than a narrow model's range would show its rim
// as the peak, and an alarm above the rim would never be raised. This check tells such pixels
// apart: a pixel without a reading whose bands all read (finite, at least the dim threshold, not
// saturated) is above the range when the likelihood fit along the model camera's locus extended
// to kAboveRangeTopC reads it above max_temperature_c by more than kAboveRangeSigmas standard
// deviations of its noise, strictly inside the extension, and its bands fit a graybody there:
// the band-consistency check (misfit.h) with the bar of ratiotemp's
// fit audit (false rejections 1e-9, 5 % model error per band; at 2 %, 5x5 units unlike the
// model's failed it noise-free). The fit is made over the whole extended locus, so a pixel that
// fits some temperature inside the range better (one refused for another reason) is not above
// it. A grey surface is assumed.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/locus.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/misfit.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

// Where the extended locus ends, degC: above the range any model may have (kModelMaxTemperatureC)
// and within what a temperature code holds (6280 degC).
inline constexpr double kAboveRangeTopC = 6000;
inline constexpr double kAboveRangeMisfitProbability = 1e-9, kAboveRangeModelError = 0.05;
// How far above the range's end a reading must be, in standard deviations of its noise: near
// the end a surface inside the range reads above it on many of its pixels (the colour test
// camera's readings scatter by about 80 degC at 3450 degC, and demosaicking makes neighbours
// scatter together: without the margin, plates at 3400-3490 degC were called hotter than a range
// ending at 3500 over hundreds to thousands of pixels), so only a reading the noise cannot have
// lifted that far counts. One-sided normal: a pixel at the end itself passes with probability
// 0.13 %.
inline constexpr double kAboveRangeSigmas = 3;

// Pixels checked at most per frame (PlaneEstimator): a frame whose whole object is above the
// range would otherwise cost about 0.5 us of CPU per pixel (2 s for a 2048 x 2048 plate), and a
// few thousand of them say all there is to say. Past it, the count is a lower bound.
inline constexpr std::size_t kAboveRangeBudget = 65536;

class AboveRangeCheck {
 public:
  // Builds the extended fit (a locus to kAboveRangeTopC: tens of ms). Shares the model; throws
  // InputError without one.
  explicit AboveRangeCheck(std::shared_ptr<const ThermalModel> model);

  // The reading of the extended fit where the pixel is above the model's range (degC, above
  // max_temperature_c), else NaN. signals: one per band, DN after dark subtraction (+INF
  // saturated, NaN invalid), as TemperatureEstimator::temperature_c takes them.
  double reading_above(const double* signals) const;
  // The shot noise's gain factor (TemperatureEstimator::set_analogue_gain). Not while a check
  // runs. Throws InputError unless positive.
  void set_analogue_gain(double factor);
  double max_temperature_c() const { return max_c_; }
  // The standard deviation of a reading at t_c that the signals' noise leaves (one sample's
  // noise per band: demosaicking averages less than that, so a little more than the truth),
  // from the curvature of the fit's chi2 over +-kCurvatureStepC.
  double noise_sd_c(const double* signals, double t_c) const;
  static constexpr double kCurvatureStepC = 20, kLocusStepC = 5;

 private:
  std::shared_ptr<const ThermalModel> extended_;  // the model, its range to kAboveRangeTopC
  std::unique_ptr<TemperatureEstimator> fit_;
  MisfitCheck misfit_;
  Locus locus_;  // max_temperature_c - kCurvatureStepC .. kAboveRangeTopC, kLocusStepC apart
  double max_c_, dim_dn_;
  int bands_;
  double analogue_gain_ = 1.0;
};

// Of the pixels `found` above the range in a frame of `size`, those whose 3 x 3 neighbourhood
// (within the frame) holds at least 5 found pixels, so that the neighbourhood's median reads
// above the range: a spot hotter than the model reads, not a lone pixel (the noise margin of
// AboveRangeCheck does the rest: neighbours share demosaicking footprints, so their noise does
// not average out over a neighbourhood). In darksub's summary of saturated samples: their count,
// bounds and tiles, in pixels of `size`.
// Points outside the frame are ignored. `kept`, if given, receives the spots' pixels.
SaturatedSamples above_range_spots(const std::vector<cv::Point>& found, cv::Size size,
                                   std::vector<cv::Point>* kept = nullptr);

}  // namespace pyrocam
