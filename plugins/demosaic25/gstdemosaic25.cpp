/**
 * SECTION:element-demosaic25
 * @title: demosaic25
 *
 * Turns a dark-subtracted mosaic (video/x-pyrocam-mosaic) into planar float32 band images
 * (video/x-pyrocam-bands, see pyrocam-caps.h), keeping the saturation (+INF) and no-reading
 * (NaN) marks: a band value computed from any saturated pixel is +INF, from any NaN pixel NaN.
 *
 * - 2x2 Bayer mosaics give 3 bands R, G, B. #GstDemosaic25:method bilinear keeps the full
 *   resolution: each missing band at a pixel is the mean of the nearest pixels of that band
 *   (mirrored at the borders), as the paper's colour camera gives a reading for every pixel.
 *   bin2x2 halves the resolution: R, the mean of both G, and B of each 2x2 cell, every value
 *   measured rather than interpolated. matched keeps the full resolution and gives every band
 *   of every pixel a symmetric 5x5 kernel of the same spread (1 pixel^2 along each axis), so
 *   that on a hot spot's curved signal the bands' interpolation errors cancel in their ratio
 *   (bilinear's differ and shift the colour: at a small peak 50-130 degC too hot) and a
 *   reading is that of the temperature field seen through one blur; a sample without light
 *   (below 5 noise-floor standard deviations) makes the bands drawn from it dim, so pixels at
 *   an edge to a cold background have no reading instead of a wild one. It costs about 1.6
 *   times bilinear's demosaicking (+6 % on the whole chain). A pool a few pixels across keeps
 *   few readings with it (its kernel reaches samples without light or saturated ones on the
 *   pool's steep sides), but right ones: bilinear's extra readings there are largely wild.
 * - 5x5 snapshot mosaics give 25 bands, one reading per 5x5 macro-pixel (output width/5 x
 *   height/5, as the paper); band index = row * 5 + column in the cell, or the band map of the
 *   camera profile named by #GstDemosaic25:profile. Each band is sampled at its own place in
 *   the cell, up to 2 pixels from the others: in a melt pool's gradient the bands of one cell
 *   see different temperatures and read far off (on simulated parabolic pools the core's
 *   median 73 degC rms, a third of the readings wild). matched (the default, through auto)
 *   interpolates each band to the cell's centre from the 3x3 cells around it with weights of
 *   the same spread for every band (0.25 cell^2 along each axis): 6 degC rms, 1.6 % wild;
 *   bilinear and bin2x2 keep the paper's one cell per reading. Averaging lowers the bands'
 *   noise, which the noise model does not know: the uncertainty output and the misfit check
 *   are conservative with it.
 *
 * #GstDemosaic25:method auto (the default) is matched, for 5x5 and Bayer mosaics alike.
 *
 * Linked to ratiotemp (directly or through a queue), a Bayer mosaic with method matched (or
 * auto) and no mixed-pixel check takes the fused path: the elements agree on
 * video/x-pyrocam-bands(memory:PyrocamMosaic), this element passes the mosaic on untouched and
 * ratiotemp demosaics it a strip of rows at a time where it reads it, so that the float planes
 * never cross memory; the readings are the same. Any other downstream element gets the planes.
 *
 * With a #GstDemosaic25:profile, a stream whose mosaic pattern (from the caps) is not the
 * profile's, or whose 5x5 band-map caps field (pyrocamsrc sets it from its profile) differs
 * from the profile's band map, is refused (CORE NEGOTIATION naming both). Without a profile the
 * stream's band-map orders the bands. The output caps' band-map says the order used.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc ! darksub dark-level=50 ! demosaic25 method=bin2x2 ! fakesink
 * gst-launch-1.0 pyrocamsrc scene=melt-pool ! darksub dark-level=50 ! demosaic25 method=matched ! \
 *     ratiotemp model=cam.json ! fakesink
 * ]|
 */
#include "gstdemosaic25.h"

#include <string>
#include <vector>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/mixed_pixels.h"

