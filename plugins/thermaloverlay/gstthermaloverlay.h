/* thermaloverlay: lays each frame's colour-mapped temperatures over the camera image of the same
 * frame, waiting for them rather than for a clock. */
#pragma once

#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_THERMAL_OVERLAY (gst_thermal_overlay_get_type())
G_DECLARE_FINAL_TYPE(GstThermalOverlay, gst_thermal_overlay, GST, THERMAL_OVERLAY, GstElement)

GST_ELEMENT_REGISTER_DECLARE(thermaloverlay);

G_END_DECLS
