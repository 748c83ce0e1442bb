/**
 * SECTION:element-thermaloverlay
 * @title: thermaloverlay
 *
 * Lays the colour-mapped temperatures of a frame (thermalcolormap's RGBA output, on the
 * overlay_sink pad) over the camera image of the same frame (video_sink: RGBA, BGRA, RGBx or
 * BGRx of the same size, e.g. from bayer2rgb) and sends the camera image with its overlay.
 *
 * Frames are paired by their timestamps, and a camera frame waits for its own overlay however
 * long the temperature branch takes: a view never shows a frame under another frame's
 * temperatures (over a moving melt pool, temperatures beside the pool that look right), nor
 * without its overlay because the overlay came late, from the first frame on. compositor, by
 * contrast, times out in a live pipeline and then mixes whatever overlay it has. A camera
 * frame goes out bare only when its overlay cannot come: the overlay branch dropped that frame
 * (an overlay with a later timestamp came first) or ended. Overlays older than the camera frame
 * are dropped. Frames without timestamps are paired in order.
 *
 * The time a frame waits is reported downstream as #GstThermalOverlay:latency, so that a live
 * sink shows the frames rather than dropping them as late; a frame whose overlay takes longer
 * still goes out with it, late (a sink with sync=true may drop it). Blending: each colour byte
 * becomes (overlay × alpha + camera × (255 − alpha)) / 255; the camera image's fourth byte is
 * kept. An overlay whose size differs from the camera image's is an error (STREAM FORMAT).
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc is-live=true scene=melt-pool ! \
 *     video/x-bayer,width=320,height=240,framerate=30/1 ! tee name=camera \
 *   camera. ! queue ! bayer2rgb ! video/x-raw,format=RGBA ! mix.video_sink \
 *   camera. ! queue ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=model.json ! \
 *     thermalcolormap scale-bar=true ! mix.overlay_sink \
 *   thermaloverlay name=mix ! queue ! videoconvert ! autovideosink
 * ]|
 */
#include "gstthermaloverlay.h"

#include <gst/video/video.h>

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/runtime/colormap.h"

GST_DEBUG_CATEGORY_STATIC(gst_thermal_overlay_debug);
#define GST_CAT_DEFAULT gst_thermal_overlay_debug

namespace pg = pyrocam::gst;

namespace {

enum { PROP_0, PROP_LATENCY };

constexpr guint64 DEFAULT_LATENCY = 100 * GST_MSECOND;
constexpr guint64 MAX_LATENCY = 10 * GST_SECOND;
// Overlays held ahead of their camera frames; the overlay branch waits beyond that.
constexpr std::size_t kMaxQueuedOverlays = 4;

struct Settings {
  guint64 latency = DEFAULT_LATENCY;
};

// Shared by the two streaming threads: the camera frames' (which pushes downstream) and the
// overlays'.
struct State {
  std::mutex lock;
  std::condition_variable changed;
  std::deque<GstBuffer*> overlays;  // owned, oldest first
  bool overlay_eos = false;         // no overlay will come
  bool video_eos = false;           // no camera frame will take one
  bool flushing = false;            // both pads
  bool overlay_flushing = false;
  GstVideoInfo video_info{}, overlay_info{};
  bool have_video_info = false, have_overlay_info = false;
  guint64 paired = 0, bare = 0, dropped = 0;
  bool warned_unlinked = false;  // said once that nothing is linked to overlay_sink

  void clear_overlays() {
    for (GstBuffer* b : overlays) gst_buffer_unref(b);
    overlays.clear();
  }
};

pyrocam::ChannelOrder order_of(const GstVideoInfo& info) {
  const GstVideoFormat f = GST_VIDEO_INFO_FORMAT(&info);
  return f == GST_VIDEO_FORMAT_BGRA || f == GST_VIDEO_FORMAT_BGRx ? pyrocam::ChannelOrder::kBGRA
                                                                  : pyrocam::ChannelOrder::kRGBA;
}

cv::Mat frame_mat(GstVideoFrame& frame) {
  return cv::Mat(GST_VIDEO_FRAME_HEIGHT(&frame), GST_VIDEO_FRAME_WIDTH(&frame), CV_8UC4,
                 GST_VIDEO_FRAME_PLANE_DATA(&frame, 0),
                 static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0)));
}

}  // namespace

struct _GstThermalOverlay {
  GstElement parent;
  GstPad* video_pad;
  GstPad* overlay_pad;
  GstPad* src_pad;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstThermalOverlay, gst_thermal_overlay, GST_TYPE_ELEMENT);
