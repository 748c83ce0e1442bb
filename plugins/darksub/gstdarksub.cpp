/* Over 600 lines: dark capture, the layout and saturation fields of the caps and the GObject
 * boilerplate; the caps-field copying is to move to plugins/common with the architecture issue. */
/**
 * SECTION:element-darksub
 * @title: darksub
 *
 * Subtracts a dark frame from raw mosaic frames and marks saturated pixels, giving one float32
 * per sensor pixel in DN (video/x-pyrocam-mosaic, see pyrocam-caps.h). A pixel whose raw value
 * reached #GstDarkSub:saturation-level (before subtraction) becomes +INFINITY, so that it is
 * never mistaken for a reading downstream.
 *
 * The dark frame comes from, in this order of precedence:
 * 1. a capture from the stream: the #GstDarkSub::capture-dark action signal averages the next
 *    #GstDarkSub:capture-frames frames (lens cap on). While capturing, the element outputs
 *    frames of NaN (no reading): the lens is covered, nothing downstream should be measured.
 *    The captured dark lasts until the element stops (READY) or another capture replaces it.
 *    Emitting the signal before PLAYING starts the stream with a capture. A flush restarts a
 *    capture in progress.
 * 2. an image file, #GstDarkSub:location (PGM, PNG or TIFF of the frame's size and sample
 *    depth: 8 bit for GRAY8 and video/x-bayer, 16 bit for GRAY16_LE; another size or depth is
 *    a STREAM FORMAT error);
 * 3. a constant, #GstDarkSub:dark-level (DN).
 * With none of them the element refuses to start: a thermal reading without a dark frame is
 * wrong by the dark offset, so subtracting 0 must be asked for (dark-level=0).
 *
 * Input: video/x-bayer (8-bit, pattern from the caps) or video/x-raw GRAY8/GRAY16_LE, whose
 * layout is the caps' pattern field (pyrocamsrc sets it) or else #GstDarkSub:pattern: gray
 * input that says neither is refused, as is a property that disagrees with the caps (CORE
 * NEGOTIATION): a 5x5 mosaic read as Bayer gives temperatures that look right and are wrong.
 * The significant bits are the caps' bit-depth field, #GstDarkSub:bit-depth or the sample size.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc ! darksub location=dark.pgm ! demosaic25 ! fakesink
 * ]|
 * Captures a dark at start from a live camera instead (lens cap on for the first 20 frames):
 * |[
 * gst-launch-1.0 aravissrc ! video/x-bayer,format=rggb ! darksub capture-frames=20 ! ...
 * ]| with capture-dark emitted by the application.
 */
#include "gstdarksub.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/runtime/darksub.h"

GST_DEBUG_CATEGORY_STATIC(gst_dark_sub_debug);
#define GST_CAT_DEFAULT gst_dark_sub_debug

namespace pg = pyrocam::gst;

