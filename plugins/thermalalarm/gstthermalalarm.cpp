/**
 * SECTION:element-thermalalarm
 * @title: thermalalarm
 *
 * Watches the temperatures of a region (video/x-raw GRAY16_LE in 0.1 K, 0 = no reading, from
 * ratiotemp) and posts an element message "pyrocam-alarm" when the region's median or peak
 * (#GstThermalAlarm:statistic) stays above #GstThermalAlarm:threshold-c for
 * #GstThermalAlarm:frames consecutive frames, and again when it has stayed below threshold-c
 * minus #GstThermalAlarm:hysteresis-c as long. Frames pass through unchanged. Frames without a
 * reading in the region (a camera looking elsewhere) neither count nor break a run, so they
 * never clear a raised alarm.
 *
 * A part too bright for the exposure has no reading either, and the statistic of the rest (a
 * saturated melt pool's rim) reads below the object. Frames whose region has pixels without a
 * reading within the demosaicking kernels' reach of the saturated samples named by their
 * PyrocamSaturationMeta (from darksub, carried through demosaic25 and ratiotemp) therefore
 * count as above the threshold by default (#GstThermalAlarm:saturated-raises): the alarm errs
 * towards raising. With the property off, and where saturation left every pixel a reading,
 * they count by their readings. Pixels hotter than the model's range have no reading either:
 * those without a reading in the tiles where the frame's PyrocamAboveRangeMeta (ratiotemp's)
 * puts such pixels count as hotter than any reading in the statistic (the median or the peak),
 * and a frame whose statistic is then one of them counts as above the threshold (above-range in
 * the message; value-c is the range's end, a lower bound). A threshold above the range's end
 * cannot be compared with them: they then count as no reading, and a warning says so.
 *
 * The message's fields:
 * - state (string): raised or cleared; active (boolean): true when raised;
 * - statistic (string): median or peak; value-c (double, degC): the statistic of the frame that
 *   changed the state (absent when the alarm was turned off with threshold-c);
 * - threshold-c, clear-c (double, degC): the levels that raise and clear (absent when the alarm
 *   was turned off); frames (guint);
 * - saturated (boolean): the frame that changed the state counted as above the threshold
 *   because saturation left pixels of the region without a reading;
 * - above-range (boolean): the frame's statistic was that of pixels hotter than the model's
 *   range;
 * - timestamp, running-time (guint64, ns; GST_CLOCK_TIME_NONE when unknown);
 * - region-x, region-y, region-width, region-height (int): the pixels watched (the region
 *   clipped to the frame).
 * A raised alarm is also logged as a warning of the thermalalarm debug category, a cleared one
 * as info.
 *
 * The peak is the largest median of the #GstThermalAlarm:peak-window square windows (as
 * ratiotemp's peak-c), so that single wild pixels at a sharp edge raise nothing. A region that
 * lies outside the frame, or a peak window larger than the region, stops the pipeline with an
 * error (RESOURCE SETTINGS) rather than watch nothing; a region partly outside is clipped, with
 * a warning. A malformed region or an even peak window is refused, with an error at the start
 * (set in a launch line) and a warning while playing. Every property can change while playing;
 * new settings keep the alarm's state.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc scene=melt-pool ! darksub dark-level=50 ! demosaic25 ! \
 *     ratiotemp model=model.json ! thermalalarm threshold-c=2200 statistic=peak \
 *     region=100,80,120,80 ! fakesink
 * ]|
 */
#include "gstthermalalarm.h"

#include <cmath>
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/alarm.h"
#include "pyrocam/runtime/region_stats.h"

GST_DEBUG_CATEGORY_STATIC(gst_thermal_alarm_debug);
#define GST_CAT_DEFAULT gst_thermal_alarm_debug

namespace pg = pyrocam::gst;

