/**
 * SECTION:element-mosaicfuse
 * @title: mosaicfuse
 *
 * High dynamic range from an exposure bracket, fused before demosaicking: the camera cycles
 * through two or more exposures (pyrocamsrc #GstPyrocamSrc:bracket) and mosaicfuse, between
 * darksub and demosaic25, gives each dark-subtracted mosaic (video/x-pyrocam-mosaic) the samples
 * of the last #GstMosaicFuse:frames frames: each sample from the frame taken with the most light
 * (exposure times the linear gain, from the frames' PyrocamExposureMeta) where it is a number
 * (neither saturated nor without a reading) and, where it is near the level, no sample of its
 * band within two cells of the mosaic is saturated, scaled to the DN of the frame with the most
 * light. (The neighbours decide, not the sample itself: a sample just below the level would
 * otherwise be kept where its own noise pulled it down, and the fused values along the level's
 * contour would be low: a colour plate with red at the level read 9 degC high.)
 * So each band of a demosaicking footprint has a value even where the footprint spans more
 * brightness than one exposure holds (a melt pool's steep side), where thermalfuse, fusing whole
 * readings after ratiotemp, has none: on simulated melt pools (targets suite, six exposures a
 * factor 3 apart) 87 % of the pixels hotter than 1300 degC read against 63 %, 0.5 % of the
 * readings more than max(150 degC, 10 %) off. The output buffer's PyrocamExposureMeta is that of
 * the frame with the most light, whose DN the values are in; values above the saturation level
 * are readings from a shorter exposure. One frame out per frame in, with the latest frame's time.
 *
 * A sample from a shorter exposure, scaled up, is noisier than the noise model of the longest
 * one says: ratiotemp's uncertainty output and misfit check are too confident on such pixels.
 * Samples of different frames meet in one footprint: over a pool that moves between the frames
 * of a bracket, the bands of a pixel near the boundary would be from different places, and its
 * reading of no temperature at all. With #GstMosaicFuse:follow-motion (the default) the fusion
 * follows a scene that moves as a whole at a steady velocity (a melt pool along its track): the
 * velocity is the shift between the latest frame and the last one with the same exposure (the
 * cycle before), found where both expose well, and each earlier frame's samples are taken from
 * where the scene has moved since, interpolated along their band's samples, and brought forward
 * by the change of brightness found between the same two frames (a pool's peak that rises or
 * falls). On a simulated pool moving 0.67 pixels a frame, its peak changing by up to 20 degC a
 * frame (targets suite, six exposures) 93 % of the pixels hotter than 1300 degC read instead of
 * 81 %, and 8.2 % of the readings were more than max(150 degC, 10 %) off the latest frame's
 * truth instead of 35 %; what is left reads high at the pool's steep front. A still
 * scene, or one moving under about one cell of the mosaic a cycle, is fused as it is. Each frame
 * is also compared with the one before on the samples both expose well, scaled to one exposure:
 * once, over the stream, they disagree beyond a bound on the noise several times a sensor's on
 * at least 20 samples and 0.2 % of those compared, one warning on the bus (STREAM FORMAT) says
 * that the scene moves (and whether the fusion follows it); the fusion goes on (a still pool's
 * frames disagree on none).
 *
 * A frame without exposure metadata passes unchanged and starts the fusion anew, with one
 * warning on the bus (STREAM FORMAT). A frame whose time is before the frame's before it
 * (frames out of order) starts anew too, with one warning. New caps or a flush start anew.
 *
 * ## Example launch line
 * (pyrocamsrc's melt pool moves, about 1.6 pixels a frame at 320x240: mosaicfuse follows it
 * and warns once that the scene moves)
 * |[
 * gst-launch-1.0 pyrocamsrc scene=melt-pool bracket=3,1,0.333,0.111,0.037,0.012,0.004 ! \
 *     darksub dark-level=50 ! mosaicfuse frames=7 ! demosaic25 ! \
 *     ratiotemp model=model.json blur-correction=true ! thermalcolormap ! videoconvert ! \
 *     autovideosink
 * ]|
 */