GST_DEBUG_CATEGORY_STATIC(gst_demosaic25_debug);
#define GST_CAT_DEFAULT gst_demosaic25_debug

namespace pg = pyrocam::gst;

namespace {

enum { PROP_0, PROP_METHOD, PROP_PROFILE, PROP_MIXED_PIXELS };

constexpr GstDemosaic25Method DEFAULT_METHOD = GST_DEMOSAIC25_METHOD_AUTO;
// Off by default: it costs under the 15 % of the colour chain a default may cost, but it takes
// most readings of small melt pools at a fixed exposure (their steep sides; docs/elements.md).
constexpr double DEFAULT_MIXED_PIXELS = 0;
// The shipped colour camera, whose noise the mixed-pixel check assumes without a profile.
constexpr const char* kColourCameraProfile = "rgb-reference";

struct Settings {
  GstDemosaic25Method method = DEFAULT_METHOD;
  std::string profile;
  double mixed_pixels = DEFAULT_MIXED_PIXELS;  // relative spread; 0: no check
};

struct State {
  bool have_snapshot_layout = false;  // from the profile, loaded in start()
  pyrocam::MosaicLayout snapshot_layout;
  std::string profile_name, profile_pattern;  // the profile's mosaic as a caps pattern
  std::string profile_band_map;  // band-map text of a 5x5 profile; under the object lock
  bool configured = false;
  pyrocam::MosaicLayout layout;
  pyrocam::DemosaicMethod method = pyrocam::DemosaicMethod::kBilinear;
  int in_width = 0, in_height = 0, out_width = 0, out_height = 0, bands = 0;
  std::vector<cv::Mat> planes;                      // headers onto the output buffer, reused
  std::vector<pyrocam::SignalNoise> profile_noise;  // per band, from the profile; empty: none
  std::vector<pyrocam::SignalNoise> noise;          // per band, for the stream's bit depth
  double profile_dim_dn = -1;                       // the profile's dim threshold; <0: none
  float skip_below_dn = 0;  // the mixed-pixel check leaves footprints dimmer than this alone
  float no_signal_dn = 0;   // method matched: samples below it hold no light
};

pyrocam::DemosaicMethod to_library(GstDemosaic25Method m) {
  switch (m) {
    case GST_DEMOSAIC25_METHOD_BIN2X2:
      return pyrocam::DemosaicMethod::kBinCells;
    case GST_DEMOSAIC25_METHOD_MATCHED:
      return pyrocam::DemosaicMethod::kMatched;
    case GST_DEMOSAIC25_METHOD_AUTO:
      return pyrocam::DemosaicMethod::kAuto;
    default:
      return pyrocam::DemosaicMethod::kBilinear;
  }
}

bool is_snapshot(const char* pattern) {
  return pattern && g_str_equal(pattern, PYROCAM_SNAPSHOT_PATTERN_NAME);
}

}  // namespace

struct _GstDemosaic25 {
  GstBaseTransform parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstDemosaic25, gst_demosaic25, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(demosaic25, "demosaic25", GST_RANK_NONE, GST_TYPE_DEMOSAIC25);

GType gst_demosaic25_method_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_DEMOSAIC25_METHOD_BILINEAR, "Bilinear interpolation, full resolution", "bilinear"},
      {GST_DEMOSAIC25_METHOD_BIN2X2, "2x2 binning (R, mean G, B per cell), half resolution",
       "bin2x2"},
      {GST_DEMOSAIC25_METHOD_MATCHED,
       "Moment-matched interpolation, full resolution: every band through a kernel of the same "
       "spread, samples without light make a band dim",
       "matched"},
      {GST_DEMOSAIC25_METHOD_AUTO, "matched, for 5x5 and Bayer mosaics", "auto"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstDemosaic25Method", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_MOSAIC_CAPS));
static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS,
                            GST_STATIC_CAPS(PYROCAM_BANDS_CAPS "; " PYROCAM_FUSED_BANDS_CAPS));

