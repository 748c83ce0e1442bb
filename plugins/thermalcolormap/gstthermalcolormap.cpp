/**
 * SECTION:element-thermalcolormap
 * @title: thermalcolormap
 *
 * Paints temperature images (video/x-raw GRAY16_LE in 0.1 K, 0 = no reading) in false colour
 * for display: RGBA/BGRA (or RGBx/BGRx) with the chosen #GstThermalColormap:palette between
 * #GstThermalColormap:min-temperature and #GstThermalColormap:max-temperature (fixed), or the
 * frame's own valid range smoothed over time (auto, see #GstThermalColormap:auto-smoothing),
 * without the #GstThermalColormap:auto-trim percent hottest and coldest readings of each frame
 * (the wild mixed pixels at sharp edges would otherwise stretch it).
 * Pixels without a reading get #GstThermalColormap:invalid-color, fully transparent by default,
 * so the output overlays cleanly on the camera image with compositor. Pixels at or above
 * #GstThermalColormap:isotherm-threshold get #GstThermalColormap:isotherm-color (an alarm).
 * #GstThermalColormap:scale-bar draws the palette with labelled ticks in degC at the right edge.
 * #GstThermalColormap:peak-marker rings the frame's peak (the largest median of
 * #GstThermalColormap:peak-window square windows, as ratiotemp's peak-c) and writes its
 * temperature at the top left: "peak 2213 degC", or "peak >= 2213 degC (saturated)" where
 * pixels have no reading beside the saturated samples the frame's PyrocamSaturationMeta
 * (darksub's, carried through demosaic25 and ratiotemp) names: that part is hotter than the
 * peak read ("saturated, no reading" when nothing reads). Where the frame's PyrocamAboveRangeMeta
 * (ratiotemp's) names pixels hotter than the model's range, the ring goes round them and the
 * label reads "peak > 3500 degC (above range)", the range's end, whatever reads elsewhere. On
 * frames whose PyrocamUncertaintyMeta (ratiotemp's) gives the model's systematic uncertainty, a
 * peak that reads says it: "peak 2213 degC +/-38 sys" (expanded; the pixels' noise not in it).
 *
 * In fixed mode a range narrower than one temperature code (max-temperature - min-temperature
 * below 0.1 degC, including min-temperature >= max-temperature) is refused with a warning on
 * the bus (RESOURCE SETTINGS) and the last good range stays in use (the default 500..2500 degC
 * before there is one), so that a user interface setting one end after the other never stops
 * the display.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=model.json ! \
 *     thermalcolormap palette=inferno scale-bar=true isotherm-threshold=2200 ! videoconvert ! \
 *     autovideosink
 * ]|
 */
#include "gstthermalcolormap.h"

#include <cmath>
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/colormap.h"
#include "pyrocam/runtime/region_stats.h"

GST_DEBUG_CATEGORY_STATIC(gst_thermal_colormap_debug);
#define GST_CAT_DEFAULT gst_thermal_colormap_debug

namespace pg = pyrocam::gst;

