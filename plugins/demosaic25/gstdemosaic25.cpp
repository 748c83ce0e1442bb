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

#include "demosaic25-private.h"
#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/mixed_pixels.h"

GST_DEBUG_CATEGORY(gst_demosaic25_debug);
#define GST_CAT_DEFAULT gst_demosaic25_debug

namespace pg = pyrocam::gst;
namespace dm = pyrocam::gst::demosaic25;
using dm::copy_settings;
using dm::DEFAULT_METHOD;
using dm::DEFAULT_MIXED_PIXELS;
using dm::fused_path_allowed;
using dm::is_snapshot;
using dm::kColourCameraProfile;
using dm::PROP_METHOD;
using dm::PROP_MIXED_PIXELS;
using dm::PROP_PROFILE;
using dm::Settings;
using dm::State;
using dm::to_library;

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
  pg::forget_posted_errors(GST_ELEMENT(trans));
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
  // A frame without an image (darksub capturing a dark) stays one.
  if (GST_BUFFER_FLAG_IS_SET(inbuf, GST_BUFFER_FLAG_GAP))
    GST_BUFFER_FLAG_SET(outbuf, GST_BUFFER_FLAG_GAP);
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
  const char* refused_while_running = nullptr;  // posted once the lock is released
  {
    pg::ObjectLock lock(self);
    Settings& s = *self->settings;
    const bool running = GST_STATE(self) > GST_STATE_READY;
    switch (prop_id) {
      case PROP_METHOD:
        if (running)
          refused_while_running = "method";
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
          refused_while_running = "profile";
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
  if (refused_while_running)
    pg::warn_not_changeable_while_running(GST_ELEMENT(self), refused_while_running);
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

  trans_class->transform_caps = GST_DEBUG_FUNCPTR(dm::transform_caps);
  trans_class->transform_size = GST_DEBUG_FUNCPTR(dm::transform_size);
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
