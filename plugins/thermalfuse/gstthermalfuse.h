/* thermalfuse: high dynamic range from an exposure bracket (temperature frames, GRAY16_LE). */
#pragma once

#include <gst/gst.h>
#include <gst/video/gstvideofilter.h>

G_BEGIN_DECLS

#define GST_TYPE_THERMAL_FUSE (gst_thermal_fuse_get_type())
G_DECLARE_FINAL_TYPE(GstThermalFuse, gst_thermal_fuse, GST, THERMAL_FUSE, GstVideoFilter)

GST_ELEMENT_REGISTER_DECLARE(thermalfuse);

G_END_DECLS
