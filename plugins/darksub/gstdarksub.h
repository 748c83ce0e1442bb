/* darksub: subtracts a dark frame from raw mosaics and marks saturated pixels. */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_DARK_SUB (gst_dark_sub_get_type())
G_DECLARE_FINAL_TYPE(GstDarkSub, gst_dark_sub, GST, DARK_SUB, GstBaseTransform)

/* The mosaic layout of the input: auto takes it from the caps (the format of video/x-bayer, the
 * pattern field of gray video); the others must agree with the caps where the caps say one. */
typedef enum {
  GST_DARK_SUB_PATTERN_RGGB,
  GST_DARK_SUB_PATTERN_BGGR,
  GST_DARK_SUB_PATTERN_GRBG,
  GST_DARK_SUB_PATTERN_GBRG,
  GST_DARK_SUB_PATTERN_5X5,
  GST_DARK_SUB_PATTERN_AUTO,
} GstDarkSubPattern;
#define GST_TYPE_DARK_SUB_PATTERN (gst_dark_sub_pattern_get_type())
GType gst_dark_sub_pattern_get_type(void);

GST_ELEMENT_REGISTER_DECLARE(darksub);

G_END_DECLS