namespace {

enum {
  PROP_0,
  PROP_PALETTE,
  PROP_RANGE_MODE,
  PROP_MIN_TEMPERATURE,
  PROP_MAX_TEMPERATURE,
  PROP_AUTO_SMOOTHING,
  PROP_AUTO_TRIM,
  PROP_SCALE_BAR,
  PROP_INVALID_COLOR,
  PROP_ISOTHERM_THRESHOLD,
  PROP_ISOTHERM_COLOR,
  PROP_PEAK_MARKER,
  PROP_PEAK_WINDOW,
};

constexpr GstThermalColormapPalette DEFAULT_PALETTE = GST_THERMAL_COLORMAP_PALETTE_IRON;
constexpr GstThermalColormapRangeMode DEFAULT_RANGE_MODE = GST_THERMAL_COLORMAP_RANGE_AUTO;
constexpr double DEFAULT_MIN_TEMPERATURE = 500.0;
constexpr double DEFAULT_MAX_TEMPERATURE = 2500.0;
constexpr double DEFAULT_AUTO_SMOOTHING = 0.1;
// Enough to drop the wild mixed pixels along a plate's edges, little enough that a melt pool
// covering 1 % of the readings still sets the top of the range.
constexpr double DEFAULT_AUTO_TRIM = 0.5;
constexpr gboolean DEFAULT_SCALE_BAR = FALSE;
constexpr guint DEFAULT_INVALID_COLOR = 0x00000000u;
constexpr double ISOTHERM_OFF = -273.15;
constexpr double DEFAULT_ISOTHERM_THRESHOLD = ISOTHERM_OFF;
constexpr guint DEFAULT_ISOTHERM_COLOR = 0xFF00FF00u;
constexpr gboolean DEFAULT_PEAK_MARKER = FALSE;
constexpr guint DEFAULT_PEAK_WINDOW = pyrocam::kDefaultPeakWindow;

struct Settings {
  GstThermalColormapPalette palette = DEFAULT_PALETTE;
  GstThermalColormapRangeMode range_mode = DEFAULT_RANGE_MODE;
  double min_c = DEFAULT_MIN_TEMPERATURE, max_c = DEFAULT_MAX_TEMPERATURE;
  double auto_smoothing = DEFAULT_AUTO_SMOOTHING;
  double auto_trim = DEFAULT_AUTO_TRIM;
  gboolean scale_bar = DEFAULT_SCALE_BAR;
  guint invalid_color = DEFAULT_INVALID_COLOR;
  double isotherm_c = DEFAULT_ISOTHERM_THRESHOLD;
  guint isotherm_color = DEFAULT_ISOTHERM_COLOR;
  gboolean peak_marker = DEFAULT_PEAK_MARKER;
  guint peak_window = DEFAULT_PEAK_WINDOW;  // odd
};

struct State {
  pyrocam::ThermalColormap colormap;
  pyrocam::AutoRange auto_range;
  pyrocam::ChannelOrder order = pyrocam::ChannelOrder::kRGBA;
  bool warned_range = false;
  bool warned_peak_window = false;
};

pyrocam::Palette to_library(GstThermalColormapPalette p) {
  switch (p) {
    case GST_THERMAL_COLORMAP_PALETTE_INFERNO:
      return pyrocam::Palette::kInferno;
    case GST_THERMAL_COLORMAP_PALETTE_RAINBOW:
      return pyrocam::Palette::kRainbow;
    case GST_THERMAL_COLORMAP_PALETTE_GREY:
      return pyrocam::Palette::kGrey;
    default:
      return pyrocam::Palette::kIron;
  }
}

}  // namespace

struct _GstThermalColormap {
  GstVideoFilter parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstThermalColormap, gst_thermal_colormap, GST_TYPE_VIDEO_FILTER);
GST_ELEMENT_REGISTER_DEFINE(thermalcolormap, "thermalcolormap", GST_RANK_NONE,
                            GST_TYPE_THERMAL_COLORMAP);

GType gst_thermal_colormap_palette_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_THERMAL_COLORMAP_PALETTE_IRON, "Iron (black, purple, red, yellow, white)", "iron"},
      {GST_THERMAL_COLORMAP_PALETTE_INFERNO, "Inferno (perceptually uniform)", "inferno"},
      {GST_THERMAL_COLORMAP_PALETTE_RAINBOW, "Rainbow (blue to red)", "rainbow"},
      {GST_THERMAL_COLORMAP_PALETTE_GREY, "Grey (black to white)", "grey"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstThermalColormapPalette", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

GType gst_thermal_colormap_range_mode_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_THERMAL_COLORMAP_RANGE_FIXED, "min-temperature to max-temperature", "fixed"},
      {GST_THERMAL_COLORMAP_RANGE_AUTO, "valid range of the frames, smoothed", "auto"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstThermalColormapRangeMode", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_TEMPERATURE_CAPS));
static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RGBA_CAPS));

static GstCaps* gst_thermal_colormap_transform_caps(GstBaseTransform* trans,
                                                    GstPadDirection direction, GstCaps* caps,
                                                    GstCaps* filter) {
  GstCaps* result = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    GstStructure* s = gst_structure_copy(gst_caps_get_structure(caps, i));
    gst_structure_remove_fields(s, "format", "colorimetry", "chroma-site", nullptr);
    if (direction == GST_PAD_SINK) {
      pg::set_list_field(s, "format", PYROCAM_RGBA_FORMATS);
    } else {
      gst_structure_set(s, "format", G_TYPE_STRING, "GRAY16_LE", nullptr);
    }
    result = gst_caps_merge_structure(result, s);
  }
  if (filter) {
    GstCaps* tmp = gst_caps_intersect_full(filter, result, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(result);
    result = tmp;
  }
  GST_DEBUG_OBJECT(trans, "transformed %" GST_PTR_FORMAT " to %" GST_PTR_FORMAT, caps, result);
  return result;
}

