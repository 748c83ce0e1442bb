/**
 * SECTION:element-thermalfuse
 * @title: thermalfuse
 *
 * High dynamic range from an exposure bracket: the camera cycles through two or more exposures
 * (pyrocamsrc #GstPyrocamSrc:bracket) and thermalfuse, after ratiotemp, gives each temperature
 * frame (video/x-raw GRAY16_LE in 0.1 K, 0 = no reading) the readings of the last
 * #GstThermalFuse:frames frames: each pixel from the frame taken with the most light (exposure
 * times the linear gain, from the frames' PyrocamExposureMeta) where it reads, ties to the
 * latest. More light is more signal in every band, so of two readings the more exposed one has
 * the smaller noise; where it saturates (a 2500 degC core at the long exposure) or is dim (a
 * 1300 degC rim at the short one) it has no reading and the other exposure's is used. A pixel
 * taken from an earlier frame is as old as that frame: over a moving pool, where the pool was
 * one frame before. One frame out per frame in, with the latest frame's time.
 *
 * A frame without exposure metadata (a source that does not attach it) passes unchanged and
 * starts the fusion anew, with one warning on the bus (STREAM FORMAT): frames of unknown
 * exposure cannot be ranked, and fusing them blindly could put a dim exposure's noisier reading
 * over a good one. A frame whose time is before the frame's before it (frames out of order)
 * starts anew too, with one warning. New caps or a flush start anew.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc scene=melt-pool bracket=9,3,1,0.333,0.111,0.037 ! \
 *     darksub dark-level=50 ! demosaic25 ! ratiotemp model=model.json ! thermalfuse frames=6 ! \
 *     thermalcolormap ! videoconvert ! autovideosink
 * ]|
 */
#include "gstthermalfuse.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <memory>
#include <opencv2/core.hpp>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/bracket_fusion.h"

GST_DEBUG_CATEGORY_STATIC(gst_thermal_fuse_debug);
#define GST_CAT_DEFAULT gst_thermal_fuse_debug

namespace pg = pyrocam::gst;

namespace {

enum { PROP_0, PROP_FRAMES };

constexpr guint DEFAULT_FRAMES = 2;

struct Settings {
  guint frames = DEFAULT_FRAMES;
};

// A held frame's light and saturation (PyrocamSaturationMeta's fields; none: frame_width 0).
struct HeldSaturation {
  double light = 0;
  PyrocamSaturationMeta saturation{};
};

struct State {
  std::unique_ptr<pyrocam::BracketFusion> fusion;  // of settings' frames; rebuilt on a change
  std::deque<HeldSaturation> held;                 // the frames the fusion holds, oldest first
  bool warned_no_exposure = false;
  GstClockTime last_pts = GST_CLOCK_TIME_NONE;  // of the frame before
  bool warned_out_of_order = false;
};

/* A pixel saturated in the frame with the least light is saturated in every frame (each band
 * brighter with more light), so it has no reading in the fused frame either: that frame's
 * saturation is the fused frame's. */
void set_fused_saturation(GstBuffer* buffer, const std::deque<HeldSaturation>& fused) {
  const HeldSaturation* least = nullptr;
  for (const HeldSaturation& h : fused)
    if (!least || h.light < least->light) least = &h;
  if (PyrocamSaturationMeta* own = pyrocam_buffer_get_saturation_meta(buffer))
    gst_buffer_remove_meta(buffer, &own->meta);
  if (!least || least->saturation.frame_width <= 0) return;  // not known
  const PyrocamSaturationMeta& m = least->saturation;
  pyrocam_buffer_set_saturation_meta(buffer, m.samples, m.x, m.y, m.width, m.height, m.frame_width,
                                     m.frame_height, m.tiles);
}

}  // namespace

struct _GstThermalFuse {
  GstVideoFilter parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstThermalFuse, gst_thermal_fuse, GST_TYPE_VIDEO_FILTER);
GST_ELEMENT_REGISTER_DEFINE(thermalfuse, "thermalfuse", GST_RANK_NONE, GST_TYPE_THERMAL_FUSE);

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_TEMPERATURE_CAPS));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_TEMPERATURE_CAPS));

static gboolean gst_thermal_fuse_start(GstBaseTransform* trans) {
  pg::forget_posted_errors(GST_ELEMENT(trans));
  *GST_THERMAL_FUSE(trans)->state = State();
  return TRUE;
}

static gboolean gst_thermal_fuse_stop(GstBaseTransform* trans) {
  *GST_THERMAL_FUSE(trans)->state = State();
  return TRUE;
}

static gboolean gst_thermal_fuse_set_info(GstVideoFilter* filter, GstCaps*, GstVideoInfo*, GstCaps*,
                                          GstVideoInfo*) {
  State& st = *GST_THERMAL_FUSE(filter)->state;
  if (st.fusion) st.fusion->reset();
  st.held.clear();
  st.last_pts = GST_CLOCK_TIME_NONE;
  return TRUE;
}

static gboolean gst_thermal_fuse_sink_event(GstBaseTransform* trans, GstEvent* event) {
  if (GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP) {
    State& st = *GST_THERMAL_FUSE(trans)->state;
    if (st.fusion) st.fusion->reset();
    st.held.clear();
    st.last_pts = GST_CLOCK_TIME_NONE;
  }
  return GST_BASE_TRANSFORM_CLASS(gst_thermal_fuse_parent_class)->sink_event(trans, event);
}