namespace {

enum {
  PROP_0,
  PROP_THRESHOLD,
  PROP_HYSTERESIS,
  PROP_FRAMES,
  PROP_STATISTIC,
  PROP_REGION,
  PROP_PEAK_WINDOW,
  PROP_SATURATED_RAISES,
};

constexpr const char* ALARM_MESSAGE = "pyrocam-alarm";
constexpr double THRESHOLD_OFF = -273.15;
constexpr double DEFAULT_THRESHOLD = THRESHOLD_OFF;
constexpr double DEFAULT_HYSTERESIS = 10.0;
constexpr guint DEFAULT_FRAMES = 5;
constexpr guint MAX_FRAMES = 100000;
constexpr GstThermalAlarmStatistic DEFAULT_STATISTIC = GST_THERMAL_ALARM_STATISTIC_MEDIAN;
constexpr guint DEFAULT_PEAK_WINDOW = pyrocam::kDefaultPeakWindow;
constexpr gboolean DEFAULT_SATURATED_RAISES = TRUE;
// Stands in for pixels hotter than the model's range in the statistic: above any temperature a
// code holds (6280.35 degC), so that a statistic beyond that (a median halfway to it, too) is
// theirs.
constexpr float kHotterThanRange = 1e6f;

struct Settings {
  double threshold_c = DEFAULT_THRESHOLD;
  double hysteresis_c = DEFAULT_HYSTERESIS;
  guint frames = DEFAULT_FRAMES;
  GstThermalAlarmStatistic statistic = DEFAULT_STATISTIC;
  std::string region_text;  // empty: the whole frame; always parses
  pg::Region region;
  guint peak_window = DEFAULT_PEAK_WINDOW;  // odd
  gboolean saturated_raises = DEFAULT_SATURATED_RAISES;
  guint serial = 0;  // bumped by every change of the alarm rule
  // Values refused since the last valid one of their property: set before the element is in a
  // pipeline (gst-launch), a refusal's warning reaches no bus, so start() stops on them.
  std::string refused_region, refused_window;
};

struct State {
  pyrocam::AlarmMonitor monitor;
  guint serial = 0;                 // of the settings the monitor has
  std::string warned_clip;          // the region text whose clipping was warned about
  double warned_threshold_c = NAN;  // a threshold warned to lie above the model's range
};

pyrocam::AlarmSettings to_library(const Settings& s) {
  pyrocam::AlarmSettings a;
  a.threshold_c = s.threshold_c > THRESHOLD_OFF ? s.threshold_c : NAN;
  a.hysteresis_c = s.hysteresis_c;
  a.frames = static_cast<int>(s.frames);
  return a;
}

const char* statistic_name(GstThermalAlarmStatistic s) {
  return s == GST_THERMAL_ALARM_STATISTIC_PEAK ? "peak" : "median";
}

}  // namespace

struct _GstThermalAlarm {
  GstVideoFilter parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstThermalAlarm, gst_thermal_alarm, GST_TYPE_VIDEO_FILTER);
GST_ELEMENT_REGISTER_DEFINE(thermalalarm, "thermalalarm", GST_RANK_NONE, GST_TYPE_THERMAL_ALARM);

GType gst_thermal_alarm_statistic_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_THERMAL_ALARM_STATISTIC_MEDIAN, "Median of the region's readings", "median"},
      {GST_THERMAL_ALARM_STATISTIC_PEAK, "Largest median of peak-window square windows", "peak"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstThermalAlarmStatistic", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_TEMPERATURE_CAPS));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_TEMPERATURE_CAPS));

static gboolean gst_thermal_alarm_start(GstBaseTransform* trans) {
  pg::forget_posted_errors(GST_ELEMENT(trans));
  GstThermalAlarm* self = GST_THERMAL_ALARM(trans);
  const Settings settings = pg::locked_copy(self, *self->settings);
  *self->state = State();
  self->state->serial = settings.serial;
  for (const std::string* refused : {&settings.refused_region, &settings.refused_window})
    if (!refused->empty()) {
      PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings, *refused, "property value refused");
      return FALSE;
    }
  return PYROCAM_GUARDED(self, pg::ErrorKind::kSettings, "Bad alarm settings",
                         [&] { self->state->monitor.configure(to_library(settings)); });
}

static gboolean gst_thermal_alarm_stop(GstBaseTransform* trans) {
  *GST_THERMAL_ALARM(trans)->state = State();
  return TRUE;
}

