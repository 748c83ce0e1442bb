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
// colour), on the branch of the three-band reading (a ratio may turn over; there it tells
// nothing, and the three bands say which side a pixel is on).
//
// One ratio is noisier than two: the pair takes over only where its noise is within
// kPairFullNoiseRatio of the three-band reading's (for a well exposed pixel, from the profile's
// noise model), and not at all beyond kPairNoNoiseRatio, so that a turning point of the pair's
// ratio never reads. Over the top kExtrapolationBlendC of the model's range it hands back to the
// three bands, whose smaller noise decides which pixels lie beyond the range (a network once
// trained on the pair's readings up to the top read 1.1 % of a 4000 degC plate's pixels at about
// 3480 degC). Every method reads so: the network is trained on three-band readings (trained on
// the pair's it fitted the noise-free locus twice as badly) and moved afterwards, by the same
// function of its two ratios, which its lookup table then tabulates.
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
// A pixel whose pair reads far from its three bands is not a grey body the model describes (a
// mixed or edge pixel): the pair's weight falls from 1 where the two readings differ by
// kPairFullGap of the three-band reading's absolute temperature to 0 at kPairNoGap. (A pixel's
// noise moves the two apart by sqrt(sd_pair^2 - sd_all^2): 1.5 % at 2500 degC, brightest band
// at 150 DN.)
inline constexpr double kPairFullGap = 0.1, kPairNoGap = 0.2;
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
  // The pair's bands among the profile's normalised ratios (what the network reads): the index
  // of the numerator that is the band, or -1 for the reference when it is that band alone.
  int numerator_ratio = -1, denominator_ratio = -1;
  // The locus' first temperature and step, the pair's log ratio at every sample, and per
  // interval between samples k and k + 1 the first and last sample of the run over which that
  // ratio rises or falls steadily (its branch).
  double locus_start_c = 0, locus_step_c = 1;
  std::vector<double> log_ratio;
  std::vector<int> branch_first, branch_last;

  bool active() const { return numerator >= 0; }

  // A reading t of every band, moved to the pair's reading of a pixel whose log ratio
  // ln(s_numerator / s_denominator) is pixel_log_ratio: the temperature where the locus has that
  // ratio on t's branch (interpolated between samples; the branch's end where the ratio lies
  // beyond it), by the smaller of the weights at t and there, less where the two differ much
  // (kPairFullGap). A continuous function of t and the
  // ratio (the weight is 0 where a branch ends at a turning point of the ratio, and at the
  // range's ends), so that a table of it interpolates. t itself at or below from_c and for a
  // NaN ratio. Not checked against the model's range.
  double read(double t, double pixel_log_ratio) const;
  // The weight at temperature t, linear between samples.
  double weight_at(double t) const;
};

// The pair for a model's camera over the locus `locus` (ascending temperatures, evenly spaced)
// calibrated up to calibrated_up_to_c, for a range that ends at top_c (NaN: the locus' end).
// None unless the camera has three bands, calibrated_up_to_c is inside the locus, the pair's
// weight is somewhere above 0 and its ratio is one of the normalised ratios or a quotient of two
// (a reference that is the mean of several bands is not a band: every reader then reads every
// band, as the network cannot tell the pair's ratio).
ExtrapolationPair extrapolation_pair(const CameraModel& camera, const Locus& locus,
                                     double calibrated_up_to_c, double top_c = NAN);

}  // namespace pyrocam