static GstFlowReturn gst_thermal_fuse_transform_frame_ip(GstVideoFilter* filter,
                                                         GstVideoFrame* frame) {
  GstThermalFuse* self = GST_THERMAL_FUSE(filter);
  State& st = *self->state;
  const int frames = static_cast<int>(pg::locked_copy(self, self->settings->frames));
  if (!st.fusion || st.fusion->frames() != frames) {
    st.fusion = std::make_unique<pyrocam::BracketFusion>(frames);
    st.held.clear();
  }
  // A frame without an image (GAP: darksub capturing a dark) passes as it is, with no reading,
  // and the fusion starts anew after it: fused with earlier frames it showed their readings.
  if (GST_BUFFER_FLAG_IS_SET(frame->buffer, GST_BUFFER_FLAG_GAP)) {
    st.fusion->reset();
    st.held.clear();
    return GST_FLOW_OK;
  }
  if (pg::frame_out_of_time_order(GST_ELEMENT(self), frame->buffer, st.last_pts,
                                  st.warned_out_of_order)) {
    st.fusion->reset();
    st.held.clear();
  }
  const PyrocamExposureMeta* meta = pyrocam_buffer_get_exposure_meta(frame->buffer);
  if (meta == nullptr || !(meta->exposure_us > 0)) {
    st.fusion->reset();
    st.held.clear();
    pg::warn_frame_without_exposure(GST_ELEMENT(self), st.warned_no_exposure);
    return GST_FLOW_OK;
  }
  const double light = meta->exposure_us * pyrocam::analogue_gain_factor(meta->gain_db);
  cv::Mat codes(GST_VIDEO_FRAME_HEIGHT(frame), GST_VIDEO_FRAME_WIDTH(frame), CV_16U,
                GST_VIDEO_FRAME_PLANE_DATA(frame, 0),
                static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(frame, 0)));
  const std::size_t before = st.fusion->held();
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not fuse the bracket",
                                  [&] { st.fusion->add(codes, light, codes); });
  if (!ok) return GST_FLOW_ERROR;
  // The frames fused: those held before and this one, or this one alone where the fusion
  // started anew (a new frame size).
  const std::size_t expected =
      std::min<std::size_t>(before + 1, static_cast<std::size_t>(frames - 1));
  if (st.fusion->held() < expected) st.held.clear();
  HeldSaturation now;
  now.light = light;
  if (const PyrocamSaturationMeta* m = pyrocam_buffer_get_saturation_meta(frame->buffer))
    now.saturation = *m;
  st.held.push_back(now);
  set_fused_saturation(frame->buffer, st.held);
  while (st.held.size() > st.fusion->held()) st.held.pop_front();
  return GST_FLOW_OK;
}

static void gst_thermal_fuse_set_property(GObject* object, guint prop_id, const GValue* value,
                                          GParamSpec* pspec) {
  GstThermalFuse* self = GST_THERMAL_FUSE(object);
  pg::ObjectLock lock(self);
  if (prop_id == PROP_FRAMES)
    self->settings->frames = g_value_get_uint(value);
  else
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
}

static void gst_thermal_fuse_get_property(GObject* object, guint prop_id, GValue* value,
                                          GParamSpec* pspec) {
  GstThermalFuse* self = GST_THERMAL_FUSE(object);
  pg::ObjectLock lock(self);
  if (prop_id == PROP_FRAMES)
    g_value_set_uint(value, self->settings->frames);
  else
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
}

static void gst_thermal_fuse_finalize(GObject* object) {
  GstThermalFuse* self = GST_THERMAL_FUSE(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_thermal_fuse_parent_class)->finalize(object);
}

static void gst_thermal_fuse_class_init(GstThermalFuseClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);
  GstVideoFilterClass* filter_class = GST_VIDEO_FILTER_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_thermal_fuse_debug, "thermalfuse", 0,
                          "pyrocam exposure-bracket fusion");
  gobject_class->set_property = gst_thermal_fuse_set_property;
  gobject_class->get_property = gst_thermal_fuse_get_property;
  gobject_class->finalize = gst_thermal_fuse_finalize;

  g_object_class_install_property(gobject_class, PROP_FRAMES,
                                  pg::bracket_frames_param(DEFAULT_FRAMES));

  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);
  gst_element_class_set_static_metadata(
      element_class, "Thermal exposure-bracket fusion", "Filter/Video",
      "Gives each temperature frame the readings of the last frames of an exposure bracket: "
      "each pixel from the most exposed frame where it reads",
      "pyrocam");

  trans_class->start = GST_DEBUG_FUNCPTR(gst_thermal_fuse_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_thermal_fuse_stop);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_thermal_fuse_sink_event);
  filter_class->set_info = GST_DEBUG_FUNCPTR(gst_thermal_fuse_set_info);
  filter_class->transform_frame_ip = GST_DEBUG_FUNCPTR(gst_thermal_fuse_transform_frame_ip);
}

static void gst_thermal_fuse_init(GstThermalFuse* self) {
  self->settings = new Settings();
  self->state = new State();
}