namespace {

enum {
  PROP_0,
  PROP_LOCATION,
  PROP_DARK_LEVEL,
  PROP_SATURATION_LEVEL,
  PROP_CAPTURE_FRAMES,
  PROP_PATTERN,
  PROP_BIT_DEPTH,
};

enum { SIGNAL_CAPTURE_DARK, LAST_SIGNAL };
guint gst_dark_sub_signals[LAST_SIGNAL] = {0};

constexpr double DEFAULT_DARK_LEVEL = -1.0;
constexpr double DEFAULT_SATURATION_LEVEL = -1.0;
constexpr int DEFAULT_CAPTURE_FRAMES = 10;
constexpr GstDarkSubPattern DEFAULT_PATTERN = GST_DARK_SUB_PATTERN_AUTO;
constexpr int DEFAULT_BIT_DEPTH = 0;  // from the caps

const char* pattern_name(GstDarkSubPattern p) {
  switch (p) {
    case GST_DARK_SUB_PATTERN_RGGB:
      return "rggb";
    case GST_DARK_SUB_PATTERN_BGGR:
      return "bggr";
    case GST_DARK_SUB_PATTERN_GRBG:
      return "grbg";
    case GST_DARK_SUB_PATTERN_GBRG:
      return "gbrg";
    case GST_DARK_SUB_PATTERN_5X5:
      return PYROCAM_SNAPSHOT_PATTERN_NAME;
    case GST_DARK_SUB_PATTERN_AUTO:
      return nullptr;
  }
  return nullptr;
}

/* Property values; read and written under GST_OBJECT_LOCK, copied once per buffer. */
struct Settings {
  std::string location;
  double dark_level = DEFAULT_DARK_LEVEL;
  double saturation_level = DEFAULT_SATURATION_LEVEL;
  int capture_frames = DEFAULT_CAPTURE_FRAMES;
  GstDarkSubPattern pattern = DEFAULT_PATTERN;
  int bit_depth = DEFAULT_BIT_DEPTH;
  guint capture_requests = 0;  // incremented by capture-dark
};

/* Streaming state: built in start()/set_caps(), dropped in stop(). */
struct State {
  pg::RawFormat format;
  bool have_format = false;
  int bit_depth = 8;
  std::string pattern;
  cv::Mat file_dark;  // CV_32F from `location`, decoded once the stream's size is known
  std::string file_dark_path;
  cv::Size file_dark_size;    // from the file's header, read in start()
  int file_dark_bits = 0;     // sample size of the file: 8 or 16
  int saturation_level = -1;  // raw DN from the caps' saturation-level field; -1: none
  cv::Mat captured_dark;
  pyrocam::DarkAccumulator accumulator;
  bool capturing = false;
  int capture_target = 0;
  guint capture_requests_seen = 0;
};

}  // namespace

