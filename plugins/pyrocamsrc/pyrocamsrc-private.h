/* pyrocamsrc's caps, shared by its files. */
#pragma once

#include <gst/gst.h>

#include "pyrocam/core/profile.h"

namespace pyrocam::gst::pyrocamsrc {

/* The caps the loaded profile can produce. */
GstCaps* profile_caps(const CameraProfile& profile);

/* After a failed negotiation: when downstream takes none of the profile's formats, an error
 * naming both (a camera cannot give another mosaic than its sensor's). */
void explain_refused_caps(GstElement* element, GstPad* src_pad, const CameraProfile& profile);

}  // namespace pyrocam::gst::pyrocamsrc
