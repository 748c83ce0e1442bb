/* pyrocam-serve's RTSP mount points: appsrc pipelines fed by the camera pipeline's appsinks. */
#include "rtsp.h"

#include <gst/app/gstappsrc.h>
#include <gst/video/video.h>

#include <algorithm>
#include <cstring>
#include <utility>

GST_DEBUG_CATEGORY_EXTERN(pyrocam_serve_debug);
#define GST_CAT_DEFAULT pyrocam_serve_debug

/* A media factory whose shared media is keyed by the camera's run as well as the URL: after the
 * camera stops, the old media (its clients at their end of stream) is never handed to a new
 * client, who gets a fresh one fed by the camera's next run. */
struct PyrocamServeFactory {
  GstRTSPMediaFactory parent;
  guint generation;
};
struct PyrocamServeFactoryClass {
  GstRTSPMediaFactoryClass parent_class;
};
G_DEFINE_TYPE(PyrocamServeFactory, pyrocam_serve_factory, GST_TYPE_RTSP_MEDIA_FACTORY)

static gchar* pyrocam_serve_factory_gen_key(GstRTSPMediaFactory* factory, const GstRTSPUrl* url) {
  auto* self = reinterpret_cast<PyrocamServeFactory*>(factory);
  return g_strdup_printf("%s#%u", url->abspath, g_atomic_int_get(&self->generation));
}
static void pyrocam_serve_factory_class_init(PyrocamServeFactoryClass* klass) {
  GST_RTSP_MEDIA_FACTORY_CLASS(klass)->gen_key = pyrocam_serve_factory_gen_key;
}
static void pyrocam_serve_factory_init(PyrocamServeFactory* self) { self->generation = 0; }

namespace pyrocam::serve {

GstBuffer* pack_temperature_y444(const guint8* gray16, int stride, int width, int height) {
  GstVideoInfo info;
  gst_video_info_set_format(&info, GST_VIDEO_FORMAT_Y444, width, height);
  GstBuffer* out = gst_buffer_new_allocate(nullptr, GST_VIDEO_INFO_SIZE(&info), nullptr);
  GstMapInfo map;
  gst_buffer_map(out, &map, GST_MAP_WRITE);
  for (int y = 0; y < height; ++y) {
    const guint8* row = gray16 + static_cast<std::size_t>(y) * stride;
    guint8* yp = map.data + GST_VIDEO_INFO_PLANE_OFFSET(&info, 0) +
                 static_cast<std::size_t>(y) * GST_VIDEO_INFO_PLANE_STRIDE(&info, 0);
    guint8* up = map.data + GST_VIDEO_INFO_PLANE_OFFSET(&info, 1) +
                 static_cast<std::size_t>(y) * GST_VIDEO_INFO_PLANE_STRIDE(&info, 1);
    guint8* vp = map.data + GST_VIDEO_INFO_PLANE_OFFSET(&info, 2) +
                 static_cast<std::size_t>(y) * GST_VIDEO_INFO_PLANE_STRIDE(&info, 2);
    for (int x = 0; x < width; ++x) {
      yp[x] = row[2 * x + 1];  // little-endian: the high byte second
      up[x] = row[2 * x];
    }
    std::memset(vp, 128, static_cast<std::size_t>(width));
  }
  gst_buffer_unmap(out, &map);
  return out;
}

namespace {

std::string mount_launch(const RtspConfig& c, bool temperature) {
  // do-timestamp: the buffers come without timestamps and get this pipeline's running time.
  // leaky-type=downstream: a stalled encoder drops old frames, never holds the camera.
  std::string launch =
      "( appsrc name=src is-live=true format=time do-timestamp=true max-buffers=3 "
      "leaky-type=downstream ! queue max-size-buffers=3 leaky=downstream ! ";
  const std::string key = " key-int-max=" + std::to_string(c.key_frames);
  if (temperature)
    // Quantiser 0 with 4:4:4 input is x264's lossless mode (High 4:4:4 Predictive). One
    // thread, so one slice per frame: with zerolatency's sliced threads (a slice per thread)
    // ffmpeg, and avdec_h264 reading a stored copy, decoded codes the camera never sent.
    // The profile said, not left to negotiation: x264 otherwise tries baseline first and logs
    // "baseline profile doesn't support lossless" for every client.
    launch += "x264enc tune=zerolatency speed-preset=ultrafast pass=quant quantizer=0 threads=1" +
              key + " ! video/x-h264,profile=high-4:4:4";
  else
    launch +=
        "videoconvert ! video/x-raw,format=I420 ! x264enc tune=zerolatency "
        "speed-preset=ultrafast bitrate=" +
        std::to_string(c.bitrate_kbit) + key;
  // SPS/PPS with every key frame, so that a client can join at any time.
  return launch + " ! rtph264pay name=pay0 pt=96 config-interval=-1 )";
}

}  // namespace

RtspOut::RtspOut(RtspConfig config) : config_(std::move(config)) {}

RtspOut::~RtspOut() {
  if (source_ != 0) g_source_remove(source_);
  std::vector<Feed> feeds;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    feeds.swap(feeds_);
  }
  for (Feed& f : feeds) gst_object_unref(f.appsrc);
  if (server_ != nullptr) g_object_unref(server_);
}