struct _GstDarkSub {
  GstBaseTransform parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstDarkSub, gst_dark_sub, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(darksub, "darksub", GST_RANK_NONE, GST_TYPE_DARK_SUB);

GType gst_dark_sub_pattern_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_DARK_SUB_PATTERN_RGGB, "Bayer, R G / G B", "rggb"},
      {GST_DARK_SUB_PATTERN_BGGR, "Bayer, B G / G R", "bggr"},
      {GST_DARK_SUB_PATTERN_GRBG, "Bayer, G R / B G", "grbg"},
      {GST_DARK_SUB_PATTERN_GBRG, "Bayer, G B / R G", "gbrg"},
      {GST_DARK_SUB_PATTERN_5X5, "5x5 snapshot mosaic", "5x5"},
      {GST_DARK_SUB_PATTERN_AUTO, "From the caps (video/x-bayer format, gray video's pattern)",
       "auto"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstDarkSubPattern", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RAW_CAPS));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_MOSAIC_CAPS));

static Settings copy_settings(GstDarkSub* self) { return pg::locked_copy(self, *self->settings); }

static GstCaps* gst_dark_sub_transform_caps(GstBaseTransform* trans, GstPadDirection direction,
                                            GstCaps* caps, GstCaps* filter) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  const Settings settings = copy_settings(self);
  /* Bit depth of 8-bit input: the property when it fits (set_caps refuses one that does not). */
  const int shallow = settings.bit_depth > 0 && settings.bit_depth <= 8 ? settings.bit_depth : 8;
  GstCaps* result = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    const GstStructure* s = gst_caps_get_structure(caps, i);
    if (direction == GST_PAD_SINK) {
      GstStructure* out =
          gst_structure_new(PYROCAM_MOSAIC_MEDIA_TYPE, "format", G_TYPE_STRING, "F32LE", nullptr);
      pg::copy_dimensions(s, out);
      if (gst_structure_has_name(s, "video/x-bayer")) {
        const GValue* format = gst_structure_get_value(s, "format");
        if (format)
          gst_structure_set_value(out, "pattern", format);
        else
          gst_structure_set(out, "pattern", G_TYPE_STRING, "rggb", nullptr);
        gst_structure_set(out, "bit-depth", G_TYPE_INT, shallow, nullptr);
      } else {
        /* The caps' pattern wins (set_caps refuses a property that disagrees); without one the
         * property's, and with neither any pattern: set_caps refuses it. */
        const GValue* caps_pattern = gst_structure_get_value(s, PYROCAM_FIELD_PATTERN);
        const char* property_pattern = pattern_name(settings.pattern);
        pg::copy_fields(s, out, {PYROCAM_FIELD_BAND_MAP});
        if (caps_pattern) {
          gst_structure_set_value(out, "pattern", caps_pattern);
        } else if (property_pattern) {
          gst_structure_set(out, "pattern", G_TYPE_STRING, property_pattern, nullptr);
        } else {
          pg::set_list_field(out, "pattern", PYROCAM_PATTERNS);
        }
        const char* format = gst_structure_get_string(s, "format");
        if (format && g_str_equal(format, "GRAY8")) {
          gst_structure_set(out, "bit-depth", G_TYPE_INT, shallow, nullptr);
        } else if (format && g_str_equal(format, "GRAY16_LE")) {
          const int caps_bits = pg::structure_int(s, PYROCAM_FIELD_BIT_DEPTH, 0);
          gst_structure_set(out, "bit-depth", G_TYPE_INT,
                            caps_bits > 0            ? caps_bits
                            : settings.bit_depth > 0 ? settings.bit_depth
                                                     : 16,
                            nullptr);
        } else {
          GValue list = G_VALUE_INIT, v = G_VALUE_INIT;
          gst_value_list_init(&list, 2);
          g_value_init(&v, G_TYPE_INT);
          g_value_set_int(&v, shallow);
          gst_value_list_append_value(&list, &v);
          const int deep = settings.bit_depth > 0 ? settings.bit_depth : 16;
          if (deep != shallow) {
            g_value_set_int(&v, deep);
            gst_value_list_append_value(&list, &v);
          }
          gst_structure_take_value(out, "bit-depth", &list);
          g_value_unset(&v);
        }
      }
      /* The raw level at and above which pixels are marked +INF, when it is known here. */
      int bits = 0;
      const int caps_level = pg::structure_int(s, PYROCAM_FIELD_SATURATION_LEVEL, -1);
      if (settings.saturation_level >= 0)
        gst_structure_set(out, PYROCAM_FIELD_SATURATION_LEVEL, G_TYPE_INT,
                          static_cast<int>(std::ceil(settings.saturation_level)), nullptr);
      else if (caps_level >= 0)
        gst_structure_set(out, PYROCAM_FIELD_SATURATION_LEVEL, G_TYPE_INT, caps_level, nullptr);
      else if (gst_structure_get_int(out, "bit-depth", &bits) && bits >= 1 && bits <= 16)
        gst_structure_set(out, PYROCAM_FIELD_SATURATION_LEVEL, G_TYPE_INT,
                          static_cast<int>(std::ceil(pyrocam::default_saturation_level(bits))),
                          nullptr);
      result = gst_caps_merge_structure(result, out);
    } else {
      /* Mosaic -> raw: Bayer caps of the pattern, and gray video. */
      const GValue* pattern = gst_structure_get_value(s, "pattern");
      GstCaps* bayer = gst_caps_from_string(PYROCAM_RAW_BAYER_CAPS);
      GstStructure* b = gst_caps_get_structure(bayer, 0);
      if (pattern) {
        GValue all = G_VALUE_INIT, common = G_VALUE_INIT;
        g_value_init(&all, GST_TYPE_LIST);
        gst_value_deserialize(&all, PYROCAM_BAYER_FORMATS);
        if (gst_value_intersect(&common, pattern, &all)) {
          gst_structure_take_value(b, "format", &common);
        } else {
          gst_caps_remove_structure(bayer, 0);
          b = nullptr;
        }
        g_value_unset(&all);
      }
      if (b) pg::copy_dimensions(s, b);
      GstCaps* gray = gst_caps_from_string(PYROCAM_RAW_GRAY_CAPS);
      pg::copy_dimensions(s, gst_caps_get_structure(gray, 0));
      result = gst_caps_merge(result, bayer);
      result = gst_caps_merge(result, gray);
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

static gboolean gst_dark_sub_transform_size(GstBaseTransform* trans, GstPadDirection direction,
                                            GstCaps* caps, gsize /*size*/, GstCaps* othercaps,
                                            gsize* othersize) {
  if (direction == GST_PAD_SINK) {
    const GstStructure* s = gst_caps_get_structure(othercaps, 0);
    const int w = pg::structure_int(s, "width", 0), h = pg::structure_int(s, "height", 0);
    *othersize = static_cast<gsize>(w) * static_cast<gsize>(h) * sizeof(float);
    return w > 0 && h > 0;
  }
  pg::RawFormat f;
  if (!pg::parse_raw_caps(othercaps, &f)) {
    GST_WARNING_OBJECT(trans, "cannot size %" GST_PTR_FORMAT " (from %" GST_PTR_FORMAT ")",
                       othercaps, caps);
    return FALSE;
  }
  *othersize = pg::raw_frame_size(f);
  return TRUE;
}

/* The dark frame for the next output: a captured or file dark, or nullptr for the constant
 * level (or none: see the caller). */
static const cv::Mat* frame_dark(const State& st) {
  if (!st.captured_dark.empty()) return &st.captured_dark;
  if (!st.file_dark.empty()) return &st.file_dark;
  return nullptr;
}

/* The name of a raw format in messages. */
static std::string raw_format_name(const pg::RawFormat& f) {
  if (f.bayer_caps) return "8-bit video/x-bayer";
  return f.bytes_per_sample == 1 ? "GRAY8" : "GRAY16_LE";
}

static gboolean check_dark(GstDarkSub* self) {
  State& st = *self->state;
  if (!st.captured_dark.empty() &&
      (st.captured_dark.cols != st.format.width || st.captured_dark.rows != st.format.height)) {
    GST_WARNING_OBJECT(self, "dropping the captured %dx%d dark: the stream is now %dx%d",
                       st.captured_dark.cols, st.captured_dark.rows, st.format.width,
                       st.format.height);
    st.captured_dark.release();
  }
  if (!st.file_dark_path.empty() &&
      st.file_dark_size != cv::Size(st.format.width, st.format.height)) {
    PYROCAM_POST_ERROR(
        self, pg::ErrorKind::kFormat,
        "Dark frame " + st.file_dark_path + " is " + std::to_string(st.file_dark_size.width) + "x" +
            std::to_string(st.file_dark_size.height) + " but the camera frames are " +
            std::to_string(st.format.width) + "x" + std::to_string(st.format.height),
        "size mismatch between location and the negotiated caps");
    return FALSE;
  }
  // Decoded only now, at the stream's size: a file that cannot be this camera's frame (a
  // 30000x30000 image) is refused from its header, before any pixel is decoded.
  if (!st.file_dark_path.empty() && st.file_dark.empty()) {
    const bool ok =
        PYROCAM_GUARDED(self, pg::ErrorKind::kRead, "Could not read the dark frame", [&] {
          const cv::Mat image =
              pyrocam::read_raw_image(st.file_dark_path, st.file_dark_size, "the camera frame");
          st.file_dark_bits = image.depth() == CV_8U ? 8 : 16;
          st.file_dark = pyrocam::dark_from_image(image);
        });
    if (!ok) return FALSE;
    GST_INFO_OBJECT(self, "dark frame %s, %dx%d", st.file_dark_path.c_str(), st.file_dark.cols,
                    st.file_dark.rows);
  }
  if (!st.file_dark.empty() && st.file_dark_bits != 8 * st.format.bytes_per_sample) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kFormat,
                       "Dark frame " + st.file_dark_path + " has " +
                           std::to_string(st.file_dark_bits) +
                           "-bit samples but the camera frames are " + raw_format_name(st.format) +
                           " (" + std::to_string(8 * st.format.bytes_per_sample) +
                           "-bit samples): take the dark from this stream",
                       "sample depth mismatch between location and the negotiated caps");
    return FALSE;
  }
  return TRUE;
}