static gboolean gst_thermal_colormap_set_info(GstVideoFilter* filter, GstCaps* /*incaps*/,
                                              GstVideoInfo* in_info, GstCaps* /*outcaps*/,
                                              GstVideoInfo* out_info) {
  GstThermalColormap* self = GST_THERMAL_COLORMAP(filter);
  const GstVideoFormat f = GST_VIDEO_INFO_FORMAT(out_info);
  self->state->order = (f == GST_VIDEO_FORMAT_BGRA || f == GST_VIDEO_FORMAT_BGRx)
                           ? pyrocam::ChannelOrder::kBGRA
                           : pyrocam::ChannelOrder::kRGBA;
  if (GST_VIDEO_INFO_WIDTH(in_info) != GST_VIDEO_INFO_WIDTH(out_info) ||
      GST_VIDEO_INFO_HEIGHT(in_info) != GST_VIDEO_INFO_HEIGHT(out_info)) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "Input and output sizes differ",
                       "set_info with different widths or heights");
    return FALSE;
  }
  GST_INFO_OBJECT(self, "%dx%d to %s", GST_VIDEO_INFO_WIDTH(in_info),
                  GST_VIDEO_INFO_HEIGHT(in_info), gst_video_format_to_string(f));
  return TRUE;
}

static gboolean gst_thermal_colormap_start(GstBaseTransform* trans) {
  pg::forget_posted_errors(GST_ELEMENT(trans));
  GstThermalColormap* self = GST_THERMAL_COLORMAP(trans);
  *self->state = State();
  return TRUE;
}

static gboolean gst_thermal_colormap_stop(GstBaseTransform* trans) {
  *GST_THERMAL_COLORMAP(trans)->state = State();
  return TRUE;
}

/* GstVideoFilter answers a buffer it cannot map as a frame with a CORE NOT_IMPLEMENTED warning
 * and drops it; a temperature stream with frames of the wrong size is a STREAM FORMAT error. */
static GstFlowReturn gst_thermal_colormap_transform(GstBaseTransform* trans, GstBuffer* inbuf,
                                                    GstBuffer* outbuf) {
  GstVideoFilter* filter = GST_VIDEO_FILTER(trans);
  if (!filter->negotiated) {
    PYROCAM_POST_ERROR(trans, pg::ErrorKind::kNegotiation, "Not negotiated",
                       "transform called before set_caps");
    return GST_FLOW_NOT_NEGOTIATED;
  }
  if (!pg::temperature_frame_fits(trans, filter->in_info, inbuf)) return GST_FLOW_ERROR;
  return GST_BASE_TRANSFORM_CLASS(gst_thermal_colormap_parent_class)
      ->transform(trans, inbuf, outbuf);
}