static void post_change(GstThermalAlarm* self, const Settings& settings, double value_c,
                        bool saturated, bool above_range, const cv::Rect& region,
                        GstClockTime pts) {
  GstBaseTransform* trans = GST_BASE_TRANSFORM(self);
  GstClockTime running_time = GST_CLOCK_TIME_NONE;
  if (GST_CLOCK_TIME_IS_VALID(pts) && trans->segment.format == GST_FORMAT_TIME)
    running_time = gst_segment_to_running_time(&trans->segment, GST_FORMAT_TIME, pts);
  const pyrocam::AlarmSettings& rule = self->state->monitor.settings();
  const bool active = self->state->monitor.active();
  GstStructure* s = gst_structure_new(
      ALARM_MESSAGE, "state", G_TYPE_STRING, active ? "raised" : "cleared", "active",
      G_TYPE_BOOLEAN, active, "statistic", G_TYPE_STRING, statistic_name(settings.statistic),
      "frames", G_TYPE_UINT, settings.frames, "timestamp", G_TYPE_UINT64, static_cast<guint64>(pts),
      "running-time", G_TYPE_UINT64, static_cast<guint64>(running_time), "region-x", G_TYPE_INT,
      region.x, "region-y", G_TYPE_INT, region.y, "region-width", G_TYPE_INT, region.width,
      "region-height", G_TYPE_INT, region.height, "saturated", G_TYPE_BOOLEAN, saturated,
      "above-range", G_TYPE_BOOLEAN, above_range, nullptr);
  if (!std::isnan(value_c)) gst_structure_set(s, "value-c", G_TYPE_DOUBLE, value_c, nullptr);
  // Off (NaN) has no levels; a NaN field would print as "nan", which no parser reads back.
  if (!std::isnan(rule.threshold_c))
    gst_structure_set(s, "threshold-c", G_TYPE_DOUBLE, rule.threshold_c, "clear-c", G_TYPE_DOUBLE,
                      rule.clear_below_c(), nullptr);
  if (active)
    GST_WARNING_OBJECT(self, "alarm raised: %s %.1f degC%s above %.1f degC for %u frames",
                       statistic_name(settings.statistic), value_c,
                       saturated     ? " (saturated: counted as)"
                       : above_range ? " (above the model's range: counted as)"
                                     : "",
                       rule.threshold_c, settings.frames);
  else
    GST_INFO_OBJECT(self, "alarm cleared: %s %.1f degC", statistic_name(settings.statistic),
                    value_c);
  gst_element_post_message(GST_ELEMENT(self), gst_message_new_element(GST_OBJECT(self), s));
}

/* The region watched, clipped to the frame; empty (after an error on the bus) when nothing of
 * it is in the frame or the peak window does not fit. */
static cv::Rect watched_region(GstThermalAlarm* self, const Settings& settings, int width,
                               int height) {
  const cv::Rect frame(0, 0, width, height);
  if (settings.region_text.empty()) return frame;
  const pg::Region& r = settings.region;
  const cv::Rect wanted(r.x, r.y, r.width, r.height);
  const cv::Rect clipped = wanted & frame;
  if (clipped.empty()) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "region " + settings.region_text + " lies outside the " +
                           std::to_string(width) + "x" + std::to_string(height) + " frame",
                       "nothing to watch");
    return {};
  }
  if (clipped != wanted && self->state->warned_clip != settings.region_text) {
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("region %s reaches beyond the %dx%d frame: watching %d,%d,%d,%d",
                         settings.region_text.c_str(), width, height, clipped.x, clipped.y,
                         clipped.width, clipped.height),
                        ("region clipped"));
    self->state->warned_clip = settings.region_text;
  }
  return clipped;
}

/* A buffer too short for the frame is a STREAM FORMAT error (GstVideoFilter warned "please file a
 * bug", dropped it and the alarm never looked at the stream). */
static GstFlowReturn gst_thermal_alarm_transform_ip(GstBaseTransform* trans, GstBuffer* buffer) {
  GstVideoFilter* filter = GST_VIDEO_FILTER(trans);
  if (filter->negotiated && !pg::temperature_frame_fits(trans, filter->in_info, buffer))
    return GST_FLOW_ERROR;
  return GST_BASE_TRANSFORM_CLASS(gst_thermal_alarm_parent_class)->transform_ip(trans, buffer);
}

