/* PyrocamExposureMeta: the exposure (and gain) a frame was taken with. pyrocamsrc attaches it;
 * it has no API tags, so every GstBaseTransform of the chain (darksub, demosaic25, ratiotemp)
 * copies it to its output: autoexposure and anything downstream know each frame's own
 * exposure, whatever the latency between setting one and seeing it. */
#pragma once

#include <gst/gst.h>

G_BEGIN_DECLS

typedef struct {
  GstMeta meta;
  gdouble exposure_us; /* exposure time, microseconds */
  gdouble gain_db;     /* analogue gain, dB (0 when the camera has none) */
} PyrocamExposureMeta;

GType pyrocam_exposure_meta_api_get_type(void);
#define PYROCAM_EXPOSURE_META_API_TYPE (pyrocam_exposure_meta_api_get_type())
const GstMetaInfo* pyrocam_exposure_meta_get_info(void);

PyrocamExposureMeta* pyrocam_buffer_add_exposure_meta(GstBuffer* buffer, gdouble exposure_us,
                                                      gdouble gain_db);
#define pyrocam_buffer_get_exposure_meta(b) \
  ((PyrocamExposureMeta*)gst_buffer_get_meta((b), PYROCAM_EXPOSURE_META_API_TYPE))

G_END_DECLS