#include "gstmosaicfuse.h"

#include <cmath>
#include <deque>
#include <memory>
#include <opencv2/core.hpp>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/bracket_fusion.h"
#include "pyrocam/runtime/darksub.h"

GST_DEBUG_CATEGORY_STATIC(gst_mosaic_fuse_debug);
#define GST_CAT_DEFAULT gst_mosaic_fuse_debug

namespace pg = pyrocam::gst;

namespace {

enum { PROP_0, PROP_FRAMES, PROP_FOLLOW_MOTION };

constexpr guint DEFAULT_FRAMES = 2;
constexpr gboolean DEFAULT_FOLLOW_MOTION = TRUE;

struct Settings {
  guint frames = DEFAULT_FRAMES;
  gboolean follow_motion = DEFAULT_FOLLOW_MOTION;
};

// The exposure of a frame the fusion holds.
struct Exposure {
  double light, exposure_us, gain_db;
};

struct State {
  std::unique_ptr<pyrocam::MosaicBracketFusion> fusion;  // of settings' frames
  std::deque<Exposure> exposures;                        // as the fusion's frames, latest last
  int width = 0, height = 0;
  int period = 2;  // of the mosaic's cell: 2 for Bayer, 5 for 5x5
  bool warned_no_exposure = false;
  GstClockTime last_pts = GST_CLOCK_TIME_NONE;  // of the frame before
  bool warned_out_of_order = false;
  pyrocam::MosaicBracketFusion::Agreement agreement;  // of consecutive frames, since the start
  bool warned_moving = false;
  void reset() {
    if (fusion) fusion->reset();
    exposures.clear();
  }
};

}  // namespace

struct _GstMosaicFuse {
  GstBaseTransform parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstMosaicFuse, gst_mosaic_fuse, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(mosaicfuse, "mosaicfuse", GST_RANK_NONE, GST_TYPE_MOSAIC_FUSE);

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_MOSAIC_CAPS));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_MOSAIC_CAPS));

static gboolean gst_mosaic_fuse_start(GstBaseTransform* trans) {
  pg::forget_posted_errors(GST_ELEMENT(trans));
  *GST_MOSAIC_FUSE(trans)->state = State();
  return TRUE;
}

static gboolean gst_mosaic_fuse_stop(GstBaseTransform* trans) {
  *GST_MOSAIC_FUSE(trans)->state = State();
  return TRUE;
}

static gboolean gst_mosaic_fuse_set_caps(GstBaseTransform* trans, GstCaps* incaps, GstCaps*) {
  State& st = *GST_MOSAIC_FUSE(trans)->state;
  const GstStructure* s = gst_caps_get_structure(incaps, 0);
  int width = 0, height = 0;
  if (!gst_structure_get_int(s, "width", &width) || !gst_structure_get_int(s, "height", &height) ||
      width < 1 || height < 1) {
    PYROCAM_POST_ERROR(trans, pg::ErrorKind::kNegotiation, "Mosaic caps without a frame size",
                       "caps without width and height");
    return FALSE;
  }
  st.width = width;
  st.height = height;
  const char* pattern = gst_structure_get_string(s, PYROCAM_FIELD_PATTERN);
  const int period =
      pattern != nullptr && g_str_equal(pattern, PYROCAM_SNAPSHOT_PATTERN_NAME) ? 5 : 2;
  if (period != st.period) st.fusion.reset();
  st.period = period;
  st.reset();
  st.last_pts = GST_CLOCK_TIME_NONE;
  return TRUE;
}

static gboolean gst_mosaic_fuse_sink_event(GstBaseTransform* trans, GstEvent* event) {
  if (GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP) {
    State& st = *GST_MOSAIC_FUSE(trans)->state;
    st.reset();
    st.last_pts = GST_CLOCK_TIME_NONE;
  }
  return GST_BASE_TRANSFORM_CLASS(gst_mosaic_fuse_parent_class)->sink_event(trans, event);
}