GST_ELEMENT_REGISTER_DEFINE(thermaloverlay, "thermaloverlay", GST_RANK_NONE,
                            GST_TYPE_THERMAL_OVERLAY);

static GstStaticPadTemplate video_template = GST_STATIC_PAD_TEMPLATE(
    "video_sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RGBA_CAPS));
static GstStaticPadTemplate overlay_template = GST_STATIC_PAD_TEMPLATE(
    "overlay_sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_OVERLAY_CAPS));
static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RGBA_CAPS));

/* Whether an overlay belongs to a camera frame at `pts`, comes before it (<0) or after (>0). */
static int compare_to_frame(GstBuffer* overlay, GstClockTime pts) {
  const GstClockTime o = GST_BUFFER_PTS(overlay);
  if (!GST_CLOCK_TIME_IS_VALID(o) || !GST_CLOCK_TIME_IS_VALID(pts) || o == pts) return 0;
  return o < pts ? -1 : 1;
}

/* Blends `overlay` (consumed) into the camera frame; false after posting an error. */
static bool blend(GstThermalOverlay* self, GstBuffer** frame, GstBuffer* overlay) {
  State& st = *self->state;
  const GstVideoInfo& vi = st.video_info;
  const GstVideoInfo& oi = st.overlay_info;
  if (!st.have_overlay_info || GST_VIDEO_INFO_WIDTH(&oi) != GST_VIDEO_INFO_WIDTH(&vi) ||
      GST_VIDEO_INFO_HEIGHT(&oi) != GST_VIDEO_INFO_HEIGHT(&vi)) {
    const std::string size = st.have_overlay_info
                                 ? std::to_string(GST_VIDEO_INFO_WIDTH(&oi)) + "x" +
                                       std::to_string(GST_VIDEO_INFO_HEIGHT(&oi))
                                 : "without caps";
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kFormat,
                       "The temperature overlay (" + size + ") does not fit the camera image (" +
                           std::to_string(GST_VIDEO_INFO_WIDTH(&vi)) + "x" +
                           std::to_string(GST_VIDEO_INFO_HEIGHT(&vi)) + ")",
                       "overlay_sink and video_sink sizes differ");
    gst_buffer_unref(overlay);
    return false;
  }
  *frame = gst_buffer_make_writable(*frame);
  GstVideoFrame image, colours;
  if (!gst_video_frame_map(&image, &st.video_info, *frame, GST_MAP_READWRITE)) {
    gst_buffer_unref(overlay);
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kFormat, "A camera frame is smaller than its caps say",
                       "video frame map failed");
    return false;
  }
  if (!gst_video_frame_map(&colours, &st.overlay_info, overlay, GST_MAP_READ)) {
    gst_video_frame_unmap(&image);
    gst_buffer_unref(overlay);
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kFormat,
                       "A temperature overlay is smaller than its caps say",
                       "overlay frame map failed");
    return false;
  }
  cv::Mat picture = frame_mat(image);
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not lay the overlay", [&] {
    pyrocam::blend_overlay(frame_mat(colours), order_of(st.overlay_info), picture,
                           order_of(st.video_info));
  });
  gst_video_frame_unmap(&colours);
  gst_video_frame_unmap(&image);
  gst_buffer_unref(overlay);
  return ok;
}

