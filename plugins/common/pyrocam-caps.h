/* The media types the pyrocam elements exchange, defined once. Every field is documented here;
 * elements use only these macros for their pad templates and caps.
 *
 * Raw mosaics (camera input, what pyrocamsrc produces and darksub consumes):
 *   video/x-bayer, format=(string){rggb,bggr,grbg,gbrg}: 8-bit Bayer as aravissrc gives it; the
 *     format names the colour of the top-left 2x2 cell. Row stride: GST_ROUND_UP_4 (width), as
 *     bayer2rgb expects; a buffer of exactly width*height bytes (no padding) is accepted too.
 *   video/x-raw, format=(string){GRAY8,GRAY16_LE}: a mosaic carried as gray video (16-bit Bayer
 *     has no caps in GStreamer 1.22); strides as GstVideoInfo gives them. Optional fields, set
 *     by pyrocamsrc (and by a capsfilter after any other camera, e.g.
 *     `aravissrc ! video/x-raw,format=GRAY16_LE,pattern=5x5,bit-depth=12`):
 *     pattern          (string) the mosaic layout, as in x-pyrocam-mosaic below. Without it
 *                      darksub must be told one by its `pattern` property, else it refuses the
 *                      stream; a property that disagrees with the field is refused too (CORE
 *                      NEGOTIATION): a 5x5 mosaic read as Bayer gives plausible wrong readings.
 *     bit-depth        (int) [1, 16] significant bits of the samples (at most 8 for GRAY8).
 *                      Without it: darksub's `bit-depth` property, else the sample size.
 *     band-map         (string) for 5x5: the band index of each position in the cell,
 *                      row-major, 25 comma-separated integers ("0,1,...,24" is row * 5 +
 *                      column): the camera profile's band map. darksub passes it on in
 *                      x-pyrocam-mosaic, demosaic25 orders the bands by it and says the order
 *                      it used in x-pyrocam-bands; a demosaic25 profile or a ratiotemp model
 *                      whose band map differs is refused (CORE NEGOTIATION).
 *     saturation-level (int) raw DN at and above which a pixel is saturated: the camera
 *                      profile's inference saturation threshold, the one `measure` and the
 *                      calibration use. Without it: darksub's `saturation-level` property,
 *                      else 220/255 of the full scale of the bit depth (220 for 8 bit).
 *   video/x-bayer carries no such fields (bayer2rgb shares the stream); its bit depth is 8 and
 *   its saturation level darksub's default, which is the shipped profiles' threshold (220).
 *
 * video/x-pyrocam-mosaic: the mosaic after dark subtraction (darksub's output).
 *   format    (string) F32LE: one little-endian IEEE float32 per sensor pixel, in DN above the
 *             dark level. +INFINITY marks a saturated pixel (raw value >= the saturation level
 *             before subtraction); NaN a pixel without a reading (e.g. while a dark is captured).
 *   width     (int) sensor pixels per row; height (int) rows. Row stride is width * 4 bytes, no
 *             padding; a buffer holds exactly width * height * 4 bytes.
 *   framerate (fraction) as the camera's.
 *   pattern   (string) rggb, bggr, grbg, gbrg (2x2 Bayer, named by the top-left cell) or 5x5
 *             (snapshot mosaic, band index = row * 5 + column in the cell unless a camera profile
 *             says otherwise).
 *   bit-depth (int) significant bits of the raw samples (8 for 8-bit input, e.g. 12 for a 12-bit
 *             camera carried as GRAY16_LE); the DN scale of the values.
 *   band-map  (string, optional, 5x5 only) as in the raw gray caps above.
 *   saturation-level (int, optional) the raw DN at and above which darksub marked pixels +INF
 *             (its saturation-level property, else the raw caps' field, else its default);
 *             darksub renegotiates when the property changes.
 *
 * video/x-pyrocam-bands: planar band images (demosaic25's output, ratiotemp's input).
 *   format    (string) F32LE: float32 DN as in x-pyrocam-mosaic, with the same marks: a value
 *             computed from any saturated pixel is +INFINITY, from any NaN pixel NaN.
 *   bands     (int) number of planes: 3 for Bayer (R, G, B), 25 for 5x5 (band index = row * 5 +
 *             column in the 5x5 cell, or the camera profile's band map).
 *   width, height (int) size of each plane (the output size: full sensor size for bilinear
 *             Bayer, sensor size / period for binned Bayer and 5x5).
 *   framerate (fraction) as the input's.
 *   layout    (string) bayer or 5x5: the mosaic the bands come from.
 *   saturation-level (int, optional) as in x-pyrocam-mosaic, passed on by demosaic25. ratiotemp
 *             refuses a level above its model profile's inference saturation threshold: pixels
 *             the model calls saturated would reach it unmarked.
 *   band-map  (string, 5x5 only) the band map demosaic25 ordered the planes by (the input's
 *             band-map field, its profile's, or row * 5 + column); plane b holds band b.
 *   demosaic  (string, optional) how demosaic25 made the planes: matched, bilinear or bin2x2
 *             (binned cells; 5x5 mosaics bin with any method but matched). ratiotemp's
 *             uncertainty takes each band value's noise from it (a kernel's mean of several
 *             samples is less noisy than one); without it, each value's noise is one sample's.
 *   pattern   (string, optional, bayer only) the Bayer pattern the planes come from, as in
 *             x-pyrocam-mosaic: which band each pixel's own sample is.
 *   Memory: plane after plane (band 0 first), each width * height floats, rows without padding;
 *   a buffer holds exactly bands * width * height * 4 bytes.
 *
 * video/x-pyrocam-bands(memory:PyrocamMosaic): the same band planes, not yet computed (the fused
 *   path between demosaic25 and ratiotemp when they are linked: the planes are demosaicked a
 *   strip of rows at a time where they are read, and never cross memory). demosaic25 offers it
 *   for Bayer mosaics with method matched (auto) and no mixed-pixel check, after the plain
 *   bands, so that any other element gets the planes; ratiotemp asks for it first.
 *   Fields as x-pyrocam-bands (bands=3, layout=bayer, width and height the mosaic's), and:
 *   pattern         (string) rggb, bggr, grbg or gbrg: the Bayer pattern, as in
 *                   x-pyrocam-mosaic.
 *   no-signal-level (double) the level in DN below which a sample holds no light (matched
 *                   demosaicking makes every band value drawn from it dim): demosaic25's,
 *                   from its profile's noise and the stream's bit depth; set when demosaic25
 *                   fixes its caps.
 *   Memory: the dark-subtracted mosaic as in x-pyrocam-mosaic (width * height floats, the same
 *   marks): demosaic25 passes darksub's buffer on untouched.
 *
 * Temperatures: video/x-raw, format=(string)GRAY16_LE, one value per pixel in units of 0.1 K
 *   (e.g. 14732 = 1473.2 K = 1200.05 degC); 0 means "no reading" (saturated, too dim, invalid).
 *   The code and its conversions are defined once, in the library:
 * pyrocam/core/temperature_codes.h.
 */
