/* thermalcolormap: temperature images (GRAY16_LE, 0.1 K) to false-colour RGBA for display. */
#pragma once

#include <gst/gst.h>
#include <gst/video/gstvideofilter.h>

G_BEGIN_DECLS

#define GST_TYPE_THERMAL_COLORMAP (gst_thermal_colormap_get_type())
G_DECLARE_FINAL_TYPE(GstThermalColormap, gst_thermal_colormap, GST, THERMAL_COLORMAP,
                     GstVideoFilter)

typedef enum {
  GST_THERMAL_COLORMAP_PALETTE_IRON,
  GST_THERMAL_COLORMAP_PALETTE_INFERNO,
  GST_THERMAL_COLORMAP_PALETTE_RAINBOW,
  GST_THERMAL_COLORMAP_PALETTE_GREY,
} GstThermalColormapPalette;
#define GST_TYPE_THERMAL_COLORMAP_PALETTE (gst_thermal_colormap_palette_get_type())
GType gst_thermal_colormap_palette_get_type(void);

typedef enum {
  GST_THERMAL_COLORMAP_RANGE_FIXED,
  GST_THERMAL_COLORMAP_RANGE_AUTO,
} GstThermalColormapRangeMode;
#define GST_TYPE_THERMAL_COLORMAP_RANGE_MODE (gst_thermal_colormap_range_mode_get_type())
GType gst_thermal_colormap_range_mode_get_type(void);

GST_ELEMENT_REGISTER_DECLARE(thermalcolormap);

G_END_DECLS