static GstFlowReturn gst_mosaic_fuse_transform_ip(GstBaseTransform* trans, GstBuffer* buffer) {
  GstMosaicFuse* self = GST_MOSAIC_FUSE(trans);
  State& st = *self->state;
  if (st.width < 1) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "No format negotiated",
                       "transform called before set_caps");
    return GST_FLOW_NOT_NEGOTIATED;
  }
  const Settings settings = pg::locked_copy(self, *self->settings);
  const int frames = static_cast<int>(settings.frames);
  if (!st.fusion || st.fusion->frames() != frames) {
    st.fusion = std::make_unique<pyrocam::MosaicBracketFusion>(frames, st.period);
    st.exposures.clear();
  }
  st.fusion->set_follows_motion(settings.follow_motion);
  if (pg::frame_out_of_time_order(GST_ELEMENT(self), buffer, st.last_pts, st.warned_out_of_order))
    st.reset();
  PyrocamExposureMeta* meta = pyrocam_buffer_get_exposure_meta(buffer);
  if (meta == nullptr || !(meta->exposure_us > 0)) {
    st.reset();
    pg::warn_frame_without_exposure(GST_ELEMENT(self), st.warned_no_exposure);
    return GST_FLOW_OK;
  }
  const Exposure now{meta->exposure_us * pyrocam::analogue_gain_factor(meta->gain_db),
                     meta->exposure_us, meta->gain_db};
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not fuse the bracket", [&] {
    pg::MappedImage mosaic;
    mosaic.map_float(buffer, st.width, st.height, 1,
                     static_cast<GstMapFlags>(GST_MAP_READ | GST_MAP_WRITE));
    const double reference = st.fusion->add(mosaic.image(), now.light, mosaic.image());
    const pyrocam::MosaicBracketFusion::Agreement& agreement = st.fusion->last_agreement();
    const cv::Point2d& velocity = st.fusion->velocity();
    GST_LOG_OBJECT(self,
                   "the frame before disagrees on %zu of %zu samples; velocity followed %.2f, "
                   "%.2f pixels a frame",
                   agreement.disagreeing, agreement.compared, velocity.x, velocity.y);
    st.agreement += agreement;
    if (!st.warned_moving && st.agreement.moved()) {
      st.warned_moving = true;
      if (settings.follow_motion)
        GST_ELEMENT_WARNING(
            self, STREAM, FORMAT,
            ("The scene moves between the bracket's frames: consecutive frames disagree on %zu "
             "of %zu samples both expose well. mosaicfuse follows it as a shift at a steady "
             "velocity (%.2f, %.2f pixels a frame so far; 0, 0 until a cycle of the bracket "
             "shows it) and a change of brightness; where the scene changes otherwise (its "
             "shape), samples of different moments still meet in one demosaicking footprint: if "
             "its boundaries read wrong, fuse the readings with thermalfuse after ratiotemp "
             "instead",
             st.agreement.disagreeing, st.agreement.compared, velocity.x, velocity.y),
            ("beyond 4 standard deviations of a bound on the noise (1 DN of shot variance per "
             "DN, 4 DN^2 floor) and 5 %%"));
      else
        GST_ELEMENT_WARNING(
            self, STREAM, FORMAT,
            ("The scene moves between the bracket's frames: consecutive frames disagree on %zu "
             "of %zu samples both expose well. Samples of different moments meet in one "
             "demosaicking footprint, whose reading may be of no temperature; set "
             "follow-motion=true, or fuse a moving scene's readings with thermalfuse after "
             "ratiotemp instead (or, if the scene holds still, the frames were not taken with "
             "the exposures their metadata say)",
             st.agreement.disagreeing, st.agreement.compared),
            ("beyond 4 standard deviations of a bound on the noise (1 DN of shot variance per "
             "DN, 4 DN^2 floor) and 5 %%"));
    }
    // Saturated now only where no frame of the bracket read: say where, for the elements
    // downstream, in place of darksub's count for this frame alone.
    const pyrocam::SaturatedSamples saturated = pyrocam::find_saturated(mosaic.image());
    const cv::Rect& box = saturated.bounds;
    pyrocam_buffer_set_saturation_meta(buffer, saturated.count, box.x, box.y, box.width, box.height,
                                       st.width, st.height, saturated.tiles.data());
    st.exposures.push_back(now);
    while (static_cast<int>(st.exposures.size()) > frames) st.exposures.pop_front();
    // The values are in the DN of the frame with the most light: say its exposure.
    for (const Exposure& e : st.exposures)
      if (e.light == reference) {
        meta->exposure_us = e.exposure_us;
        meta->gain_db = e.gain_db;
      }
  });
  return ok ? GST_FLOW_OK : GST_FLOW_ERROR;
}

