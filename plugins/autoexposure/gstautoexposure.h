/* autoexposure: sets the camera's exposure so that the hottest region reads (raw mosaic in,
 * passed through unchanged). */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_AUTO_EXPOSURE (gst_auto_exposure_get_type())
G_DECLARE_FINAL_TYPE(GstAutoExposure, gst_auto_exposure, GST, AUTO_EXPOSURE, GstBaseTransform)

GST_ELEMENT_REGISTER_DECLARE(autoexposure);

G_END_DECLS