static gboolean gst_dark_sub_set_caps(GstBaseTransform* trans, GstCaps* incaps, GstCaps* outcaps) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  const Settings settings = copy_settings(self);
  State& st = *self->state;
  pg::RawFormat f;
  if (!pg::parse_raw_caps(incaps, &f)) {
    GST_WARNING_OBJECT(self, "cannot parse %" GST_PTR_FORMAT, incaps);
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "Unsupported input format",
                       "parse_raw_caps failed on the sink caps");
    return FALSE;
  }
  const int sample_bits = 8 * f.bytes_per_sample;
  if (settings.bit_depth > sample_bits) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "bit-depth " + std::to_string(settings.bit_depth) + " does not fit the " +
                           raw_format_name(f) + " input (" + std::to_string(sample_bits) +
                           "-bit samples)",
                       "bit-depth property above the sample size of the sink caps");
    return FALSE;
  }
  /* The layout: from the caps, or told by the property; both must agree. */
  const GstStructure* in = gst_caps_get_structure(incaps, 0);
  const char* caps_pattern =
      f.bayer_caps ? f.pattern.c_str() : gst_structure_get_string(in, PYROCAM_FIELD_PATTERN);
  const char* property_pattern = pattern_name(settings.pattern);
  if (!caps_pattern && !property_pattern) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       raw_format_name(f) +
                           " input does not say its mosaic layout: set darksub pattern (rggb, "
                           "bggr, grbg, gbrg or 5x5) or a pattern field in the caps",
                       "gray sink caps without a pattern field and pattern=auto");
    return FALSE;
  }
  if (caps_pattern && property_pattern && !g_str_equal(caps_pattern, property_pattern)) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       "darksub pattern=" + std::string(property_pattern) +
                           " but the stream is a " + caps_pattern + " mosaic",
                       "pattern property differs from the sink caps");
    return FALSE;
  }
  const int caps_bits = pg::structure_int(in, PYROCAM_FIELD_BIT_DEPTH, 0);
  if (caps_bits > 0 && settings.bit_depth > 0 && caps_bits != settings.bit_depth) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       "darksub bit-depth=" + std::to_string(settings.bit_depth) +
                           " but the stream says its samples have " + std::to_string(caps_bits) +
                           " significant bits",
                       "bit-depth property differs from the sink caps");
    return FALSE;
  }
  /* The saturation level: the property, else the caps' (the camera profile's), else the
   * default share of the full scale. */
  st.saturation_level = pg::structure_int(in, PYROCAM_FIELD_SATURATION_LEVEL, -1);
  const GstStructure* out = gst_caps_get_structure(outcaps, 0);
  st.format = f;
  st.have_format = true;
  st.bit_depth = pg::structure_int(out, "bit-depth", sample_bits);
  st.pattern = caps_pattern ? caps_pattern : property_pattern;
  const char* out_pattern = gst_structure_get_string(out, "pattern");
  if (!out_pattern || st.pattern != out_pattern) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       "The stream is a " + st.pattern + " mosaic but downstream asks for " +
                           (out_pattern ? out_pattern : "no pattern"),
                       "pattern of the source caps differs from the input's");
    return FALSE;
  }
  if (st.bit_depth < 1 || st.bit_depth > sample_bits) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       "Output caps with bit-depth " + std::to_string(st.bit_depth) +
                           " do not fit the " + raw_format_name(f) + " input",
                       "bit-depth of the source caps out of range");
    return FALSE;
  }
  bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kNegotiation, "Unsupported mosaic", [&] {
    const pyrocam::MosaicLayout layout = pg::layout_for_pattern(st.pattern);
    if (f.width % layout.period_width || f.height % layout.period_height)
      throw pyrocam::InputError(std::to_string(f.width) + "x" + std::to_string(f.height) +
                                " frames are not whole " + st.pattern + " periods");
  });
  if (!ok) return FALSE;
  if (settings.saturation_level > pyrocam::full_scale_dn(st.bit_depth))
    GST_WARNING_OBJECT(self,
                       "saturation-level %g is above the %d-bit full scale: nothing "
                       "will be marked saturated",
                       settings.saturation_level, st.bit_depth);
  GST_INFO_OBJECT(self, "%dx%d %s, %d bit, %d byte(s) per sample", f.width, f.height,
                  st.pattern.c_str(), st.bit_depth, f.bytes_per_sample);
  return check_dark(self);
}