#pragma once

#include <gst/gst.h>
#include <gst/video/video.h>

#define PYROCAM_BAYER_MEDIA_TYPE "video/x-bayer"
#define PYROCAM_VIDEO_MEDIA_TYPE "video/x-raw"
#define PYROCAM_MOSAIC_MEDIA_TYPE "video/x-pyrocam-mosaic"
#define PYROCAM_BANDS_MEDIA_TYPE "video/x-pyrocam-bands"

#define PYROCAM_BAYER_FORMATS "{ rggb, bggr, grbg, gbrg }"
#define PYROCAM_PATTERNS "{ rggb, bggr, grbg, gbrg, 5x5 }"
#define PYROCAM_LAYOUTS "{ bayer, 5x5 }"
#define PYROCAM_SNAPSHOT_PATTERN_NAME "5x5"

/* Names of the optional raw gray caps fields described above. */
#define PYROCAM_FIELD_PATTERN "pattern"
#define PYROCAM_FIELD_BIT_DEPTH "bit-depth"
#define PYROCAM_FIELD_SATURATION_LEVEL "saturation-level"
#define PYROCAM_FIELD_BAND_MAP "band-map"
#define PYROCAM_FIELD_DEMOSAIC "demosaic"

#define PYROCAM_SIZE_RANGE "width = (int) [ 1, max ], height = (int) [ 1, max ]"
#define PYROCAM_FRAMERATE_RANGE "framerate = (fraction) [ 0/1, max ]"