static GstFlowReturn gst_thermal_overlay_video_chain(GstPad*, GstObject* parent, GstBuffer* frame) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(parent);
  State& st = *self->state;
  const GstClockTime pts = GST_BUFFER_PTS(frame);
  GstBuffer* overlay = nullptr;
  // With nothing linked to overlay_sink no overlay can come: the frame waited for one for ever
  // (a launch line that forgot the branch prerolled for ever, without a word).
  const bool overlay_linked = gst_pad_is_linked(self->overlay_pad);
  if (!overlay_linked && !st.warned_unlinked) {
    st.warned_unlinked = true;
    GST_ELEMENT_WARNING(self, CORE, PAD,
                        ("%s: nothing is linked to overlay_sink: camera frames go out without "
                         "an overlay",
                         GST_OBJECT_NAME(self)),
                        ("overlay_sink unlinked"));
  }
  {
    std::unique_lock<std::mutex> lock(st.lock);
    if (!st.have_video_info) {
      lock.unlock();
      gst_buffer_unref(frame);
      return GST_FLOW_NOT_NEGOTIATED;
    }
    for (;;) {
      if (st.flushing) {
        lock.unlock();
        gst_buffer_unref(frame);
        return GST_FLOW_FLUSHING;
      }
      while (!st.overlays.empty() && compare_to_frame(st.overlays.front(), pts) < 0) {
        GST_DEBUG_OBJECT(self, "overlay %" GST_TIME_FORMAT " has no camera frame: dropped",
                         GST_TIME_ARGS(GST_BUFFER_PTS(st.overlays.front())));
        gst_buffer_unref(st.overlays.front());
        st.overlays.pop_front();
        ++st.dropped;
        st.changed.notify_all();
      }
      if (!st.overlays.empty()) {
        if (compare_to_frame(st.overlays.front(), pts) == 0) {
          overlay = st.overlays.front();
          st.overlays.pop_front();
          st.changed.notify_all();
        }
        break;  // else the next overlay is a later frame's: this one has none
      }
      if (st.overlay_eos || !overlay_linked) break;
      st.changed.wait(lock);
    }
    if (overlay != nullptr)
      ++st.paired;
    else
      ++st.bare;
  }
  if (overlay == nullptr)
    GST_INFO_OBJECT(self, "camera frame %" GST_TIME_FORMAT " has no overlay: sent bare",
                    GST_TIME_ARGS(pts));
  else if (!blend(self, &frame, overlay)) {
    gst_buffer_unref(frame);
    return GST_FLOW_ERROR;
  }
  return gst_pad_push(self->src_pad, frame);
}

static GstFlowReturn gst_thermal_overlay_overlay_chain(GstPad*, GstObject* parent,
                                                       GstBuffer* overlay) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(parent);
  State& st = *self->state;
  std::unique_lock<std::mutex> lock(st.lock);
  st.changed.wait(lock, [&] {
    return st.flushing || st.overlay_flushing || st.video_eos ||
           st.overlays.size() < kMaxQueuedOverlays;
  });
  const GstFlowReturn ret = st.flushing || st.overlay_flushing ? GST_FLOW_FLUSHING
                            : st.video_eos                     ? GST_FLOW_EOS
                                                               : GST_FLOW_OK;
  if (ret != GST_FLOW_OK) {
    lock.unlock();
    gst_buffer_unref(overlay);
    return ret;
  }
  st.overlays.push_back(overlay);
  st.changed.notify_all();
  return GST_FLOW_OK;
}

static bool parse_caps(GstThermalOverlay* self, GstEvent* event, GstVideoInfo* info) {
  GstCaps* caps = nullptr;
  gst_event_parse_caps(event, &caps);
  if (gst_video_info_from_caps(info, caps)) return true;
  gchar* text = gst_caps_to_string(caps);
  PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                     std::string("Caps that are no video frame: ") + text,
                     "gst_video_info_from_caps failed");
  g_free(text);
  return false;
}

static gboolean gst_thermal_overlay_video_event(GstPad* pad, GstObject* parent, GstEvent* event) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(parent);
  State& st = *self->state;
  switch (GST_EVENT_TYPE(event)) {
    case GST_EVENT_CAPS: {
      GstVideoInfo info;
      if (!parse_caps(self, event, &info)) {
        gst_event_unref(event);
        return FALSE;
      }
      std::lock_guard<std::mutex> lock(st.lock);
      st.video_info = info;
      st.have_video_info = true;
      break;
    }
    case GST_EVENT_FLUSH_START: {
      std::lock_guard<std::mutex> lock(st.lock);
      st.flushing = true;
      st.changed.notify_all();
      break;
    }
    case GST_EVENT_FLUSH_STOP: {
      std::lock_guard<std::mutex> lock(st.lock);
      st.flushing = false;
      st.video_eos = false;
      break;
    }
    case GST_EVENT_EOS: {
      std::lock_guard<std::mutex> lock(st.lock);
      st.video_eos = true;
      st.clear_overlays();
      st.changed.notify_all();
      GST_INFO_OBJECT(self,
                      "end: %" G_GUINT64_FORMAT " frames with their overlay, %" G_GUINT64_FORMAT
                      " bare, %" G_GUINT64_FORMAT " overlays without a frame",
                      st.paired, st.bare, st.dropped);
      break;
    }
    default:
      break;
  }
  return gst_pad_event_default(pad, parent, event);
}