static gboolean gst_dark_sub_start(GstBaseTransform* trans) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  const Settings settings = copy_settings(self);
  State& st = *self->state;
  st = State();
  st.capture_requests_seen = settings.capture_requests;  // capture-dark before start counts
  if (settings.capture_requests > 0) {
    st.capturing = true;
    st.capture_target = settings.capture_frames;
    st.capture_requests_seen = settings.capture_requests;
  }
  if (!settings.location.empty()) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(settings.location, ec)) {
      PYROCAM_POST_ERROR(self, pg::ErrorKind::kNotFound,
                         "Dark frame file " + settings.location + " not found",
                         "location does not name a regular file");
      return FALSE;
    }
    // The header only: the pixels are decoded in set_caps, once the frame size is known.
    const bool ok =
        PYROCAM_GUARDED(self, pg::ErrorKind::kRead, "Could not read the dark frame",
                        [&] { st.file_dark_size = pyrocam::read_image_size(settings.location); });
    if (!ok) return FALSE;
    st.file_dark_path = settings.location;
  } else if (settings.dark_level < 0 && !st.capturing) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "No dark frame: set location, dark-level or emit capture-dark",
                       "location is empty, dark-level < 0 and no capture was requested");
    return FALSE;
  }
  return TRUE;
}

static gboolean gst_dark_sub_stop(GstBaseTransform* trans) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  *self->state = State();  // releases the dark frames
  pg::ObjectLock lock(self);
  self->settings->capture_requests = 0;
  return TRUE;
}