static GstFlowReturn gst_thermal_alarm_transform_frame_ip(GstVideoFilter* filter,
                                                          GstVideoFrame* frame) {
  GstThermalAlarm* self = GST_THERMAL_ALARM(filter);
  const Settings settings = pg::locked_copy(self, *self->settings);
  State& st = *self->state;
  const int width = GST_VIDEO_FRAME_WIDTH(frame), height = GST_VIDEO_FRAME_HEIGHT(frame);
  const GstClockTime pts = GST_BUFFER_PTS(frame->buffer);
  // Only on a change: configuring restarts the run of frames.
  if (settings.serial != st.serial) {
    if (!PYROCAM_GUARDED(self, pg::ErrorKind::kSettings, "Bad alarm settings",
                         [&] { st.monitor.configure(to_library(settings)); }))
      return GST_FLOW_ERROR;
    st.serial = settings.serial;
  }
  // A frame without an image (GAP: darksub capturing a dark) tells nothing either way.
  if (GST_BUFFER_FLAG_IS_SET(frame->buffer, GST_BUFFER_FLAG_GAP)) return GST_FLOW_OK;
  const bool off = !(settings.threshold_c > THRESHOLD_OFF);
  if (off) {
    if (st.monitor.update(NAN) != pyrocam::AlarmChange::kNone)
      post_change(self, settings, NAN, false, false, cv::Rect(0, 0, width, height), pts);
    return GST_FLOW_OK;
  }
  const cv::Rect region = watched_region(self, settings, width, height);
  if (region.empty()) return GST_FLOW_ERROR;
  const int window = static_cast<int>(settings.peak_window);
  if (settings.statistic == GST_THERMAL_ALARM_STATISTIC_PEAK &&
      (window > region.width || window > region.height)) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "peak-window " + std::to_string(window) + " is larger than the " +
                           std::to_string(region.width) + "x" + std::to_string(region.height) +
                           " region watched",
                       "no peak can be computed");
    return GST_FLOW_ERROR;
  }
  const cv::Mat codes(height, width, CV_16U, GST_VIDEO_FRAME_PLANE_DATA(frame, 0),
                      static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(frame, 0)));
  double value_c = NAN;
  // Saturated samples that took readings in the region: the part hidden is hotter than what
  // reads there.
  const bool saturated = settings.saturated_raises &&
                         pg::saturation_hides_readings(
                             pyrocam_buffer_get_saturation_meta(frame->buffer), codes, region);
  pyrocam::AlarmChange change = pyrocam::AlarmChange::kNone;
  bool above_range = false;
  if (!PYROCAM_GUARDED(self, pg::ErrorKind::kNumeric, "Could not compute the alarm statistic", [&] {
        cv::Mat t = pyrocam::decode_decikelvin(codes(region));
        // Pixels hotter than the range: above any reading (a temperature no code holds), and so
        // above a threshold within the range; one above it they cannot be compared with.
        const PyrocamAboveRangeMeta* meta = pyrocam_buffer_get_above_range_meta(frame->buffer);
        const bool comparable = !meta || settings.threshold_c <= meta->max_temperature_c;
        if (!comparable && meta->pixels > 0 && settings.threshold_c != st.warned_threshold_c) {
          GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                              ("threshold-c %.1f lies above the model's range (up to %.0f degC): "
                               "pixels hotter than the range cannot be compared with it and "
                               "count as no reading",
                               settings.threshold_c, meta->max_temperature_c),
                              ("ratiotemp's PyrocamAboveRangeMeta names such pixels"));
          st.warned_threshold_c = settings.threshold_c;
        }
        for (cv::Rect r :
             pg::above_range_rects(comparable ? meta : nullptr, cv::Size(width, height))) {
          r &= region;
          if (r.empty()) continue;
          cv::Mat part = t(r - region.tl());
          part.setTo(kHotterThanRange, part != part);
        }
        value_c = settings.statistic == GST_THERMAL_ALARM_STATISTIC_PEAK
                      ? pyrocam::region_peak(t, window).c
                      : pyrocam::region_stats(t).median_c;
        above_range = value_c > pyrocam::code_to_celsius(pyrocam::kMaxCode);
        if (above_range) value_c = meta->max_temperature_c;
        change = st.monitor.update(saturated || above_range ? INFINITY : value_c);
      }))
    return GST_FLOW_ERROR;
  if (change != pyrocam::AlarmChange::kNone)
    post_change(self, settings, value_c, saturated, above_range, region, pts);
  return GST_FLOW_OK;
}