/* The overlay stream's events stay here: the camera's stream is the one that goes on. */
static gboolean gst_thermal_overlay_overlay_event(GstPad*, GstObject* parent, GstEvent* event) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(parent);
  State& st = *self->state;
  gboolean ok = TRUE;
  switch (GST_EVENT_TYPE(event)) {
    case GST_EVENT_CAPS: {
      GstVideoInfo info;
      ok = parse_caps(self, event, &info);
      if (ok) {
        std::lock_guard<std::mutex> lock(st.lock);
        st.overlay_info = info;
        st.have_overlay_info = true;
      }
      break;
    }
    case GST_EVENT_EOS: {
      std::lock_guard<std::mutex> lock(st.lock);
      st.overlay_eos = true;
      st.changed.notify_all();
      break;
    }
    case GST_EVENT_FLUSH_START: {
      std::lock_guard<std::mutex> lock(st.lock);
      st.overlay_flushing = true;
      st.changed.notify_all();
      break;
    }
    case GST_EVENT_FLUSH_STOP: {
      std::lock_guard<std::mutex> lock(st.lock);
      st.overlay_flushing = false;
      st.overlay_eos = false;
      st.clear_overlays();
      break;
    }
    default:
      break;
  }
  gst_event_unref(event);
  return ok;
}

static gboolean gst_thermal_overlay_overlay_query(GstPad* pad, GstObject* parent, GstQuery* query) {
  switch (GST_QUERY_TYPE(query)) {
    case GST_QUERY_CAPS: {
      GstCaps* filter = nullptr;
      gst_query_parse_caps(query, &filter);
      GstCaps* caps = gst_pad_get_pad_template_caps(pad);
      if (filter != nullptr) {
        GstCaps* both = gst_caps_intersect_full(filter, caps, GST_CAPS_INTERSECT_FIRST);
        gst_caps_unref(caps);
        caps = both;
      }
      gst_query_set_caps_result(query, caps);
      gst_caps_unref(caps);
      return TRUE;
    }
    case GST_QUERY_ACCEPT_CAPS: {
      GstCaps* caps = nullptr;
      gst_query_parse_accept_caps(query, &caps);
      GstCaps* templ = gst_pad_get_pad_template_caps(pad);
      gst_query_set_accept_caps_result(query, gst_caps_is_subset(caps, templ));
      gst_caps_unref(templ);
      return TRUE;
    }
    case GST_QUERY_ALLOCATION:
      return FALSE;  // the overlay is read, never sent on: no downstream pool for it
    default:
      return gst_pad_query_default(pad, parent, query);
  }
}

static gboolean gst_thermal_overlay_src_query(GstPad* pad, GstObject* parent, GstQuery* query) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(parent);
  switch (GST_QUERY_TYPE(query)) {
    case GST_QUERY_CAPS: {
      GstCaps* filter = nullptr;
      gst_query_parse_caps(query, &filter);
      GstCaps* caps = gst_pad_peer_query_caps(self->video_pad, filter);
      GstCaps* templ = gst_pad_get_pad_template_caps(pad);
      GstCaps* both = gst_caps_intersect(caps, templ);
      gst_query_set_caps_result(query, both);
      gst_caps_unref(both);
      gst_caps_unref(templ);
      gst_caps_unref(caps);
      return TRUE;
    }
    case GST_QUERY_LATENCY: {
      if (!gst_pad_peer_query(self->video_pad, query)) return FALSE;
      gboolean live = FALSE;
      GstClockTime min = 0, max = GST_CLOCK_TIME_NONE;
      gst_query_parse_latency(query, &live, &min, &max);
      const guint64 wait = pg::locked_copy(self, self->settings->latency);
      gst_query_set_latency(query, live, min + wait,
                            GST_CLOCK_TIME_IS_VALID(max) ? max + wait : max);
      return TRUE;
    }
    default:
      return gst_pad_query_default(pad, parent, query);
  }
}

/* Events from downstream go up the camera's branch only: a seek reaches the camera through it,
 * and quality-of-service events would make the overlay branch skip frames, which then go out
 * bare; late frames are the sink's to drop. */
static gboolean gst_thermal_overlay_src_event(GstPad*, GstObject* parent, GstEvent* event) {
  return gst_pad_push_event(GST_THERMAL_OVERLAY(parent)->video_pad, event);
}

static GstStateChangeReturn gst_thermal_overlay_change_state(GstElement* element,
                                                             GstStateChange transition) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(element);
  State& st = *self->state;
  if (transition == GST_STATE_CHANGE_READY_TO_PAUSED) {
    pg::forget_posted_errors(element);
    std::lock_guard<std::mutex> lock(st.lock);
    st.clear_overlays();
    st.flushing = st.overlay_flushing = st.overlay_eos = st.video_eos = false;
    st.paired = st.bare = st.dropped = 0;
  } else if (transition == GST_STATE_CHANGE_PAUSED_TO_READY) {
    // Wakes both streaming threads before the pads are deactivated.
    std::lock_guard<std::mutex> lock(st.lock);
    st.flushing = true;
    st.changed.notify_all();
  }
  const GstStateChangeReturn ret =
      GST_ELEMENT_CLASS(gst_thermal_overlay_parent_class)->change_state(element, transition);
  if (transition == GST_STATE_CHANGE_PAUSED_TO_READY) {
    std::lock_guard<std::mutex> lock(st.lock);
    st.clear_overlays();
    st.have_video_info = st.have_overlay_info = false;
  }
  return ret;
}

