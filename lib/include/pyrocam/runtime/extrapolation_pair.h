// Which band ratio reads a colour camera above its calibration (METHOD.md section 5, beyond).
//
// A furnace campaign ends near 1100 degC; melt pools are read at 1500-2600. Above the hottest
// calibrated temperature every reading extrapolates the fitted QE, and a band extrapolates worse
// the less of its light there comes from the wavelengths the calibration saw. Through a colour
// camera's blue filter a 1100 degC furnace is seen almost only through the filter's infrared
// leak, a 2500 degC melt pool mostly through its visible pass band, which the furnace left
// nearly unconstrained. So above the calibration the likelihood fit of a three-band camera
// passes to the ratio of the two bands whose light overlaps most between the calibration's top
// and a melt pool's core (a spectral overlap computed from the model's QE, not a band named by
// colour), on the branch nearest the three-band reading (a ratio may turn over; there it tells
// nothing, and the three bands say which side a pixel is on).
//
// One ratio is noisier than two: the pair takes over only where its noise is within
// kPairFullNoiseRatio of the three-band reading's (for a well exposed pixel, from the profile's
// noise model), and not at all beyond kPairNoNoiseRatio, so that a turning point of the pair's
// ratio never reads. Over the top kExtrapolationBlendC of the model's range it hands back to the
// three bands, whose smaller noise decides which pixels lie beyond the range: trained on the
// pair's readings up to the top, the network read 1.1 % of a 4000 degC plate's pixels at about
// 3480 degC (the likelihood fit none; the fit's reading through the pair applies only where the
// three-band reading is inside the range, a decision the network cannot copy).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <vector>

#include "pyrocam/core/locus.h"

namespace pyrocam {

// Over this many degC above the hottest calibrated temperature the reading passes linearly from
// the three-band reading to the pair's, so that no step appears in a gradient.
inline constexpr double kExtrapolationBlendC = 200;
// The temperature whose light the overlap below compares with the calibration's: a melt pool's
// core (fixed, so that every reader of a camera, whatever its range, chooses the same pair).
inline constexpr double kExtrapolationOverlapC = 2500;
// The pair reads alone where its standard deviation is at most this multiple of the three-band
// reading's, not at all where it is kPairNoNoiseRatio or more, in proportion between.
inline constexpr double kPairFullNoiseRatio = 1.5, kPairNoNoiseRatio = 2.5;
// The signal of the brightest band of the pixel the noise ratio is computed for, DN.
inline constexpr double kPairNoiseSignalDn = 150;

struct ExtrapolationPair {
  int numerator = -1, denominator = -1;  // bands; -1: no pair (read with every band)
  double from_c = 0;                     // the hottest calibrated temperature
  // Of each band, the share of its signal's spectrum at kExtrapolationOverlapC that it shares
  // with its spectrum at from_c (integral of the smaller of the two normalised spectra): 1 where
  // the calibration saw the light the band reads there, small where it did not.
  std::vector<double> overlap;
  // Per locus sample: the pair's reading's standard deviation over the three-band reading's
  // (infinite where the pair's ratio does not change), and the weight of the pair's reading
  // there (0 at and below from_c).
  std::vector<double> noise_ratio, weight;

  bool active() const { return numerator >= 0; }
};

// The pair for a model's camera over the locus `locus` (ascending temperatures, evenly spaced)
// calibrated up to calibrated_up_to_c, for a range that ends at top_c (NaN: the locus' end).
// None unless the camera has three bands, calibrated_up_to_c is inside the locus and the pair's
// weight is somewhere above 0.
ExtrapolationPair extrapolation_pair(const CameraModel& camera, const Locus& locus,
                                     double calibrated_up_to_c, double top_c = NAN);

}  // namespace pyrocam