static Settings copy_settings(GstDemosaic25* self) {
  return pg::locked_copy(self, *self->settings);
}

/* Whether the settings let demosaic25 hand its planes on as their mosaic (the fused path): a
 * Bayer mosaic with method matched and no mixed-pixel check (the defaults). */
static bool fused_path_allowed(const Settings& s) {
  return (s.method == GST_DEMOSAIC25_METHOD_MATCHED || s.method == GST_DEMOSAIC25_METHOD_AUTO) &&
         s.mixed_pixels == 0;
}

/* A dimension scaled by 1/divisor (forward) or by divisor (backward, any remainder allowed). */
static void scale_dimension(const GstStructure* from, GstStructure* to, const char* field,
                            int divisor, bool forward) {
  const GValue* v = gst_structure_get_value(from, field);
  if (v && G_VALUE_HOLDS_INT(v)) {
    const int n = g_value_get_int(v);
    if (divisor == 1)
      gst_structure_set(to, field, G_TYPE_INT, n, nullptr);
    else if (forward)
      gst_structure_set(to, field, G_TYPE_INT, std::max(1, n / divisor), nullptr);
    else if (n <= G_MAXINT / divisor - 1)
      gst_structure_set(to, field, GST_TYPE_INT_RANGE, n * divisor, n * divisor + divisor - 1,
                        nullptr);
    else
      gst_structure_set(to, field, GST_TYPE_INT_RANGE, 1, G_MAXINT, nullptr);
  } else {
    gst_structure_set(to, field, GST_TYPE_INT_RANGE, 1, G_MAXINT, nullptr);
  }
}

static GstCaps* gst_demosaic25_transform_caps(GstBaseTransform* trans, GstPadDirection direction,
                                              GstCaps* caps, GstCaps* filter) {
  GstDemosaic25* self = GST_DEMOSAIC25(trans);
  const Settings settings = copy_settings(self);
  const int bayer_divisor = settings.method == GST_DEMOSAIC25_METHOD_BIN2X2 ? 2 : 1;
  const std::string profile_band_map = pg::locked_copy(self, self->state->profile_band_map);
  const bool forward = direction == GST_PAD_SINK;
  const bool fusable = fused_path_allowed(settings);
  GstCaps* result = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    const GstStructure* s = gst_caps_get_structure(caps, i);
    // Fused bands come from a Bayer mosaic demosaicked with matched, without the check.
    if (!forward && pg::is_fused_bands(caps, i) && !fusable) continue;
    /* Which layouts this structure allows. */
    bool bayer = true, snapshot = true;
    const char* fixed = gst_structure_get_string(s, forward ? "pattern" : "layout");
    if (fixed) {
      snapshot = is_snapshot(fixed);
      bayer = !snapshot;
    }
    for (int pass = 0; pass < 2; ++pass) {
      const bool snap = pass == 1;
      if ((snap && !snapshot) || (!snap && !bayer)) continue;
      const int divisor = snap ? 5 : bayer_divisor;
      GstStructure* out;
      if (forward) {
        out = gst_structure_new(PYROCAM_BANDS_MEDIA_TYPE, "format", G_TYPE_STRING, "F32LE", "bands",
                                G_TYPE_INT, snap ? 25 : 3, "layout", G_TYPE_STRING,
                                snap ? PYROCAM_SNAPSHOT_PATTERN_NAME : "bayer", nullptr);
        if (snap) {
          /* The band order of the planes: the profile's, else the input's, else row * 5 +
           * column (set_caps refuses a profile and an input that disagree). */
          const char* in_map = gst_structure_get_string(s, PYROCAM_FIELD_BAND_MAP);
          std::string map = profile_band_map.empty() ? (in_map ? in_map : "") : profile_band_map;
          if (map.empty())
            map = pg::band_map_text(pg::layout_for_pattern(PYROCAM_SNAPSHOT_PATTERN_NAME));
          gst_structure_set(out, PYROCAM_FIELD_BAND_MAP, G_TYPE_STRING, map.c_str(), nullptr);
        }
      } else {
        out = gst_structure_new(PYROCAM_MOSAIC_MEDIA_TYPE, "format", G_TYPE_STRING, "F32LE",
                                "bit-depth", GST_TYPE_INT_RANGE, 1, 16, nullptr);
        if (snap) {
          gst_structure_set(out, "pattern", G_TYPE_STRING, PYROCAM_SNAPSHOT_PATTERN_NAME, nullptr);
        } else {
          pg::set_list_field(out, "pattern", PYROCAM_BAYER_FORMATS);
        }
      }
      if (forward) pg::copy_fields(s, out, {PYROCAM_FIELD_SATURATION_LEVEL});
      if (!forward && pg::is_fused_bands(caps, i)) pg::copy_fields(s, out, {"pattern"});
      scale_dimension(s, out, "width", divisor, forward);
      scale_dimension(s, out, "height", divisor, forward);
      pg::copy_fields(s, out, {"framerate"});
      // The planes as their mosaic, after the planes themselves: ratiotemp asks for it first,
      // any other element (or a sink taking anything) gets the planes.
      GstStructure* fused = forward && !snap && fusable ? gst_structure_copy(out) : nullptr;
      result = gst_caps_merge_structure(result, out);
      if (fused) {
        if (const char* p = gst_structure_get_string(s, "pattern"))
          gst_structure_set(fused, "pattern", G_TYPE_STRING, p, nullptr);
        else
          pg::set_list_field(fused, "pattern", PYROCAM_BAYER_FORMATS);
        result = gst_caps_merge_structure_full(
            result, fused, gst_caps_features_new(PYROCAM_CAPS_FEATURE_MOSAIC, nullptr));
      }
    }
  }
  if (filter) {
    GstCaps* tmp = gst_caps_intersect_full(filter, result, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(result);
    result = tmp;
  }
  GST_DEBUG_OBJECT(self, "transformed %" GST_PTR_FORMAT " to %" GST_PTR_FORMAT, caps, result);
  return result;
}