static void gst_thermal_alarm_set_property(GObject* object, guint prop_id, const GValue* value,
                                           GParamSpec* pspec) {
  GstThermalAlarm* self = GST_THERMAL_ALARM(object);
  std::string refused;  // a warning posted after the lock is released
  {
    pg::ObjectLock lock(self);
    Settings& s = *self->settings;
    switch (prop_id) {
      case PROP_THRESHOLD:
        s.threshold_c = g_value_get_double(value);
        break;
      case PROP_HYSTERESIS:
        s.hysteresis_c = g_value_get_double(value);
        break;
      case PROP_FRAMES:
        s.frames = g_value_get_uint(value);
        break;
      case PROP_STATISTIC:
        s.statistic = static_cast<GstThermalAlarmStatistic>(g_value_get_enum(value));
        break;
      case PROP_REGION: {
        const char* v = g_value_get_string(value);
        const std::string text = v ? v : "";
        pg::Region r;
        if (text.empty() || pg::parse_region(text, &r)) {
          s.region_text = text;
          s.region = r;
          s.refused_region.clear();
        } else {
          s.refused_region = "region '" + text +
                             "' is not x,y,width,height (non-negative integers, width and "
                             "height at least 1)";
          refused = s.refused_region + "; keeping '" + s.region_text + "'";
        }
        break;
      }
      case PROP_PEAK_WINDOW: {
        const guint w = g_value_get_uint(value);
        if (w % 2 == 1) {
          s.peak_window = w;
          s.refused_window.clear();
        } else {
          s.refused_window = "peak-window " + std::to_string(w) + " is not odd";
          refused = s.refused_window + "; keeping " + std::to_string(s.peak_window);
        }
        break;
      }
      case PROP_SATURATED_RAISES:
        s.saturated_raises = g_value_get_boolean(value);
        break;
      default:
        G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
        return;
    }
    ++s.serial;
  }
  if (!refused.empty())
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS, ("%s", refused.c_str()),
                        ("property value refused"));
}

