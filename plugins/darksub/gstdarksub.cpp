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
 *    frames of NaN (no reading), flagged GAP: the lens is covered, nothing downstream should be
 *    measured (ratiotemp posts no statistics for them).
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
/* The streaming: dark capture and subtraction, set_caps' checks; the caps it makes
 * (darksub-caps.cpp) and its properties (darksub-properties.cpp) are beside it. */
#include "gstdarksub.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>

#include "darksub-private.h"
#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/runtime/darksub.h"

GST_DEBUG_CATEGORY(gst_dark_sub_debug);
#define GST_CAT_DEFAULT gst_dark_sub_debug

namespace pg = pyrocam::gst;
namespace ds = pyrocam::gst::darksub;
using ds::Settings;

namespace {

enum { SIGNAL_CAPTURE_DARK, LAST_SIGNAL };
guint gst_dark_sub_signals[LAST_SIGNAL] = {0};

}  // namespace

/* Streaming state: built in start()/set_caps(), dropped in stop(). */
struct pyrocam::gst::darksub::State {
  pg::RawFormat format;
  bool have_format = false;
  int bit_depth = 8;
  std::string pattern;
  cv::Mat file_dark;  // CV_32F from `location`, decoded once the stream's size is known
  std::string file_dark_path;
  cv::Size file_dark_size;    // from the file's header, read in start()
  int file_dark_bits = 0;     // sample size of the file: 8 or 16
  int saturation_level = -1;  // raw DN from the caps' saturation-level field; -1: none
  // The dark-level subtracted: a level set while playing above the full scale is refused (it
  // would leave no reading anywhere), with a warning once per value.
  double dark_level = -1;
  double refused_dark_level = NAN;
  cv::Mat captured_dark;
  pyrocam::DarkAccumulator accumulator;
  bool capturing = false;
  int capture_target = 0;
  guint capture_requests_seen = 0;
  // Bayer mosaics: the cells' sums that tell where the greens are, until a verdict.
  pyrocam::BayerCellSums phase_sums;
  int phase_first_cell_row = 0;  // moves on a row each frame: every row of a 5x5 period is seen
  bool phase_warned = false;     // since start
  ds::DarkLevelWatch dark_level_watch;
};
using ds::State;

G_DEFINE_TYPE(GstDarkSub, gst_dark_sub, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(darksub, "darksub", GST_RANK_NONE, GST_TYPE_DARK_SUB);

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RAW_CAPS));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_MOSAIC_CAPS));

static Settings copy_settings(GstDarkSub* self) { return pg::locked_copy(self, *self->settings); }

static GstCaps* gst_dark_sub_transform_caps(GstBaseTransform* trans, GstPadDirection direction,
                                            GstCaps* caps, GstCaps* filter) {
  GstDarkSub* self = GST_DARK_SUB(trans);
  const Settings settings = copy_settings(self);
  GstCaps* result = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    const GstStructure* s = gst_caps_get_structure(caps, i);
    if (direction == GST_PAD_SINK)
      result = gst_caps_merge_structure(result, ds::mosaic_structure(s, settings));
    else
      result = gst_caps_merge(result, ds::raw_caps(s));
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
    // Said on the bus: the readings change to what the fallback gives.
    const Settings settings = copy_settings(self);
    const std::string instead = !st.file_dark_path.empty() ? "the dark frame " + st.file_dark_path
                                : settings.dark_level >= 0
                                    ? "dark-level " + std::to_string(settings.dark_level) + " DN"
                                    : std::string("no dark at all");
    GST_ELEMENT_WARNING(self, STREAM, FORMAT,
                        ("%s: the captured %dx%d dark does not fit the stream, now %dx%d: dropped; "
                         "%s is subtracted until a new capture (emit capture-dark)",
                         GST_OBJECT_NAME(self), st.captured_dark.cols, st.captured_dark.rows,
                         st.format.width, st.format.height, instead.c_str()),
                        ("caps changed after a dark capture"));
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
  const char* property_pattern = ds::pattern_name(settings.pattern);
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
    if (f.width < layout.period_width || f.height < layout.period_height)
      throw pyrocam::InputError(std::to_string(f.width) + "x" + std::to_string(f.height) +
                                " frames are smaller than one " + st.pattern + " period (" +
                                std::to_string(layout.period_width) + "x" +
                                std::to_string(layout.period_height) + ")");
    const int right = f.width % layout.period_width, bottom = f.height % layout.period_height;
    // Snapshot sensors carry a few columns and rows beyond the mosaic (2048x1088 around a
    // 2045x1085 5x5 one): say how to crop them.
    if (right || bottom)
      throw pyrocam::InputError(
          std::to_string(f.width) + "x" + std::to_string(f.height) + " frames are not whole " +
          st.pattern + " periods: crop them to the mosaic's " + std::to_string(f.width - right) +
          "x" + std::to_string(f.height - bottom) + " first, e.g. videocrop right=" +
          std::to_string(right) + " bottom=" + std::to_string(bottom) +
          " (or left/top where the mosaic starts later on the sensor)");
  });
  if (!ok) return FALSE;
  if (settings.dark_level > pyrocam::full_scale_dn(st.bit_depth)) {
    // Every sample below it: no reading anywhere, and nothing would say why.
    char level[32];
    std::snprintf(level, sizeof level, "%g", settings.dark_level);
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "dark-level " + std::string(level) + " is above the " +
                           std::to_string(st.bit_depth) + "-bit full scale (" +
                           std::to_string(pyrocam::full_scale_dn(st.bit_depth)) + " DN)",
                       "dark-level out of the stream's range");
    return FALSE;
  }
  st.dark_level = settings.dark_level;
  if (!ds::saturation_above_dark(
          GST_ELEMENT(self), settings,
          ds::saturation_in_use(settings, st.saturation_level, st.bit_depth)))
    return FALSE;
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
  pg::forget_posted_errors(GST_ELEMENT(trans));
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