static gboolean gst_demosaic25_transform_size(GstBaseTransform* /*trans*/,
                                              GstPadDirection direction, GstCaps* /*caps*/,
                                              gsize /*size*/, GstCaps* othercaps,
                                              gsize* othersize) {
  const GstStructure* s = gst_caps_get_structure(othercaps, 0);
  const gsize w = static_cast<gsize>(pg::structure_int(s, "width", 0));
  const gsize h = static_cast<gsize>(pg::structure_int(s, "height", 0));
  const gsize planes =
      direction == GST_PAD_SINK ? static_cast<gsize>(pg::structure_int(s, "bands", 0)) : 1;
  *othersize = w * h * planes * sizeof(float);
  return *othersize > 0;
}

/* The bit depth of a mosaic's caps (8 without the field). */
static int stream_bit_depth(GstCaps* caps) {
  int depth = 8;
  gst_structure_get_int(gst_caps_get_structure(caps, 0), "bit-depth", &depth);
  return depth;
}

/* The noise of the stream's bands, for the mixed-pixel check and matched's no-light level: the
 * profile's, else, for a Bayer mosaic, that of the shipped colour camera band by band (what
 * pyrocam-calib measure uses for its models) scaled to the stream's bit depth, else its red
 * band's (0.03 DN per electron, 6 electrons read noise at 8 bits) for every band. */