static GstFlowReturn gst_thermal_colormap_transform_frame(GstVideoFilter* filter,
                                                          GstVideoFrame* in_frame,
                                                          GstVideoFrame* out_frame) {
  GstThermalColormap* self = GST_THERMAL_COLORMAP(filter);
  const Settings settings = pg::locked_copy(self, *self->settings);
  State& st = *self->state;
  const int width = GST_VIDEO_FRAME_WIDTH(in_frame), height = GST_VIDEO_FRAME_HEIGHT(in_frame);
  const cv::Mat in(height, width, CV_16U, GST_VIDEO_FRAME_PLANE_DATA(in_frame, 0),
                   static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(in_frame, 0)));
  cv::Mat out(height, width, CV_8UC4, GST_VIDEO_FRAME_PLANE_DATA(out_frame, 0),
              static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(out_frame, 0)));

  pyrocam::ColormapSettings cs;
  cs.palette = to_library(settings.palette);
  cs.invalid_argb = settings.invalid_color;
  cs.isotherm_argb = settings.isotherm_color;
  if (settings.isotherm_c > ISOTHERM_OFF) cs.isotherm_c = settings.isotherm_c;
  cs.order = st.order;
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kNumeric, "Could not colour the frame", [&] {
    if (settings.range_mode == GST_THERMAL_COLORMAP_RANGE_AUTO) {
      st.auto_range.update(pyrocam::trimmed_range_c(in, settings.auto_trim),
                           settings.auto_smoothing);
      cs.min_c = st.auto_range.valid() ? st.auto_range.min_c() : settings.min_c;
      cs.max_c = st.auto_range.valid() ? st.auto_range.max_c() : settings.max_c;
    } else {
      st.auto_range.reset();
      cs.min_c = settings.min_c;
      cs.max_c = settings.max_c;
    }
    if (!(cs.max_c - cs.min_c >= pyrocam::kMinColormapSpanC)) {
      if (!st.warned_range)
        GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                            ("min-temperature %.17g degC is not at least %g degC below "
                             "max-temperature %.17g degC; keeping the last range",
                             cs.min_c, pyrocam::kMinColormapSpanC, cs.max_c),
                            ("fixed range narrower than one temperature code"));
      st.warned_range = true;
      if (st.colormap.settings().max_c - st.colormap.settings().min_c >=
          pyrocam::kMinColormapSpanC) {
        cs.min_c = st.colormap.settings().min_c;
        cs.max_c = st.colormap.settings().max_c;
      } else {
        cs.min_c = DEFAULT_MIN_TEMPERATURE;
        cs.max_c = DEFAULT_MAX_TEMPERATURE;
      }
    } else {
      st.warned_range = false;
    }
    st.colormap.configure(cs);
    st.colormap.apply(in, out);
    if (settings.scale_bar) pyrocam::draw_scale_bar(out, cs.palette, cs.min_c, cs.max_c, cs.order);
    if (settings.peak_marker) {
      const int window = static_cast<int>(settings.peak_window);
      if (window <= width && window <= height) {
        const pyrocam::RegionPeak peak =
            pyrocam::region_peak(pyrocam::decode_decikelvin(in), window);
        // Light saturated the camera where pixels have no reading: they are hotter.
        const bool saturated =
            pg::saturation_hides_readings(pyrocam_buffer_get_saturation_meta(in_frame->buffer), in,
                                          cv::Rect(0, 0, width, height));
        // Parts hotter than the model's range: the ring on the largest of them (not between
        // two), the label says so.
        const PyrocamAboveRangeMeta* above = pyrocam_buffer_get_above_range_meta(in_frame->buffer);
        const cv::Rect spot = pg::largest_above_range_spot(above, cv::Size(width, height));
        if (spot.empty())
          pyrocam::draw_peak_marker(out, peak.x, peak.y, peak.c, cs.order, saturated, NAN,
                                    pg::systematic_u_at(in_frame->buffer, peak.c));
        else
          pyrocam::draw_peak_marker(out, spot.x + spot.width / 2, spot.y + spot.height / 2, peak.c,
                                    cs.order, saturated, above->max_temperature_c);
      } else if (!st.warned_peak_window) {
        GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                            ("peak-window %d is larger than the %dx%d frame: no peak marker",
                             window, width, height),
                            ("peak window does not fit"));
        st.warned_peak_window = true;
      }
    }
  });
  return ok ? GST_FLOW_OK : GST_FLOW_ERROR;
}

/* A stream whose tags say it holds expanded uncertainties (ratiotemp output=uncertainty, or a
 * recording of it played back) would be coloured and labelled as temperatures near -273 degC. */
static gboolean gst_thermal_colormap_sink_event(GstBaseTransform* trans, GstEvent* event) {
  if (pg::refuses_other_quantity(GST_ELEMENT(trans), event)) {
    gst_event_unref(event);
    return FALSE;
  }
  return GST_BASE_TRANSFORM_CLASS(gst_thermal_colormap_parent_class)->sink_event(trans, event);
}