bool RtspOut::start(std::string& error) {
  server_ = gst_rtsp_server_new();
  gst_rtsp_server_set_address(server_, config_.address.c_str());
  gst_rtsp_server_set_service(server_, std::to_string(config_.port).c_str());
  GstRTSPMountPoints* mounts = gst_rtsp_server_get_mount_points(server_);
  for (bool temperature : {false, true}) {
    auto* factory =
        static_cast<GstRTSPMediaFactory*>(g_object_new(pyrocam_serve_factory_get_type(), nullptr));
    gst_rtsp_media_factory_set_launch(factory, mount_launch(config_, temperature).c_str());
    gst_rtsp_media_factory_set_shared(factory, TRUE);
    g_object_set_data(G_OBJECT(factory), "pyrocam-temperature", GINT_TO_POINTER(temperature));
    g_signal_connect(factory, "media-configure", G_CALLBACK(on_media_configure), this);
    factories_.push_back(factory);
    gst_rtsp_mount_points_add_factory(mounts, temperature ? "/temperature" : "/thermal",
                                      factory);  // takes the reference
  }
  g_object_unref(mounts);

  // A client over TCP that reads slower than the stream comes gets its packets held, not
  // dropped: a dropped packet of the lossless stream would decode to wrong temperatures until
  // the next key frame. The encoders' input queues drop whole frames instead.
  g_signal_connect(server_, "client-connected",
                   G_CALLBACK(+[](GstRTSPServer*, GstRTSPClient* client, gpointer) {
                     g_object_set(client, "drop-backlog", FALSE, nullptr);
                   }),
                   nullptr);
  GError* err = nullptr;
  GSource* source = gst_rtsp_server_create_source(server_, nullptr, &err);
  if (source == nullptr) {
    error = err != nullptr ? err->message : "unknown error";
    if (err != nullptr) g_error_free(err);
    return false;
  }
  source_ = g_source_attach(source, nullptr);
  g_source_unref(source);
  bound_port_ = gst_rtsp_server_get_bound_port(server_);
  return true;
}

void RtspOut::on_media_configure(GstRTSPMediaFactory* factory, GstRTSPMedia* media, gpointer data) {
  auto* self = static_cast<RtspOut*>(data);
  const bool temperature =
      GPOINTER_TO_INT(g_object_get_data(G_OBJECT(factory), "pyrocam-temperature")) != 0;
  GstElement* bin = gst_rtsp_media_get_element(media);
  GstElement* appsrc = gst_bin_get_by_name(GST_BIN(bin), "src");
  gst_object_unref(bin);
  if (appsrc == nullptr) return;
  g_signal_connect(media, "unprepared", G_CALLBACK(on_media_unprepared), self);
  std::lock_guard<std::mutex> lock(self->mutex_);
  self->feeds_.push_back(Feed{media, appsrc, temperature});
  GST_INFO("new %s media %p", temperature ? "temperature" : "thermal", static_cast<void*>(media));
}

