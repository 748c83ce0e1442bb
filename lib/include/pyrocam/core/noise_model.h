// Signal noise of one band reading (EMVA 1288): what the likelihood fit, the band-consistency
// check, the GUM uncertainty and the noisy locus copies weigh or draw signals by.
#pragma once

#include <vector>

#include "pyrocam/core/profile.h"

namespace pyrocam {

// An analogue gain in dB as the factor it multiplies the signal by, 10^(dB / 20).
double analogue_gain_factor(double gain_db);

// Signal noise variance of one band reading (EMVA 1288), DN^2, averaged over `frames` frames;
// the dark frame's noise is included. `gain`: the analogue gain the frame was taken with, as a
// factor (10^(dB / 20)) over the profile's system gain: the shot noise in DN per electron
// scales by it, the read noise and quantisation in DN do not (as pyrocamsrc simulates it).
double signal_variance_dn2(const CameraProfile& profile, int band, double signal_dn, int frames = 1,
                           double gain = 1.0);

// The same for a single frame as shot_gain * max(signal, 0) + floor (shot noise; read noise and
// quantisation of the frame and of its dark), for loops that weigh many pixels.
struct SignalNoise {
  double shot_gain;  // DN per electron
  double floor_dn2;
};
SignalNoise signal_noise(const CameraProfile& profile, int band, double gain = 1.0);

// The level below which a dark-subtracted sample may hold no light at all: 5 standard
// deviations of the noisiest band's floor (read noise and quantisation of the frame and its
// dark). At an edge to a cold background, interpolation mixes such samples with lit ones.
double no_signal_level_dn(const std::vector<SignalNoise>& noise);

}  // namespace pyrocam