static gboolean gst_dark_sub_sink_event(GstBaseTransform* trans, GstEvent* event) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  if (GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP && self->state->capturing) {
    GST_INFO_OBJECT(self, "flush: restarting the dark capture");
    self->state->accumulator.reset();
  }
  return GST_BASE_TRANSFORM_CLASS(gst_dark_sub_parent_class)->sink_event(trans, event);
}

static GstFlowReturn gst_dark_sub_transform(GstBaseTransform* trans, GstBuffer* inbuf,
                                            GstBuffer* outbuf) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  State& st = *self->state;
  if (!st.have_format) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "No format negotiated",
                       "transform called before set_caps");
    return GST_FLOW_NOT_NEGOTIATED;
  }
  const Settings settings = copy_settings(self);
  if (settings.capture_requests != st.capture_requests_seen) {
    st.capture_requests_seen = settings.capture_requests;
    st.capturing = true;
    st.capture_target = settings.capture_frames;
    st.accumulator.reset();
    GST_INFO_OBJECT(self, "capturing a dark over %d frames", st.capture_target);
  }
  GstFlowReturn ret = GST_FLOW_OK;
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not subtract the dark", [&] {
    pg::MappedImage raw, out;
    raw.map_raw(inbuf, st.format);
    out.map_float(outbuf, st.format.width, st.format.height, 1, GST_MAP_WRITE);
    if (st.capturing) {
      st.accumulator.add(raw.image());
      out.image().setTo(std::numeric_limits<float>::quiet_NaN());
      if (st.accumulator.count() >= st.capture_target) {
        st.captured_dark = st.accumulator.mean();
        st.capturing = false;
        st.accumulator.reset();
        GST_INFO_OBJECT(self, "dark captured from %d frames", st.capture_target);
        gst_element_post_message(
            GST_ELEMENT(self),
            gst_message_new_element(GST_OBJECT(self),
                                    gst_structure_new("pyrocam-dark-captured", "frames", G_TYPE_INT,
                                                      st.capture_target, nullptr)));
      }
      return;
    }
    const double saturation = settings.saturation_level >= 0 ? settings.saturation_level
                              : st.saturation_level >= 0
                                  ? st.saturation_level
                                  : pyrocam::default_saturation_level(st.bit_depth);
    if (const cv::Mat* dark = frame_dark(st)) {
      pyrocam::subtract_dark(raw.image(), *dark, saturation, out.image());
    } else if (settings.dark_level >= 0) {
      pyrocam::subtract_dark_level(raw.image(), settings.dark_level, saturation, out.image());
    } else {
      PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                         "No dark frame: set location, dark-level or emit capture-dark",
                         "location is empty, dark-level < 0 and no dark was captured");
      ret = GST_FLOW_ERROR;
    }
  });
  return ok ? ret : GST_FLOW_ERROR;
}