void RtspOut::on_media_unprepared(GstRTSPMedia* media, gpointer data) {
  auto* self = static_cast<RtspOut*>(data);
  std::lock_guard<std::mutex> lock(self->mutex_);
  auto gone = std::remove_if(self->feeds_.begin(), self->feeds_.end(), [&](const Feed& f) {
    if (f.media != media) return false;
    gst_object_unref(f.appsrc);
    return true;
  });
  self->feeds_.erase(gone, self->feeds_.end());
}

void RtspOut::push_overlay(GstSample* sample) { push(sample, false); }
void RtspOut::push_temperature(GstSample* sample) { push(sample, true); }

void RtspOut::push(GstSample* sample, bool temperature) {
  std::vector<GstElement*> targets;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const Feed& f : feeds_)
      if (f.temperature == temperature) targets.push_back(GST_ELEMENT(gst_object_ref(f.appsrc)));
  }
  if (targets.empty()) return;
  GstBuffer* in = gst_sample_get_buffer(sample);
  GstCaps* in_caps = gst_sample_get_caps(sample);
  GstVideoInfo info;
  GstBuffer* out = nullptr;
  GstCaps* caps = nullptr;
  if (in != nullptr && in_caps != nullptr && gst_video_info_from_caps(&info, in_caps)) {
    if (!temperature) {
      // Memory only: no timestamps, so that the appsrc gives its own (do-timestamp).
      out = gst_buffer_copy_region(in, GST_BUFFER_COPY_MEMORY, 0, static_cast<gsize>(-1));
      caps = gst_caps_ref(in_caps);
    } else if (GST_VIDEO_INFO_FORMAT(&info) == GST_VIDEO_FORMAT_GRAY16_LE) {
      GstVideoFrame frame;
      if (gst_video_frame_map(&frame, &info, in, GST_MAP_READ)) {
        out =
            pack_temperature_y444(static_cast<const guint8*>(GST_VIDEO_FRAME_PLANE_DATA(&frame, 0)),
                                  GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0), info.width, info.height);
        gst_video_frame_unmap(&frame);
        caps = gst_caps_new_simple("video/x-raw", "format", G_TYPE_STRING, "Y444", "width",
                                   G_TYPE_INT, info.width, "height", G_TYPE_INT, info.height,
                                   "framerate", GST_TYPE_FRACTION, info.fps_n, info.fps_d,
                                   "pixel-aspect-ratio", GST_TYPE_FRACTION, 1, 1, nullptr);
      }
    }
  }
  for (GstElement* target : targets) {
    if (out != nullptr) {
      GstCaps* current = gst_app_src_get_caps(GST_APP_SRC(target));
      if (current == nullptr || !gst_caps_is_equal(current, caps))
        gst_app_src_set_caps(GST_APP_SRC(target), caps);
      if (current != nullptr) gst_caps_unref(current);
      gst_app_src_push_buffer(GST_APP_SRC(target), gst_buffer_ref(out));
    }
    gst_object_unref(target);
  }
  if (out != nullptr) gst_buffer_unref(out);
  if (caps != nullptr) gst_caps_unref(caps);
}

void RtspOut::camera_lost() {
  for (GstRTSPMediaFactory* f : factories_)
    g_atomic_int_inc(&reinterpret_cast<PyrocamServeFactory*>(f)->generation);
  std::vector<Feed> stale;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stale.swap(feeds_);
  }
  for (Feed& f : stale) {
    gst_app_src_end_of_stream(GST_APP_SRC(f.appsrc));
    gst_object_unref(f.appsrc);
  }
}

}  // namespace pyrocam::serve
