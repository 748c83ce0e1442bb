/* demosaic25: dark-subtracted mosaics (Bayer or 5x5) to planar band images. */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_DEMOSAIC25 (gst_demosaic25_get_type())
G_DECLARE_FINAL_TYPE(GstDemosaic25, gst_demosaic25, GST, DEMOSAIC25, GstBaseTransform)

typedef enum {
  GST_DEMOSAIC25_METHOD_BILINEAR,
  GST_DEMOSAIC25_METHOD_BIN2X2,
  GST_DEMOSAIC25_METHOD_MATCHED,
  GST_DEMOSAIC25_METHOD_AUTO,
} GstDemosaic25Method;
#define GST_TYPE_DEMOSAIC25_METHOD (gst_demosaic25_method_get_type())
GType gst_demosaic25_method_get_type(void);

GST_ELEMENT_REGISTER_DECLARE(demosaic25);

G_END_DECLS