static void gst_dark_sub_capture_dark(GstDarkSub* self) {
  {
    pg::ObjectLock lock(self);
    ++self->settings->capture_requests;
  }
  GST_INFO_OBJECT(self, "dark capture requested");
}

static void gst_dark_sub_set_property(GObject* object, guint prop_id, const GValue* value,
                                      GParamSpec* pspec) {
  GstDarkSub* self = GST_DARK_SUB(object);
  {
    pg::ObjectLock lock(self);
    Settings& s = *self->settings;
    switch (prop_id) {
      case PROP_LOCATION:
        if (GST_STATE(self) > GST_STATE_READY) {
          GST_WARNING_OBJECT(self, "location can only change in NULL or READY");
        } else {
          const char* v = g_value_get_string(value);
          s.location = v ? v : "";
        }
        break;
      case PROP_DARK_LEVEL:
        s.dark_level = g_value_get_double(value);
        break;
      case PROP_SATURATION_LEVEL:
        s.saturation_level = g_value_get_double(value);
        break;
      case PROP_CAPTURE_FRAMES:
        s.capture_frames = g_value_get_int(value);
        break;
      case PROP_PATTERN:
        s.pattern = static_cast<GstDarkSubPattern>(g_value_get_enum(value));
        break;
      case PROP_BIT_DEPTH:
        s.bit_depth = g_value_get_int(value);
        break;
      default:
        G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
        break;
    }
  }
  /* The saturation level is in the output caps: renegotiate, so that ratiotemp sees it. */
  if (prop_id == PROP_SATURATION_LEVEL)
    gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

static void gst_dark_sub_get_property(GObject* object, guint prop_id, GValue* value,
                                      GParamSpec* pspec) {
  GstDarkSub* self = GST_DARK_SUB(object);
  pg::ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_LOCATION:
      g_value_set_string(value, s.location.empty() ? nullptr : s.location.c_str());
      break;
    case PROP_DARK_LEVEL:
      g_value_set_double(value, s.dark_level);
      break;
    case PROP_SATURATION_LEVEL:
      g_value_set_double(value, s.saturation_level);
      break;
    case PROP_CAPTURE_FRAMES:
      g_value_set_int(value, s.capture_frames);
      break;
    case PROP_PATTERN:
      g_value_set_enum(value, s.pattern);
      break;
    case PROP_BIT_DEPTH:
      g_value_set_int(value, s.bit_depth);
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

static void gst_dark_sub_finalize(GObject* object) {
  GstDarkSub* self = GST_DARK_SUB(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_dark_sub_parent_class)->finalize(object);
}

static void gst_dark_sub_class_init(GstDarkSubClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_dark_sub_debug, "darksub", 0, "pyrocam dark subtraction");

  gobject_class->set_property = gst_dark_sub_set_property;
  gobject_class->get_property = gst_dark_sub_get_property;
  gobject_class->finalize = gst_dark_sub_finalize;

  const auto ready = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                              GST_PARAM_MUTABLE_READY);
  const auto playing = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING | GST_PARAM_CONTROLLABLE);
  g_object_class_install_property(
      gobject_class, PROP_LOCATION,
      g_param_spec_string("location", "Dark frame file",
                          "Dark frame image (PGM, PNG or TIFF of the frame's size and sample "
                          "depth: 8 bit for 8-bit input, 16 bit for GRAY16_LE) "
                          "taken at the same exposure with the lens covered; empty: none",
                          nullptr, ready));
  g_object_class_install_property(
      gobject_class, PROP_DARK_LEVEL,
      g_param_spec_double("dark-level", "Constant dark level",
                          "Dark level in DN subtracted from every pixel when there is no dark "
                          "frame (0..65535); -1: a dark frame is required",
                          -1.0, 65535.0, DEFAULT_DARK_LEVEL, playing));
  g_object_class_install_property(
      gobject_class, PROP_SATURATION_LEVEL,
      g_param_spec_double("saturation-level", "Saturation level",
                          "Raw value in DN (before dark subtraction) at and above which a "
                          "pixel is marked saturated (+INF) (0..65535); -1: the caps' "
                          "saturation-level (pyrocamsrc: the camera profile's inference "
                          "threshold), else 220/255 of the full scale of the bit depth (220 for "
                          "8 bit)",
                          -1.0, 65535.0, DEFAULT_SATURATION_LEVEL, playing));
  g_object_class_install_property(
      gobject_class, PROP_CAPTURE_FRAMES,
      g_param_spec_int("capture-frames", "Dark capture frames",
                       "Number of frames capture-dark averages into a dark frame (1..1000)", 1,
                       1000, DEFAULT_CAPTURE_FRAMES,
                       static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING)));
  g_object_class_install_property(
      gobject_class, PROP_PATTERN,
      g_param_spec_enum("pattern", "Mosaic pattern",
                        "Mosaic layout of the input. auto: from the caps (the format of "
                        "video/x-bayer, the pattern field of GRAY8/GRAY16_LE); gray input "
                        "without a pattern field must be told one. A pattern that differs from "
                        "the caps' is refused (CORE NEGOTIATION)",
                        GST_TYPE_DARK_SUB_PATTERN, DEFAULT_PATTERN, ready));
  g_object_class_install_property(
      gobject_class, PROP_BIT_DEPTH,
      g_param_spec_int("bit-depth", "Bit depth",
                       "Significant bits of the input samples, e.g. 12 for a 12-bit camera "
                       "carried as GRAY16_LE (0..16; at most 8 for GRAY8 and video/x-bayer, "
                       "which are refused otherwise; 0: the full sample size, 8 or 16)",
                       0, 16, DEFAULT_BIT_DEPTH, ready));

  /**
   * GstDarkSub::capture-dark:
   * @darksub: the element
   *
   * Averages the next #GstDarkSub:capture-frames frames into a new dark frame (cover the lens
   * first). Frames output meanwhile are NaN. When done, an element message
   * "pyrocam-dark-captured" (frames: int) is posted.
   */
  gst_dark_sub_signals[SIGNAL_CAPTURE_DARK] = g_signal_new_class_handler(
      "capture-dark", G_TYPE_FROM_CLASS(klass),
      static_cast<GSignalFlags>(G_SIGNAL_RUN_LAST | G_SIGNAL_ACTION),
      G_CALLBACK(gst_dark_sub_capture_dark), nullptr, nullptr, nullptr, G_TYPE_NONE, 0);

  gst_element_class_set_static_metadata(
      element_class, "Dark frame subtraction", "Filter/Video",
      "Subtracts a dark frame from raw mosaics and marks saturated pixels (float32 DN)",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  trans_class->transform_caps = GST_DEBUG_FUNCPTR(gst_dark_sub_transform_caps);
  trans_class->transform_size = GST_DEBUG_FUNCPTR(gst_dark_sub_transform_size);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_dark_sub_set_caps);
  trans_class->decide_allocation = GST_DEBUG_FUNCPTR(pg::decide_allocation);
  trans_class->before_transform = GST_DEBUG_FUNCPTR(pg::sync_controlled_properties);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_dark_sub_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_dark_sub_stop);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_dark_sub_sink_event);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_dark_sub_transform);
  trans_class->passthrough_on_same_caps = FALSE;

  gst_type_mark_as_plugin_api(GST_TYPE_DARK_SUB_PATTERN, static_cast<GstPluginAPIFlags>(0));
}

static void gst_dark_sub_init(GstDarkSub* self) {
  self->settings = new Settings();
  self->state = new State();
}
