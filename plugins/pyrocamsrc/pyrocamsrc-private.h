/* pyrocamsrc's caps and frame exposures, shared by its files. */
#pragma once

#include <gst/gst.h>

#include "pyrocam/core/profile.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::gst::pyrocamsrc {

/* The caps the loaded profile can produce. */
GstCaps* profile_caps(const CameraProfile& profile);

/* After a failed negotiation: when downstream takes none of the profile's formats, an error
 * naming both (a camera cannot give another mosaic than its sensor's). */
void explain_refused_caps(GstElement* element, GstPad* src_pad, const CameraProfile& profile);

/* Frames go into a pool of their own size (`frame_size` bytes), first in the allocation query:
 * a pool proposed downstream may be for other caps (a capssetter between, as in carrying Bayer
 * as GRAY8 into an encoder) and its buffers too small. */
void propose_own_pool(GstQuery* query, gsize frame_size);

/* The longest exposure, the property's (automatic included) and a bracket step's. */
inline constexpr double kMaxExposureUs = 1e7;

/* A frame's exposure: `exposure_us` (0: the camera's automatic one for the scene's nominal
 * temperature, held to kMaxExposureUs) times the bracket's `factor`, held to kMaxExposureUs
 * with one RESOURCE SETTINGS warning (when `warned` is false; it is then set). */
double frame_exposure_us(GstElement* element, const Simulator& camera, double exposure_us,
                         double factor, double nominal_c, double emissivity, bool& warned);

}  // namespace pyrocam::gst::pyrocamsrc