static void gst_thermal_colormap_set_property(GObject* object, guint prop_id, const GValue* value,
                                              GParamSpec* pspec) {
  GstThermalColormap* self = GST_THERMAL_COLORMAP(object);
  pg::ObjectLock lock(self);
  Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_PALETTE:
      s.palette = static_cast<GstThermalColormapPalette>(g_value_get_enum(value));
      break;
    case PROP_RANGE_MODE:
      s.range_mode = static_cast<GstThermalColormapRangeMode>(g_value_get_enum(value));
      break;
    case PROP_MIN_TEMPERATURE:
      s.min_c = g_value_get_double(value);
      break;
    case PROP_MAX_TEMPERATURE:
      s.max_c = g_value_get_double(value);
      break;
    case PROP_AUTO_SMOOTHING:
      s.auto_smoothing = g_value_get_double(value);
      break;
    case PROP_AUTO_TRIM:
      s.auto_trim = g_value_get_double(value);
      break;
    case PROP_SCALE_BAR:
      s.scale_bar = g_value_get_boolean(value);
      break;
    case PROP_INVALID_COLOR:
      s.invalid_color = g_value_get_uint(value);
      break;
    case PROP_ISOTHERM_THRESHOLD:
      s.isotherm_c = g_value_get_double(value);
      break;
    case PROP_ISOTHERM_COLOR:
      s.isotherm_color = g_value_get_uint(value);
      break;
    case PROP_PEAK_MARKER:
      s.peak_marker = g_value_get_boolean(value);
      break;
    case PROP_PEAK_WINDOW: {
      const guint w = g_value_get_uint(value);
      if (w % 2 == 1)
        s.peak_window = w;
      else
        GST_WARNING_OBJECT(self, "peak-window %u is not odd; keeping %u", w, s.peak_window);
      break;
    }
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

static void gst_thermal_colormap_get_property(GObject* object, guint prop_id, GValue* value,
                                              GParamSpec* pspec) {
  GstThermalColormap* self = GST_THERMAL_COLORMAP(object);
  pg::ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_PALETTE:
      g_value_set_enum(value, s.palette);
      break;
    case PROP_RANGE_MODE:
      g_value_set_enum(value, s.range_mode);
      break;
    case PROP_MIN_TEMPERATURE:
      g_value_set_double(value, s.min_c);
      break;
    case PROP_MAX_TEMPERATURE:
      g_value_set_double(value, s.max_c);
      break;
    case PROP_AUTO_SMOOTHING:
      g_value_set_double(value, s.auto_smoothing);
      break;
    case PROP_AUTO_TRIM:
      g_value_set_double(value, s.auto_trim);
      break;
    case PROP_SCALE_BAR:
      g_value_set_boolean(value, s.scale_bar);
      break;
    case PROP_INVALID_COLOR:
      g_value_set_uint(value, s.invalid_color);
      break;
    case PROP_ISOTHERM_THRESHOLD:
      g_value_set_double(value, s.isotherm_c);
      break;
    case PROP_ISOTHERM_COLOR:
      g_value_set_uint(value, s.isotherm_color);
      break;
    case PROP_PEAK_MARKER:
      g_value_set_boolean(value, s.peak_marker);
      break;
    case PROP_PEAK_WINDOW:
      g_value_set_uint(value, s.peak_window);
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

static void gst_thermal_colormap_finalize(GObject* object) {
  GstThermalColormap* self = GST_THERMAL_COLORMAP(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_thermal_colormap_parent_class)->finalize(object);
}

static void gst_thermal_colormap_class_init(GstThermalColormapClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);
  GstVideoFilterClass* filter_class = GST_VIDEO_FILTER_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_thermal_colormap_debug, "thermalcolormap", 0,
                          "pyrocam false-colour display");

  gobject_class->set_property = gst_thermal_colormap_set_property;
  gobject_class->get_property = gst_thermal_colormap_get_property;
  gobject_class->finalize = gst_thermal_colormap_finalize;

  const auto display = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING | GST_PARAM_CONTROLLABLE);
  g_object_class_install_property(
      gobject_class, PROP_PALETTE,
      g_param_spec_enum("palette", "Palette", "Colours from cold to hot",
                        GST_TYPE_THERMAL_COLORMAP_PALETTE, DEFAULT_PALETTE, display));
  g_object_class_install_property(
      gobject_class, PROP_RANGE_MODE,
      g_param_spec_enum(
          "range-mode", "Range mode",
          "fixed: min-temperature..max-temperature; auto: the valid range of the "
          "frames less auto-trim, smoothed by auto-smoothing (min/max-temperature until a frame "
          "has a reading)",
          GST_TYPE_THERMAL_COLORMAP_RANGE_MODE, DEFAULT_RANGE_MODE, display));
  g_object_class_install_property(
      gobject_class, PROP_MIN_TEMPERATURE,
      g_param_spec_double("min-temperature", "Minimum temperature",
                          "Temperature in degC at the cold end of the palette in fixed mode "
                          "(-273.15..10000)",
                          -273.15, 10000.0, DEFAULT_MIN_TEMPERATURE, display));
  g_object_class_install_property(
      gobject_class, PROP_MAX_TEMPERATURE,
      g_param_spec_double("max-temperature", "Maximum temperature",
                          "Temperature in degC at the hot end of the palette in fixed mode "
                          "(-273.15..10000)",
                          -273.15, 10000.0, DEFAULT_MAX_TEMPERATURE, display));
  g_object_class_install_property(
      gobject_class, PROP_AUTO_SMOOTHING,
      g_param_spec_double("auto-smoothing", "Auto range smoothing",
                          "Share of the newest frame in the auto range as it narrows, an "
                          "exponential moving average of each frame's min and max; it widens "
                          "at once to take in a frame's range, so no reading is painted as "
                          "another temperature (0.001..1; 1 = no smoothing, 0.1 settles in "
                          "about 20 frames)",
                          0.001, 1.0, DEFAULT_AUTO_SMOOTHING, display));
  g_object_class_install_property(
      gobject_class, PROP_AUTO_TRIM,
      g_param_spec_double("auto-trim", "Auto range trim",
                          "Percent of each frame's readings left out at each end of its auto "
                          "range, so that a few wild pixels do not stretch it (0..10; 0 = the "
                          "frame's min and max; an object hotter than the rest covering more "
                          "than this share of the readings still sets the top)",
                          0.0, pyrocam::kMaxTrimPercent, DEFAULT_AUTO_TRIM, display));
  g_object_class_install_property(
      gobject_class, PROP_SCALE_BAR,
      g_param_spec_boolean("scale-bar", "Scale bar",
                           "Draw the palette with labelled ticks in degC at the right edge",
                           DEFAULT_SCALE_BAR, display));
  g_object_class_install_property(
      gobject_class, PROP_INVALID_COLOR,
      g_param_spec_uint(
          "invalid-color", "Invalid colour",
          "Colour of pixels without a reading, 0xAARRGGBB (0..0xFFFFFFFF; default fully "
          "transparent, so the camera image shows through in thermaloverlay or compositor)",
          0, G_MAXUINT, DEFAULT_INVALID_COLOR, display));
  g_object_class_install_property(
      gobject_class, PROP_ISOTHERM_THRESHOLD,
      g_param_spec_double("isotherm-threshold", "Isotherm threshold",
                          "Pixels at or above this temperature in degC get isotherm-color "
                          "(-273.15..10000; -273.15 = off)",
                          -273.15, 10000.0, DEFAULT_ISOTHERM_THRESHOLD, display));
  g_object_class_install_property(
      gobject_class, PROP_ISOTHERM_COLOR,
      g_param_spec_uint("isotherm-color", "Isotherm colour",
                        "Colour of pixels at or above isotherm-threshold, 0xAARRGGBB "
                        "(0..0xFFFFFFFF)",
                        0, G_MAXUINT, DEFAULT_ISOTHERM_COLOR, display));
  g_object_class_install_property(
      gobject_class, PROP_PEAK_MARKER,
      g_param_spec_boolean("peak-marker", "Peak marker",
                           "Ring the frame's peak (the largest median of peak-window square "
                           "windows, robust to wild edge pixels) and write \"peak N degC\" at "
                           "the top left",
                           DEFAULT_PEAK_MARKER, display));
  g_object_class_install_property(
      gobject_class, PROP_PEAK_WINDOW,
      g_param_spec_uint("peak-window", "Peak window",
                        "Side in pixels of the square windows of the peak marker (odd, "
                        "1..255; an even value is refused with a warning in the log; larger "
                        "than the frame: a warning on the bus and no marker)",
                        1, pyrocam::kMaxPeakWindow, DEFAULT_PEAK_WINDOW, display));

  gst_element_class_set_static_metadata(
      element_class, "Thermal false colour", "Filter/Effect/Video",
      "Paints temperature images (GRAY16_LE, 0.1 K) with a palette, scale bar and isotherm",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_thermal_colormap_transform_caps);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_thermal_colormap_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_thermal_colormap_stop);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_thermal_colormap_transform);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_thermal_colormap_sink_event);
  trans_class->before_transform = GST_DEBUG_FUNCPTR(pg::sync_controlled_properties);
  filter_class->set_info = GST_DEBUG_FUNCPTR(gst_thermal_colormap_set_info);
  filter_class->transform_frame = GST_DEBUG_FUNCPTR(gst_thermal_colormap_transform_frame);

  gst_type_mark_as_plugin_api(GST_TYPE_THERMAL_COLORMAP_PALETTE, static_cast<GstPluginAPIFlags>(0));
  gst_type_mark_as_plugin_api(GST_TYPE_THERMAL_COLORMAP_RANGE_MODE,
                              static_cast<GstPluginAPIFlags>(0));
}

static void gst_thermal_colormap_init(GstThermalColormap* self) {
  self->settings = new Settings();
  self->state = new State();
  // A frame without an image (GAP: darksub capturing a dark) stays one when coloured.
  gst_base_transform_set_gap_aware(GST_BASE_TRANSFORM(self), TRUE);
}