static std::vector<pyrocam::SignalNoise> stream_noise(GstDemosaic25* self, const State& st,
                                                      int bands, pyrocam::MosaicLayout::Kind kind,
                                                      int depth) {
  std::vector<pyrocam::SignalNoise> noise = st.profile_noise;
  const double scale = std::ldexp(1.0, depth - 8);
  if (static_cast<int>(noise.size()) < bands && kind == pyrocam::MosaicLayout::Kind::kBayer) {
    try {
      const pyrocam::CameraProfile colour = pyrocam::load_profile_by_name(kColourCameraProfile);
      const double s = std::ldexp(1.0, depth - colour.bit_depth);
      if (colour.band_count() == bands)
        for (int b = 0; b < bands; ++b) {
          const pyrocam::SignalNoise n = pyrocam::signal_noise(colour, b);
          noise.push_back(pyrocam::SignalNoise{n.shot_gain * s, n.floor_dn2 * s * s});
        }
    } catch (const std::exception& e) {
      GST_WARNING_OBJECT(self, "no %s profile for the mixed-pixel check's noise: %s",
                         kColourCameraProfile, e.what());
    }
  }
  if (static_cast<int>(noise.size()) < bands)
    noise.assign(static_cast<std::size_t>(bands),
                 pyrocam::SignalNoise{0.03 * scale, 0.23 * scale * scale});
  return noise;
}

/* Fused bands carry the no-light level ratiotemp demosaics with: set here, once the input is
 * known. */
static GstCaps* gst_demosaic25_fixate_caps(GstBaseTransform* trans, GstPadDirection direction,
                                           GstCaps* caps, GstCaps* othercaps) {
  GstDemosaic25* self = GST_DEMOSAIC25(trans);
  othercaps = gst_caps_fixate(othercaps);
  if (direction != GST_PAD_SINK || !pg::is_fused_bands(othercaps)) return othercaps;
  othercaps = gst_caps_make_writable(othercaps);
  const std::vector<pyrocam::SignalNoise> noise = stream_noise(
      self, *self->state, 3, pyrocam::MosaicLayout::Kind::kBayer, stream_bit_depth(caps));
  gst_structure_set(
      gst_caps_get_structure(othercaps, 0), PYROCAM_FIELD_NO_SIGNAL_LEVEL, G_TYPE_DOUBLE,
      static_cast<double>(static_cast<float>(pyrocam::no_signal_level_dn(noise))), nullptr);
  return othercaps;
}

