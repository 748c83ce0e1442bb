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

/* PyrocamSaturationMeta: where the camera's light saturated a frame. darksub attaches it to
 * every subtracted frame (samples 0 when none); without API tags it travels with the frame's
 * exposure through demosaic25 and ratiotemp, so that the elements reading temperatures
 * (thermalcolormap's peak readout, thermalalarm) know that a part of the frame without a
 * reading was too bright to read rather than cold: its temperature is above what the rest of
 * the frame reads. The rectangle is in pixels of a frame_width x frame_height frame (darksub's
 * mosaic); an element whose frames have another size (5x5 band planes) scales it. Elements
 * that crop or flip frames carry it unchanged: read it before them. */
typedef struct {
  GstMeta meta;
  guint64 samples;                /* raw samples at or above the saturation level; 0: none */
  gint x, y, width, height;       /* the smallest rectangle holding them; 0 x 0 when none */
  gint frame_width, frame_height; /* the frame those pixels are of */
  /* Which tiles of a 64 x 64 grid over the frame hold any (tile column j of row i: bit j of
   * tiles[i]; tile j spans the columns x with x * 64 / frame_width == j, rounded down, rows
   * alike); all bits set where not known (the rectangle alone then). */
  guint64 tiles[64];
} PyrocamSaturationMeta;

GType pyrocam_saturation_meta_api_get_type(void);
#define PYROCAM_SATURATION_META_API_TYPE (pyrocam_saturation_meta_api_get_type())
const GstMetaInfo* pyrocam_saturation_meta_get_info(void);

/* Adds the meta, or overwrites the buffer's own (one per buffer). `tiles`: 64 words as the
 * field's, or NULL where not known. */
PyrocamSaturationMeta* pyrocam_buffer_set_saturation_meta(GstBuffer* buffer, guint64 samples,
                                                          gint x, gint y, gint width, gint height,
                                                          gint frame_width, gint frame_height,
                                                          const guint64* tiles);
#define pyrocam_buffer_get_saturation_meta(b) \
  ((PyrocamSaturationMeta*)gst_buffer_get_meta((b), PYROCAM_SATURATION_META_API_TYPE))

/* PyrocamAboveRangeMeta: where a frame's temperatures are hotter than the model's range.
 * ratiotemp attaches it to every output frame (pixels 0 when none): the pixels without a reading
 * that its above-range check found hotter than max_temperature_c, where most of a pixel's 3 x 3
 * neighbourhood is (a spot, not a pixel lifted over the range's end by noise). Like the
 * saturation meta, it tells thermalcolormap's peak readout and thermalalarm that a part of the
 * frame without a reading is hotter than the rest, here hotter than max_temperature_c. In pixels
 * of a frame_width x frame_height frame (ratiotemp's output); without API tags it travels with
 * the frame through elements that do not crop or flip it. */
typedef struct {
  GstMeta meta;
  guint64 pixels;                 /* pixels hotter than the range; 0: none */
  gint x, y, width, height;       /* the smallest rectangle holding them; 0 x 0 when none */
  gint frame_width, frame_height; /* the frame those pixels are of */
  guint64 tiles[64];              /* as PyrocamSaturationMeta's, for these pixels */
  gdouble max_temperature_c;      /* the model's range ends here, degC */
} PyrocamAboveRangeMeta;

GType pyrocam_above_range_meta_api_get_type(void);
#define PYROCAM_ABOVE_RANGE_META_API_TYPE (pyrocam_above_range_meta_api_get_type())
const GstMetaInfo* pyrocam_above_range_meta_get_info(void);

/* Adds the meta, or overwrites the buffer's own (one per buffer); `tiles`: 64 words. */
PyrocamAboveRangeMeta* pyrocam_buffer_set_above_range_meta(GstBuffer* buffer, guint64 pixels,
                                                           gint x, gint y, gint width, gint height,
                                                           gint frame_width, gint frame_height,
                                                           const guint64* tiles,
                                                           gdouble max_temperature_c);
#define pyrocam_buffer_get_above_range_meta(b) \
  ((PyrocamAboveRangeMeta*)gst_buffer_get_meta((b), PYROCAM_ABOVE_RANGE_META_API_TYPE))

/* PyrocamUncertaintyMeta: what a reading of a frame is uncertain by, whatever its pixel's noise.
 * ratiotemp attaches it to every temperature frame: the expanded (coverage_factor) systematic
 * uncertainty of its readings (calibration, QE model, emissivity slope) at `count` temperatures
 * evenly over the model's range, so that an element that sees only temperatures
 * (thermalcolormap's peak readout) can say how far a reading is to be trusted: above the
 * furnace's range it grows where the model extrapolates. The sensor noise of a pixel is not in
 * it (ratiotemp output=uncertainty has both). Without API tags it travels with the frame. */
#define PYROCAM_UNCERTAINTY_META_SAMPLES 64
typedef struct {
  GstMeta meta;
  gdouble coverage_factor; /* k of the values (2 unless the model says otherwise) */
  guint count;             /* samples used, at most PYROCAM_UNCERTAINTY_META_SAMPLES */
  gdouble temperature_c[PYROCAM_UNCERTAINTY_META_SAMPLES]; /* ascending, degC */
  gdouble expanded_u_c[PYROCAM_UNCERTAINTY_META_SAMPLES];  /* degC, at those temperatures */
} PyrocamUncertaintyMeta;
GType pyrocam_uncertainty_meta_api_get_type(void);
#define PYROCAM_UNCERTAINTY_META_API_TYPE (pyrocam_uncertainty_meta_api_get_type())
const GstMetaInfo* pyrocam_uncertainty_meta_get_info(void);
/* Adds the meta, or overwrites the buffer's own (one per buffer); `count` values of each array
 * (at most PYROCAM_UNCERTAINTY_META_SAMPLES are kept). */
PyrocamUncertaintyMeta* pyrocam_buffer_set_uncertainty_meta(GstBuffer* buffer,
                                                            gdouble coverage_factor, guint count,
                                                            const gdouble* temperature_c,
                                                            const gdouble* expanded_u_c);
#define pyrocam_buffer_get_uncertainty_meta(b) \
  ((PyrocamUncertaintyMeta*)gst_buffer_get_meta((b), PYROCAM_UNCERTAINTY_META_API_TYPE))

G_END_DECLS
