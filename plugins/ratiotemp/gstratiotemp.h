/* ratiotemp: band planes to temperature images (GRAY16_LE, 0.1 K) with a calibrated model. */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_RATIO_TEMP (gst_ratio_temp_get_type())
G_DECLARE_FINAL_TYPE(GstRatioTemp, gst_ratio_temp, GST, RATIO_TEMP, GstBaseTransform)

/* The per-pixel estimator (docs/elements.md). */
typedef enum {
  GST_RATIO_TEMP_METHOD_AUTO,
  GST_RATIO_TEMP_METHOD_MLP,
  GST_RATIO_TEMP_METHOD_LUT,
  GST_RATIO_TEMP_METHOD_LIKELIHOOD,
} GstRatioTempMethod;
#define GST_TYPE_RATIO_TEMP_METHOD (gst_ratio_temp_method_get_type())
GType gst_ratio_temp_method_get_type(void);

/* What the output pixels hold. */
typedef enum {
  GST_RATIO_TEMP_OUTPUT_TEMPERATURE,
  GST_RATIO_TEMP_OUTPUT_UNCERTAINTY,
} GstRatioTempOutput;
#define GST_TYPE_RATIO_TEMP_OUTPUT (gst_ratio_temp_output_get_type())

typedef enum {
  GST_RATIO_TEMP_PARTIAL_OFF,
  GST_RATIO_TEMP_PARTIAL_SAFE,
  GST_RATIO_TEMP_PARTIAL_ANY,
} GstRatioTempPartial;
#define GST_TYPE_RATIO_TEMP_PARTIAL (gst_ratio_temp_partial_get_type())
GType gst_ratio_temp_partial_get_type(void);
GType gst_ratio_temp_output_get_type(void);

GST_ELEMENT_REGISTER_DECLARE(ratiotemp);

G_END_DECLS