static gboolean gst_demosaic25_set_caps(GstBaseTransform* trans, GstCaps* incaps,
                                        GstCaps* outcaps) {
  GstDemosaic25* self = GST_DEMOSAIC25(trans);
  const Settings settings = copy_settings(self);
  State& st = *self->state;
  st.configured = false;
  const GstStructure* in = gst_caps_get_structure(incaps, 0);
  const GstStructure* out = gst_caps_get_structure(outcaps, 0);
  const char* pattern = gst_structure_get_string(in, "pattern");
  st.in_width = pg::structure_int(in, "width", 0);
  st.in_height = pg::structure_int(in, "height", 0);
  st.out_width = pg::structure_int(out, "width", 0);
  st.out_height = pg::structure_int(out, "height", 0);
  st.bands = pg::structure_int(out, "bands", 0);
  st.method = to_library(settings.method);
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kNegotiation, "Unsupported mosaic", [&] {
    if (!pattern) throw pyrocam::InputError("the input caps name no pattern");
    if (!st.profile_pattern.empty() && st.profile_pattern != pattern)
      throw pyrocam::InputError("camera profile " + st.profile_name + " has a " +
                                st.profile_pattern + " mosaic but the stream is a " + pattern +
                                " mosaic");
    const char* in_map = gst_structure_get_string(in, PYROCAM_FIELD_BAND_MAP);
    if (is_snapshot(pattern) && in_map) {
      const pyrocam::MosaicLayout camera = pg::layout_for_band_map(in_map);
      if (st.have_snapshot_layout && camera.band_map != st.snapshot_layout.band_map)
        throw pyrocam::InputError("camera profile " + st.profile_name + " orders the 5x5 bands " +
                                  pg::band_map_text(st.snapshot_layout) +
                                  " but the stream's camera orders them " + in_map);
      st.layout = st.have_snapshot_layout ? st.snapshot_layout : camera;
    } else if (is_snapshot(pattern) && st.have_snapshot_layout) {
      st.layout = st.snapshot_layout;
    } else {
      st.layout = pg::layout_for_pattern(pattern);
    }
    const char* out_map = gst_structure_get_string(out, PYROCAM_FIELD_BAND_MAP);
    if (is_snapshot(pattern) && out_map && pg::band_map_text(st.layout) != out_map)
      throw pyrocam::InputError("downstream asks for the 5x5 band order " + std::string(out_map) +
                                ", the planes are in the order " + pg::band_map_text(st.layout));
    const cv::Size size =
        pyrocam::demosaic_output_size(st.layout, st.method, {st.in_width, st.in_height});
    if (size.width != st.out_width || size.height != st.out_height ||
        st.bands != st.layout.band_count())
      throw pyrocam::InputError("a " + std::to_string(st.in_width) + "x" +
                                std::to_string(st.in_height) + " " + pattern + " mosaic gives " +
                                std::to_string(st.layout.band_count()) + " bands of " +
                                std::to_string(size.width) + "x" + std::to_string(size.height) +
                                ", not " + std::to_string(st.bands) + " of " +
                                std::to_string(st.out_width) + "x" + std::to_string(st.out_height));
    if (size.width < 1 || size.height < 1)
      throw pyrocam::InputError("the mosaic is smaller than one period");
  });
  if (!ok) return FALSE;
  const int depth = stream_bit_depth(incaps);
  st.noise = stream_noise(self, st, st.bands, st.layout.kind, depth);
  // Footprints all below the dim threshold give pixels without a reading whatever the check
  // says: the profile's threshold, else the shipped profiles' 20 DN at 8 bits.
  st.skip_below_dn = static_cast<float>(st.profile_dim_dn >= 0 ? st.profile_dim_dn
                                                               : 20 * std::ldexp(1.0, depth - 8));
  st.no_signal_dn = static_cast<float>(pyrocam::no_signal_level_dn(st.noise));
  // The fused path: the planes go on as their mosaic, which ratiotemp demosaics the same way.
  const bool fused = pg::is_fused_bands(outcaps);
  if (fused) {
    double level = NAN;
    gst_structure_get_double(out, PYROCAM_FIELD_NO_SIGNAL_LEVEL, &level);
    if (!fused_path_allowed(settings) || st.layout.kind != pyrocam::MosaicLayout::Kind::kBayer ||
        static_cast<float>(level) != st.no_signal_dn) {
      PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "Unsupported output format",
                         "fused bands asked for without a Bayer mosaic, method matched and no "
                         "mixed-pixel check, or with another no-signal level");
      return FALSE;
    }
  }
  gst_base_transform_set_passthrough(trans, fused);
  st.configured = true;
  GST_INFO_OBJECT(self, "%dx%d %s -> %d bands of %dx%d%s", st.in_width, st.in_height, pattern,
                  st.bands, st.out_width, st.out_height,
                  fused ? " (fused: the mosaic passes on, ratiotemp demosaics it)" : "");
  return TRUE;
}

static gboolean gst_demosaic25_start(GstBaseTransform* trans) {
  GstDemosaic25* self = GST_DEMOSAIC25(trans);
  const Settings settings = copy_settings(self);
  State& st = *self->state;
  {
    pg::ObjectLock lock(self);
    st = State();
  }
  if (settings.profile.empty()) return TRUE;
  pyrocam::CameraProfile profile;
  const bool ok = PYROCAM_GUARDED(self, pg::profile_error_kind(settings.profile),
                                  "Could not load camera profile " + settings.profile, [&] {
                                    profile = pyrocam::load_profile_by_name(settings.profile);
                                  });
  if (!ok) return FALSE;
  if (profile.mosaic.kind == pyrocam::MosaicLayout::Kind::kSnapshot) {
    if (profile.mosaic.period_width != 5 || profile.mosaic.period_height != 5) {
      PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                         "Camera profile " + settings.profile + " has a " + profile.mosaic.pattern +
                             " mosaic; only 5x5 is supported",
                         "snapshot mosaic period is not 5x5");
      return FALSE;
    }
    st.snapshot_layout = profile.mosaic;
    st.have_snapshot_layout = true;
    {
      pg::ObjectLock lock(self);
      st.profile_band_map = pg::band_map_text(profile.mosaic);
    }
    st.profile_pattern = PYROCAM_SNAPSHOT_PATTERN_NAME;
  } else {
    st.profile_pattern = profile.mosaic.pattern;
    for (char& c : st.profile_pattern) c = static_cast<char>(g_ascii_tolower(c));
  }
  for (int b = 0; b < profile.band_count(); ++b)
    st.profile_noise.push_back(pyrocam::signal_noise(profile, b));
  st.profile_dim_dn = profile.thresholds.inference_dim_dn;
  st.profile_name = settings.profile;
  GST_INFO_OBJECT(self, "camera profile %s (%s)", profile.name.c_str(),
                  profile.mosaic.pattern.c_str());
  return TRUE;
}