static void gst_mosaic_fuse_set_property(GObject* object, guint prop_id, const GValue* value,
                                         GParamSpec* pspec) {
  GstMosaicFuse* self = GST_MOSAIC_FUSE(object);
  pg::ObjectLock lock(self);
  if (prop_id == PROP_FRAMES)
    self->settings->frames = g_value_get_uint(value);
  else if (prop_id == PROP_FOLLOW_MOTION)
    self->settings->follow_motion = g_value_get_boolean(value);
  else
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
}

static void gst_mosaic_fuse_get_property(GObject* object, guint prop_id, GValue* value,
                                         GParamSpec* pspec) {
  GstMosaicFuse* self = GST_MOSAIC_FUSE(object);
  pg::ObjectLock lock(self);
  if (prop_id == PROP_FRAMES)
    g_value_set_uint(value, self->settings->frames);
  else if (prop_id == PROP_FOLLOW_MOTION)
    g_value_set_boolean(value, self->settings->follow_motion);
  else
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
}

static void gst_mosaic_fuse_finalize(GObject* object) {
  GstMosaicFuse* self = GST_MOSAIC_FUSE(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_mosaic_fuse_parent_class)->finalize(object);
}

static void gst_mosaic_fuse_class_init(GstMosaicFuseClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_mosaic_fuse_debug, "mosaicfuse", 0,
                          "pyrocam exposure-bracket fusion of mosaics");
  gobject_class->set_property = gst_mosaic_fuse_set_property;
  gobject_class->get_property = gst_mosaic_fuse_get_property;
  gobject_class->finalize = gst_mosaic_fuse_finalize;

  g_object_class_install_property(gobject_class, PROP_FRAMES,
                                  pg::bracket_frames_param(DEFAULT_FRAMES));
  /**
   * GstMosaicFuse:follow-motion:
   *
   * Follow a scene that moves between the bracket's frames as a shift at a steady velocity,
   * found between frames of the same exposure: earlier frames' samples are taken from where the
   * scene has moved since. Off: every frame's samples where they are.
   */
  g_object_class_install_property(
      gobject_class, PROP_FOLLOW_MOTION,
      g_param_spec_boolean(
          "follow-motion", "Follow motion",
          "Take earlier frames' samples from where a moving scene has gone since (a steady "
          "velocity, found between frames of the same exposure); false: where they are",
          DEFAULT_FOLLOW_MOTION,
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_PLAYING)));

  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);
  gst_element_class_set_static_metadata(
      element_class, "Mosaic exposure-bracket fusion", "Filter/Video",
      "Gives each dark-subtracted mosaic the samples of the last frames of an exposure bracket: "
      "each sample from the most exposed frame where it is a number, scaled to that exposure",
      "pyrocam");

  trans_class->passthrough_on_same_caps = FALSE;
  trans_class->start = GST_DEBUG_FUNCPTR(gst_mosaic_fuse_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_mosaic_fuse_stop);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_mosaic_fuse_set_caps);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_mosaic_fuse_sink_event);
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_mosaic_fuse_transform_ip);
}

static void gst_mosaic_fuse_init(GstMosaicFuse* self) {
  self->settings = new Settings();
  self->state = new State();
}
