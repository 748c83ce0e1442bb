/* mosaicfuse: high dynamic range from an exposure bracket, fused before demosaicking
 * (dark-subtracted mosaics, video/x-pyrocam-mosaic). */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_MOSAIC_FUSE (gst_mosaic_fuse_get_type())
G_DECLARE_FINAL_TYPE(GstMosaicFuse, gst_mosaic_fuse, GST, MOSAIC_FUSE, GstBaseTransform)

GST_ELEMENT_REGISTER_DECLARE(mosaicfuse);

G_END_DECLS