static gboolean gst_demosaic25_stop(GstBaseTransform* trans) {
  pg::ObjectLock lock(trans);
  *GST_DEMOSAIC25(trans)->state = State();
  return TRUE;
}

static GstFlowReturn gst_demosaic25_transform(GstBaseTransform* trans, GstBuffer* inbuf,
                                              GstBuffer* outbuf) {
  GstDemosaic25* self = GST_DEMOSAIC25(trans);
  State& st = *self->state;
  if (!st.configured) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "No format negotiated",
                       "transform called before set_caps");
    return GST_FLOW_NOT_NEGOTIATED;
  }
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not demosaic", [&] {
    pg::MappedImage in, out;
    in.map_float(inbuf, st.in_width, st.in_height, 1, GST_MAP_READ);
    out.map_float(outbuf, st.out_width, st.out_height, st.bands, GST_MAP_WRITE);
    st.planes.resize(static_cast<std::size_t>(st.bands));
    for (int b = 0; b < st.bands; ++b)
      st.planes[static_cast<std::size_t>(b)] = out.plane(b, st.out_width, st.out_height);
    const double spread = pg::locked_copy(self, self->settings->mixed_pixels);
    if (spread > 0) {
      pyrocam::FootprintCheck check;
      check.relative_spread = spread;
      check.noise = st.noise;
      check.skip_below_dn = st.skip_below_dn;
      pyrocam::demosaic_marking_mixed(in.image(), st.layout, st.method, check, st.planes,
                                      st.no_signal_dn);
    } else {
      pyrocam::demosaic(in.image(), st.layout, st.method, st.planes, st.no_signal_dn);
    }
  });
  return ok ? GST_FLOW_OK : GST_FLOW_ERROR;
}