static void gst_thermal_overlay_set_property(GObject* object, guint id, const GValue* value,
                                             GParamSpec* pspec) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(object);
  if (id != PROP_LATENCY) {
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, id, pspec);
    return;
  }
  {
    pg::ObjectLock lock(self);
    self->settings->latency = g_value_get_uint64(value);
  }
  gst_element_post_message(GST_ELEMENT(self), gst_message_new_latency(GST_OBJECT(self)));
}

static void gst_thermal_overlay_get_property(GObject* object, guint id, GValue* value,
                                             GParamSpec* pspec) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(object);
  if (id != PROP_LATENCY) {
    G_OBJECT_WARN_INVALID_PROPERTY_ID(object, id, pspec);
    return;
  }
  g_value_set_uint64(value, pg::locked_copy(self, self->settings->latency));
}

static void gst_thermal_overlay_finalize(GObject* object) {
  GstThermalOverlay* self = GST_THERMAL_OVERLAY(object);
  self->state->clear_overlays();
  delete self->state;
  delete self->settings;
  G_OBJECT_CLASS(gst_thermal_overlay_parent_class)->finalize(object);
}

static void gst_thermal_overlay_class_init(GstThermalOverlayClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  gobject_class->set_property = gst_thermal_overlay_set_property;
  gobject_class->get_property = gst_thermal_overlay_get_property;
  gobject_class->finalize = gst_thermal_overlay_finalize;
  element_class->change_state = gst_thermal_overlay_change_state;

  g_object_class_install_property(
      gobject_class, PROP_LATENCY,
      g_param_spec_uint64(
          "latency", "Latency",
          "Time a camera frame may wait for its temperature overlay, reported downstream as "
          "latency so that live sinks show the frames rather than drop them as late, in "
          "nanoseconds (0 to 10 s). A frame waits for its own overlay however long it takes; "
          "this only sets when a sink counts it late",
          0, MAX_LATENCY, DEFAULT_LATENCY,
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_PLAYING)));

  gst_element_class_add_static_pad_template(element_class, &video_template);
  gst_element_class_add_static_pad_template(element_class, &overlay_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);
  gst_element_class_set_static_metadata(
      element_class, "Thermal overlay", "Filter/Editor/Video",
      "Lays each frame's colour-mapped temperatures over the camera image of the same frame, "
      "waiting for them, so that no frame is shown under another frame's temperatures",
      "pyrocam");
  GST_DEBUG_CATEGORY_INIT(gst_thermal_overlay_debug, "thermaloverlay", 0,
                          "pyrocam temperature overlay on the camera image");
}

static void gst_thermal_overlay_init(GstThermalOverlay* self) {
  self->settings = new Settings();
  self->state = new State();
  self->video_pad = gst_pad_new_from_static_template(&video_template, "video_sink");
  gst_pad_set_chain_function(self->video_pad, gst_thermal_overlay_video_chain);
  gst_pad_set_event_function(self->video_pad, gst_thermal_overlay_video_event);
  GST_PAD_SET_PROXY_CAPS(self->video_pad);
  GST_PAD_SET_PROXY_ALLOCATION(self->video_pad);
  gst_element_add_pad(GST_ELEMENT(self), self->video_pad);

  self->overlay_pad = gst_pad_new_from_static_template(&overlay_template, "overlay_sink");
  gst_pad_set_chain_function(self->overlay_pad, gst_thermal_overlay_overlay_chain);
  gst_pad_set_event_function(self->overlay_pad, gst_thermal_overlay_overlay_event);
  gst_pad_set_query_function(self->overlay_pad, gst_thermal_overlay_overlay_query);
  gst_element_add_pad(GST_ELEMENT(self), self->overlay_pad);

  self->src_pad = gst_pad_new_from_static_template(&src_template, "src");
  gst_pad_set_query_function(self->src_pad, gst_thermal_overlay_src_query);
  gst_pad_set_event_function(self->src_pad, gst_thermal_overlay_src_event);
  gst_element_add_pad(GST_ELEMENT(self), self->src_pad);
}