/* A Bayer mosaic whose greens are not where its pattern says was shifted by a row or a column
 * (a crop at the top or left by an odd number) and reads temperatures that look right and are
 * wrong; so do frames that are no Bayer mosaic, whose greens differ: warns once since start.
 * Every 16th row of cells (every 4th took 3 % of the colour chain's CPU) up to 4096 lit cells a
 * frame (all of a bright plate's took 8 ms), a row further on in each frame (a 5x5 mosaic's cells
 * lie inside a body in one row of its period only), over frames until enough lit ones. */
static void check_bayer_phase(GstDarkSub* self, State& st, const cv::Mat& signal,
                              GstBuffer* buffer) {
  constexpr int kCellRowStep = 16;
  constexpr std::size_t kCells = 256, kCellsAFrame = 16 * kCells;
  if (st.phase_warned || st.pattern == PYROCAM_SNAPSHOT_PATTERN_NAME) return;
  const float lit_dn =
      std::max(4.0f, 0.02f * static_cast<float>(pyrocam::full_scale_dn(st.bit_depth)));
  const float bright_dn = 0.2f * static_cast<float>(pyrocam::full_scale_dn(st.bit_depth));
  // No camera profile here: the noise of a sensor whose full well is 5000 electrons (less than
  // most industrial sensors') at the frame's analogue gain (0 dB without exposure metadata), with
  // a read noise of 1 DN; where the frame's samples scatter more (a higher gain than that),
  // add_bayer_cell_sums widens it to their measured scatter.
  const PyrocamExposureMeta* meta = pyrocam_buffer_get_exposure_meta(buffer);
  const double gain = pyrocam::analogue_gain_factor(meta ? meta->gain_db : 0.0);
  const pyrocam::SignalNoise noise{
      gain * static_cast<double>(pyrocam::full_scale_dn(st.bit_depth)) / 5000, 2.0};
  pyrocam::add_bayer_cell_sums(signal, lit_dn, bright_dn, st.phase_first_cell_row, kCellRowStep,
                               noise, st.phase_sums, kCellsAFrame);
  st.phase_first_cell_row = (st.phase_first_cell_row + 1) % kCellRowStep;
  if (st.phase_sums.cells < kCells) return;
  GST_DEBUG_OBJECT(self,
                   "phase check over %zu lit cells: green places apart in %zu of %zu, %zu of %zu",
                   st.phase_sums.cells, st.phase_sums.apart[0], st.phase_sums.bright[0],
                   st.phase_sums.apart[1], st.phase_sums.bright[1]);
  if (pyrocam::bayer_greens_elsewhere(st.phase_sums, st.pattern)) {
    const double* s = &st.phase_sums.at[0][0];
    GST_ELEMENT_WARNING(
        self, STREAM, FORMAT,
        ("%s: the stream says %s, but its green samples are on the other diagonal of the 2x2 "
         "cell: the mosaic is shifted by one row or column (a crop at the top or left by an odd "
         "number of pixels before darksub?), and its temperatures would look right and be "
         "wrong. Crop by even numbers, or give the pattern the crop leaves",
         GST_OBJECT_NAME(self), st.pattern.c_str()),
        ("mean DN per cell place (row-major) %.1f %.1f %.1f %.1f over %zu lit cells",
         s[0] / st.phase_sums.cells, s[1] / st.phase_sums.cells, s[2] / st.phase_sums.cells,
         s[3] / st.phase_sums.cells, st.phase_sums.cells));
    st.phase_warned = true;
  } else if (pyrocam::bayer_greens_disagree(st.phase_sums, st.pattern)) {
    const int k = st.pattern == "rggb" || st.pattern == "bggr" ? 1 : 0;
    GST_ELEMENT_WARNING(
        self, STREAM, FORMAT,
        ("%s: the stream says %s, but the two samples where it puts the greens differ by more "
         "than 12 %% in %zu of %zu bright cells (a Bayer sensor's greens agree within their "
         "noise): this is no Bayer mosaic (a snapshot mosaic?), and its temperatures would look "
         "right and be wrong",
         GST_OBJECT_NAME(self), st.pattern.c_str(), st.phase_sums.apart[k],
         st.phase_sums.bright[k]),
        ("over %zu lit cells", st.phase_sums.cells));
    st.phase_warned = true;
  }
  st.phase_sums = {};
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
      // No image: downstream gives it no reading and counts nothing (not saturation).
      GST_BUFFER_FLAG_SET(outbuf, GST_BUFFER_FLAG_GAP);
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
    const double saturation = ds::saturation_in_use(settings, st.saturation_level, st.bit_depth);
    pyrocam::SaturatedSamples saturated;
    if (const cv::Mat* dark = frame_dark(st)) {
      saturated = pyrocam::subtract_dark(raw.image(), *dark, saturation, out.image());
    } else if (settings.dark_level >= 0) {
      if (!ds::use_dark_level(GST_ELEMENT(self), settings.dark_level, st.bit_depth, st.dark_level,
                              st.refused_dark_level)) {
        ret = GST_FLOW_ERROR;
        return;
      }
      saturated = pyrocam::subtract_dark_level(raw.image(), st.dark_level, saturation, out.image());
    } else {
      PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                         "No dark frame: set location, dark-level or emit capture-dark",
                         "location is empty, dark-level < 0 and no dark was captured");
      ret = GST_FLOW_ERROR;
      return;
    }
    // Samples above the stated bit depth's full scale: the stream is not what its caps say
    // (scaled to 16 bits by videoconvert, MSB-aligned), and read as it is every pixel would be
    // "saturated". Looked for only in frames with saturated samples.
    if (saturated.count > 0 && st.bit_depth < 8 * st.format.bytes_per_sample) {
      double max_dn = 0;
      cv::minMaxLoc(raw.image(), nullptr, &max_dn);
      const int full_scale = pyrocam::full_scale_dn(st.bit_depth);
      if (max_dn > full_scale) {
        PYROCAM_POST_ERROR(self, pg::ErrorKind::kFormat,
                           "Samples up to " + std::to_string(static_cast<long>(max_dn)) +
                               " DN in a stream whose caps say bit-depth " +
                               std::to_string(st.bit_depth) + " (full scale " +
                               std::to_string(full_scale) +
                               " DN): the samples are not what the caps say (scaled by "
                               "videoconvert? MSB-aligned?); give the true bit-depth",
                           "sample above the bit depth's full scale");
        ret = GST_FLOW_ERROR;
        return;
      }
    }
    const cv::Rect& box = saturated.bounds;
    pyrocam_buffer_set_saturation_meta(outbuf, saturated.count, box.x, box.y, box.width, box.height,
                                       st.format.width, st.format.height, saturated.tiles.data());
    check_bayer_phase(self, st, out.image(), inbuf);
    ds::watch_dark_level(GST_ELEMENT(self), st.dark_level_watch, out.image(),
                         st.pattern == PYROCAM_SNAPSHOT_PATTERN_NAME ? 5 : 2, st.bit_depth,
                         !st.captured_dark.empty() ? "the captured dark" : st.file_dark_path,
                         st.dark_level);
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

  gobject_class->set_property = ds::set_property;
  gobject_class->get_property = ds::get_property;
  gobject_class->finalize = gst_dark_sub_finalize;

  ds::install_properties(gobject_class);

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