static void gst_demosaic25_set_property(GObject* object, guint prop_id, const GValue* value,
                                        GParamSpec* pspec) {
  GstDemosaic25* self = GST_DEMOSAIC25(object);
  bool reconfigure = false;
  {
    pg::ObjectLock lock(self);
    Settings& s = *self->settings;
    const bool running = GST_STATE(self) > GST_STATE_READY;
    switch (prop_id) {
      case PROP_METHOD:
        if (running)
          GST_WARNING_OBJECT(self, "method can only change in NULL or READY");
        else
          s.method = static_cast<GstDemosaic25Method>(g_value_get_enum(value));
        break;
      case PROP_MIXED_PIXELS: {
        const double spread = g_value_get_double(value);
        // Turning the check on or off while playing starts or ends the fused path.
        if ((spread == 0) != (s.mixed_pixels == 0)) reconfigure = true;
        s.mixed_pixels = spread;
        break;
      }
      case PROP_PROFILE:
        if (running) {
          GST_WARNING_OBJECT(self, "profile can only change in NULL or READY");
        } else {
          const char* v = g_value_get_string(value);
          s.profile = v ? v : "";
        }
        break;
      default:
        G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
        break;
    }
  }
  if (reconfigure) gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

static void gst_demosaic25_get_property(GObject* object, guint prop_id, GValue* value,
                                        GParamSpec* pspec) {
  GstDemosaic25* self = GST_DEMOSAIC25(object);
  pg::ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_METHOD:
      g_value_set_enum(value, s.method);
      break;
    case PROP_PROFILE:
      g_value_set_string(value, s.profile.empty() ? nullptr : s.profile.c_str());
      break;
    case PROP_MIXED_PIXELS:
      g_value_set_double(value, s.mixed_pixels);
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

static void gst_demosaic25_finalize(GObject* object) {
  GstDemosaic25* self = GST_DEMOSAIC25(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_demosaic25_parent_class)->finalize(object);
}

static void gst_demosaic25_class_init(GstDemosaic25Class* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_demosaic25_debug, "demosaic25", 0, "pyrocam demosaicking");

  gobject_class->set_property = gst_demosaic25_set_property;
  gobject_class->get_property = gst_demosaic25_get_property;
  gobject_class->finalize = gst_demosaic25_finalize;

  const auto ready = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                              GST_PARAM_MUTABLE_READY);
  g_object_class_install_property(
      gobject_class, PROP_METHOD,
      g_param_spec_enum(
          "method", "Demosaicking method",
          "How mosaics become band planes. Bayer: bilinear (full resolution, "
          "interpolated), bin2x2 (half resolution, R, mean G, B of each cell) or "
          "matched (full resolution, every band through a 5x5 kernel of the same "
          "spread: no colour shift on hot spots, no wild ratios at edges to a cold "
          "background; about 1.6 times bilinear's cost). 5x5 mosaics give one reading "
          "per macro-pixel: matched reads each band at the cell's centre "
          "(interpolated over 3x3 cells), bilinear and bin2x2 where it sits in the "
          "cell. auto: matched",
          GST_TYPE_DEMOSAIC25_METHOD, DEFAULT_METHOD, ready));
  g_object_class_install_property(
      gobject_class, PROP_PROFILE,
      g_param_spec_string("profile", "Camera profile",
                          "Camera profile (shipped name such as nir5x5-reference, or a path to "
                          "its JSON file) whose 5x5 band map orders the output bands; a stream "
                          "whose mosaic is not the profile's is refused; empty: band index = "
                          "row * 5 + column",
                          nullptr, ready));
  g_object_class_install_property(
      gobject_class, PROP_MIXED_PIXELS,
      g_param_spec_double(
          "mixed-pixels", "Mixed-pixel check",
          "Bayer mosaics: an output pixel whose footprint (the 3x3 mosaic pixels bilinear "
          "draws on, each band's kernel samples with matched, the 2x2 cell with bin2x2) holds "
          "samples of one band differing by more than "
          "this share of the largest plus 5 noise standard deviations gets no reading (NaN in "
          "every band): at a sharp edge they see different temperatures and read wild (0..10; "
          "0 = no check, the default; 0.5 suits method=bilinear: a gradient that makes a "
          "band's interpolation err as much as noise does at the dim threshold; the noise model "
          "is the profile's, else the shipped colour camera's scaled to the bit depth)",
          0.0, pyrocam::kMaxRelativeSpread, DEFAULT_MIXED_PIXELS,
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_PLAYING)));

  gst_element_class_set_static_metadata(
      element_class, "Mosaic to band planes", "Filter/Video",
      "Demosaics dark-subtracted Bayer or 5x5 snapshot mosaics into float32 band planes",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_demosaic25_transform_caps);
  trans_class->transform_size = GST_DEBUG_FUNCPTR(gst_demosaic25_transform_size);
  trans_class->fixate_caps = GST_DEBUG_FUNCPTR(gst_demosaic25_fixate_caps);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_demosaic25_set_caps);
  trans_class->decide_allocation = GST_DEBUG_FUNCPTR(pg::decide_allocation);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_demosaic25_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_demosaic25_stop);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_demosaic25_transform);

  gst_type_mark_as_plugin_api(GST_TYPE_DEMOSAIC25_METHOD, static_cast<GstPluginAPIFlags>(0));
}

static void gst_demosaic25_init(GstDemosaic25* self) {
  self->settings = new Settings();
  self->state = new State();
}