/* Raw mosaics: 8-bit Bayer, or gray video carrying any mosaic. */
#define PYROCAM_RAW_BAYER_CAPS                                                                  \
  PYROCAM_BAYER_MEDIA_TYPE ", format = (string) " PYROCAM_BAYER_FORMATS ", " PYROCAM_SIZE_RANGE \
                           ", " PYROCAM_FRAMERATE_RANGE
#define PYROCAM_RAW_GRAY_CAPS                                                              \
  PYROCAM_VIDEO_MEDIA_TYPE ", format = (string) { GRAY8, GRAY16_LE }, " PYROCAM_SIZE_RANGE \
                           ", " PYROCAM_FRAMERATE_RANGE
#define PYROCAM_RAW_CAPS PYROCAM_RAW_BAYER_CAPS "; " PYROCAM_RAW_GRAY_CAPS

#define PYROCAM_MOSAIC_CAPS                                                                       \
  PYROCAM_MOSAIC_MEDIA_TYPE ", format = (string) F32LE, " PYROCAM_SIZE_RANGE                      \
                            ", " PYROCAM_FRAMERATE_RANGE ", pattern = (string) " PYROCAM_PATTERNS \
                            ", bit-depth = (int) [ 1, 16 ]"

#define PYROCAM_BANDS_CAPS                                                   \
  PYROCAM_BANDS_MEDIA_TYPE                                                   \
  ", format = (string) F32LE, bands = (int) [ 1, max ], " PYROCAM_SIZE_RANGE \
  ", " PYROCAM_FRAMERATE_RANGE ", layout = (string) " PYROCAM_LAYOUTS

/* The band planes as the mosaic they are demosaicked from (the fused path, see above). */
#define PYROCAM_CAPS_FEATURE_MOSAIC "memory:PyrocamMosaic"
#define PYROCAM_FIELD_NO_SIGNAL_LEVEL "no-signal-level"
#define PYROCAM_FUSED_BANDS_CAPS                                                              \
  PYROCAM_BANDS_MEDIA_TYPE "(" PYROCAM_CAPS_FEATURE_MOSAIC                                    \
                           "), format = (string) F32LE, bands = (int) 3, " PYROCAM_SIZE_RANGE \
                           ", " PYROCAM_FRAMERATE_RANGE                                       \
                           ", layout = (string) bayer, pattern = (string) " PYROCAM_BAYER_FORMATS

/* Colour-mapped temperatures (thermalcolormap's output, thermaloverlay's overlay input) and the
 * camera images thermaloverlay lays them on: 4 bytes a pixel, alpha (or padding) last. */
#define PYROCAM_RGBA_FORMATS "{ RGBA, BGRA, RGBx, BGRx }"
#define PYROCAM_RGBA_CAPS GST_VIDEO_CAPS_MAKE(PYROCAM_RGBA_FORMATS)
#define PYROCAM_OVERLAY_CAPS GST_VIDEO_CAPS_MAKE("{ RGBA, BGRA }")

#define PYROCAM_TEMPERATURE_CAPS                                                \
  PYROCAM_VIDEO_MEDIA_TYPE ", format = (string) GRAY16_LE, " PYROCAM_SIZE_RANGE \
                           ", " PYROCAM_FRAMERATE_RANGE