static void gst_thermal_alarm_get_property(GObject* object, guint prop_id, GValue* value,
                                           GParamSpec* pspec) {
  GstThermalAlarm* self = GST_THERMAL_ALARM(object);
  pg::ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_THRESHOLD:
      g_value_set_double(value, s.threshold_c);
      break;
    case PROP_HYSTERESIS:
      g_value_set_double(value, s.hysteresis_c);
      break;
    case PROP_FRAMES:
      g_value_set_uint(value, s.frames);
      break;
    case PROP_STATISTIC:
      g_value_set_enum(value, s.statistic);
      break;
    case PROP_REGION:
      g_value_set_string(value, s.region_text.empty() ? nullptr : s.region_text.c_str());
      break;
    case PROP_PEAK_WINDOW:
      g_value_set_uint(value, s.peak_window);
      break;
    case PROP_SATURATED_RAISES:
      g_value_set_boolean(value, s.saturated_raises);
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

/* A stream of expanded uncertainties (ratiotemp output=uncertainty) would be compared with the
 * thresholds as temperatures near -273 degC: an alarm that never rises, or always. */
static gboolean gst_thermal_alarm_sink_event(GstBaseTransform* trans, GstEvent* event) {
  if (pg::refuses_other_quantity(GST_ELEMENT(trans), event)) {
    gst_event_unref(event);
    return FALSE;
  }
  return GST_BASE_TRANSFORM_CLASS(gst_thermal_alarm_parent_class)->sink_event(trans, event);
}

static void gst_thermal_alarm_finalize(GObject* object) {
  GstThermalAlarm* self = GST_THERMAL_ALARM(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_thermal_alarm_parent_class)->finalize(object);
}

static void gst_thermal_alarm_class_init(GstThermalAlarmClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);
  GstVideoFilterClass* filter_class = GST_VIDEO_FILTER_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_thermal_alarm_debug, "thermalalarm", 0, "pyrocam temperature alarm");

  gobject_class->set_property = gst_thermal_alarm_set_property;
  gobject_class->get_property = gst_thermal_alarm_get_property;
  gobject_class->finalize = gst_thermal_alarm_finalize;

  const auto playing = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING);
  g_object_class_install_property(
      gobject_class, PROP_THRESHOLD,
      g_param_spec_double("threshold-c", "Alarm threshold",
                          "The alarm is raised when the statistic stays above this temperature "
                          "in degC for frames frames (-273.15..10000; -273.15 = off, which "
                          "clears a raised alarm)",
                          THRESHOLD_OFF, 10000.0, DEFAULT_THRESHOLD, playing));
  g_object_class_install_property(
      gobject_class, PROP_HYSTERESIS,
      g_param_spec_double("hysteresis-c", "Hysteresis",
                          "A raised alarm is cleared when the statistic stays below "
                          "threshold-c minus this many degC for frames frames (0..1000)",
                          0.0, 1000.0, DEFAULT_HYSTERESIS, playing));
  g_object_class_install_property(
      gobject_class, PROP_FRAMES,
      g_param_spec_uint("frames", "Frames",
                        "Consecutive frames (with a reading) beyond the level that raise or "
                        "clear the alarm (1..100000)",
                        1, MAX_FRAMES, DEFAULT_FRAMES, playing));
  g_object_class_install_property(
      gobject_class, PROP_STATISTIC,
      g_param_spec_enum("statistic", "Statistic",
                        "What of the region is compared: median (of its readings) or peak (the "
                        "largest median of peak-window square windows)",
                        GST_TYPE_THERMAL_ALARM_STATISTIC, DEFAULT_STATISTIC, playing));
  g_object_class_install_property(
      gobject_class, PROP_REGION,
      g_param_spec_string("region", "Region",
                          "Pixels watched, \"x,y,width,height\" (empty = the whole frame; a "
                          "malformed value is refused with a warning and the last one stays)",
                          nullptr, playing));
  g_object_class_install_property(
      gobject_class, PROP_PEAK_WINDOW,
      g_param_spec_uint("peak-window", "Peak window",
                        "Side in pixels of the square windows whose largest median is the peak "
                        "(odd, 1..255; an even value is refused with a warning)",
                        1, pyrocam::kMaxPeakWindow, DEFAULT_PEAK_WINDOW, playing));
  g_object_class_install_property(
      gobject_class, PROP_SATURATED_RAISES,
      g_param_spec_boolean("saturated-raises", "Saturated raises",
                           "Count a frame whose region has pixels left without a reading by "
                           "saturated samples (too bright to read: hotter than its readings) as "
                           "above the threshold; false: by its readings, which then miss the "
                           "hottest part",
                           DEFAULT_SATURATED_RAISES, playing));

  gst_element_class_set_static_metadata(
      element_class, "Thermal alarm", "Filter/Analyzer/Video",
      "Posts pyrocam-alarm messages when a region's temperature stays above a threshold",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_thermal_alarm_sink_event);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_thermal_alarm_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_thermal_alarm_stop);
  trans_class->passthrough_on_same_caps = TRUE;
  trans_class->transform_ip_on_passthrough = TRUE;
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_thermal_alarm_transform_ip);
  filter_class->transform_frame_ip = GST_DEBUG_FUNCPTR(gst_thermal_alarm_transform_frame_ip);

  gst_type_mark_as_plugin_api(GST_TYPE_THERMAL_ALARM_STATISTIC, static_cast<GstPluginAPIFlags>(0));
}

static void gst_thermal_alarm_init(GstThermalAlarm* self) {
  self->settings = new Settings();
  self->state = new State();
}
