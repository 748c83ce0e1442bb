/* pyrocam-serve's camera pipeline: parse, start, fan out, restart with back-off. */
#include "camera.h"

#include <gst/app/gstappsink.h>

#include <algorithm>
#include <utility>

GST_DEBUG_CATEGORY_EXTERN(pyrocam_serve_debug);
#define GST_CAT_DEFAULT pyrocam_serve_debug

namespace pyrocam::serve {
namespace {

constexpr int kMaxRetryMs = 10000;

std::string quoted(const std::string& value) {
  std::string out = "\"";
  for (char c : value) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

GstFlowReturn on_sample(GstAppSink* sink, gpointer data) {
  auto* handler = static_cast<std::function<void(GstSample*)>*>(data);
  GstSample* sample = gst_app_sink_pull_sample(sink);
  if (sample == nullptr) return GST_FLOW_EOS;
  if (*handler) (*handler)(sample);
  gst_sample_unref(sample);
  return GST_FLOW_OK;
}

}  // namespace

std::string camera_description(const CameraConfig& c) {
  const bool bayer = c.caps.rfind("video/x-bayer", 0) == 0;
  std::string ratiotemp = "ratiotemp model=" + quoted(c.model) +
                          " stats-interval=" + std::to_string(c.stats_interval_ms * 1000000LL) +
                          " peak-window=" + std::to_string(c.peak_window);
  if (!c.region.empty()) ratiotemp += " region=" + quoted(c.region);
  if (c.region_tracks_peak) ratiotemp += " region-tracks-peak=true";
  if (!c.profile.empty()) ratiotemp += " profile=" + quoted(c.profile);
  std::string alarm;
  if (!c.alarm.empty()) {
    alarm = " ! thermalalarm name=alarm";
    for (const std::string& p : c.alarm) alarm += " " + p;
  }
  // autoexposure measures raw levels above darksub's dark level, where --dark gives one.
  std::string exposure;
  if (c.exposure_control) {
    exposure = " ! autoexposure";
    if (c.dark.rfind("dark-level=", 0) == 0) exposure += " " + c.dark;
  }
  // Queues that drop rather than wait: a slow consumer (encoder, JPEG) never holds the camera.
  const std::string leaky =
      "queue leaky=downstream max-size-buffers=2 max-size-time=0 "
      "max-size-bytes=0";
  const std::string sink = " sync=false max-buffers=2 drop=true";
  // A 5x5 camera's temperatures, one per macro-pixel, drawn as 5x5 blocks over its frame.
  const std::string to_sensor_size =
      bayer || c.sensor_width <= 0 || c.sensor_height <= 0
          ? std::string()
          : "videoscale method=nearest-neighbour ! video/x-raw,width=" +
                std::to_string(c.sensor_width) + ",height=" + std::to_string(c.sensor_height) +
                " ! ";
  return c.camera + " ! " + c.caps + exposure +
         " ! watchdog name=camera-sent-no-frame timeout=" + std::to_string(c.watchdog_ms) +
         " ! tee name=camera " + "camera. ! queue ! darksub " + c.dark + " ! demosaic25 ! " +
         ratiotemp + alarm +
         " ! tee name=temperature "
         "temperature. ! " +
         leaky + " ! appsink name=temperature-sink" + sink + " temperature. ! queue ! " +
         to_sensor_size +
         "thermalcolormap scale-bar=true ! video/x-raw,format=RGBA ! "
         "mix.overlay_sink "
         "camera. ! queue ! " +
         (bayer ? "bayer2rgb" : "videoconvert") +
         " ! video/x-raw,format=RGBA ! mix.video_sink "
         "thermaloverlay name=mix latency=" +
         std::to_string(c.latency_ms * 1000000LL) +
         " ! video/x-raw,format=RGBA ! queue ! tee name=overlay "
         "overlay. ! " +
         leaky + " ! appsink name=overlay-sink" + sink + " overlay. ! " + leaky +
         " ! videorate drop-only=true max-rate=" + std::to_string(std::max(1, c.jpeg_fps)) +
         " ! videoconvert ! jpegenc quality=85 ! appsink name=jpeg-sink" + sink;
}

Camera::Camera(CameraConfig config, Callbacks callbacks)
    : config_(std::move(config)), callbacks_(std::move(callbacks)) {}

Camera::~Camera() {
  stop();
  if (retry_source_ != 0) g_source_remove(retry_source_);
}

bool Camera::start(std::string& error) {
  retry_source_ = 0;
  GError* err = nullptr;
  const std::string description = camera_description(config_);
  GST_INFO("camera pipeline: %s", description.c_str());
  GstElement* pipeline =
      gst_parse_launch_full(description.c_str(), nullptr, GST_PARSE_FLAG_FATAL_ERRORS, &err);
  if (pipeline == nullptr || err != nullptr) {
    error = err != nullptr ? err->message : "unknown parse error";
    if (err != nullptr) g_error_free(err);
    if (pipeline != nullptr) gst_object_unref(pipeline);
    return false;
  }
  pipeline_ = pipeline;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    frame_seen_ = false;
  }
  struct Hook {
    const char* name;
    std::function<void(GstSample*)>* handler;
  };
  jpeg_handler_ = [this](GstSample* s) { store_jpeg(s); };
  for (const Hook& h :
       {Hook{"temperature-sink", &callbacks_.on_temperature},
        Hook{"overlay-sink", &callbacks_.on_overlay}, Hook{"jpeg-sink", &jpeg_handler_}}) {
    GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline_), h.name);
    GstAppSinkCallbacks cb = {};
    cb.new_sample = on_sample;
    gst_app_sink_set_callbacks(GST_APP_SINK(sink), &cb, h.handler, nullptr);
    gst_object_unref(sink);
  }
  GstBus* bus = gst_element_get_bus(pipeline_);
  bus_watch_ = gst_bus_add_watch(bus, on_bus, this);
  gst_object_unref(bus);
  // From another thread: loading the model can take seconds, and the page and RTSP server live
  // on this thread. A failure comes as an error message on the bus.
  gst_element_call_async(
      pipeline_,
      [](GstElement* element, gpointer) { gst_element_set_state(element, GST_STATE_PLAYING); },
      nullptr, nullptr);
  return true;
}

void Camera::stop() {
  if (pipeline_ == nullptr) return;
  if (bus_watch_ != 0) g_source_remove(bus_watch_);
  bus_watch_ = 0;
  gst_element_set_state(pipeline_, GST_STATE_NULL);
  gst_object_unref(pipeline_);
  pipeline_ = nullptr;
}

bool Camera::running() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pipeline_ != nullptr && frame_seen_;
}

std::shared_ptr<const std::vector<std::uint8_t>> Camera::latest_jpeg(std::uint64_t& seq) const {
  std::lock_guard<std::mutex> lock(mutex_);
  seq = jpeg_seq_;
  return jpeg_;
}

void Camera::store_jpeg(GstSample* sample) {
  GstBuffer* buffer = gst_sample_get_buffer(sample);
  GstMapInfo map;
  if (buffer == nullptr || !gst_buffer_map(buffer, &map, GST_MAP_READ)) return;
  auto jpeg = std::make_shared<const std::vector<std::uint8_t>>(map.data, map.data + map.size);
  gst_buffer_unmap(buffer, &map);
  bool first = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jpeg_ = std::move(jpeg);
    ++jpeg_seq_;
    first = !frame_seen_;
    frame_seen_ = true;
  }
  if (first) g_idle_add(on_first_frame, this);
}

gboolean Camera::on_first_frame(gpointer data) {
  auto* self = static_cast<Camera*>(data);
  self->ever_ran_ = true;
  self->retry_ms_ = 1000;
  if (self->callbacks_.on_running) self->callbacks_.on_running();
  return G_SOURCE_REMOVE;
}

gboolean Camera::on_bus(GstBus*, GstMessage* message, gpointer data) {
  auto* self = static_cast<Camera*>(data);
  switch (GST_MESSAGE_TYPE(message)) {
    case GST_MESSAGE_ERROR: {
      GError* err = nullptr;
      gchar* debug = nullptr;
      gst_message_parse_error(message, &err, &debug);
      std::string why = std::string(GST_OBJECT_NAME(GST_MESSAGE_SRC(message))) + ": " +
                        (err != nullptr ? err->message : "error");
      // The chain's own elements fail on the model or the settings, which a restart does not
      // mend; the camera (or the watchdog) may come back.
      if (GST_IS_ELEMENT(GST_MESSAGE_SRC(message))) {
        GstElementFactory* f = gst_element_get_factory(GST_ELEMENT(GST_MESSAGE_SRC(message)));
        const std::string kind = f != nullptr ? GST_OBJECT_NAME(f) : "";
        self->chain_error_ = kind == "darksub" || kind == "demosaic25" || kind == "ratiotemp" ||
                             kind == "thermalalarm" || kind == "thermalcolormap";
      }
      // Nor caps or settings the camera refuses (a size that is no whole number of mosaic
      // periods): a camera that is away fails otherwise.
      if (err != nullptr && (g_error_matches(err, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION) ||
                             g_error_matches(err, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT) ||
                             g_error_matches(err, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS)))
        self->chain_error_ = true;
      GST_WARNING("camera pipeline error: %s (%s)", why.c_str(), debug != nullptr ? debug : "");
      if (err != nullptr) g_error_free(err);
      g_free(debug);
      self->lost(why);
      return G_SOURCE_REMOVE;
    }
    case GST_MESSAGE_WARNING: {
      GError* err = nullptr;
      gst_message_parse_warning(message, &err, nullptr);
      if (self->callbacks_.on_warning)
        self->callbacks_.on_warning(GST_OBJECT_NAME(GST_MESSAGE_SRC(message)),
                                    err != nullptr ? err->message : "warning");
      if (err != nullptr) g_error_free(err);
      break;
    }
    case GST_MESSAGE_EOS:
      self->lost("the camera ended its stream");
      return G_SOURCE_REMOVE;
    case GST_MESSAGE_ELEMENT: {
      const GstStructure* s = gst_message_get_structure(message);
      if (s != nullptr && self->callbacks_.on_message) self->callbacks_.on_message(s);
      break;
    }
    default:
      break;
  }
  return G_SOURCE_CONTINUE;
}

void Camera::lost(const std::string& why) {
  bus_watch_ = 0;  // the watch ends with this message (the caller returns G_SOURCE_REMOVE)
  if (pipeline_ != nullptr) {
    gst_element_set_state(pipeline_, GST_STATE_NULL);
    gst_object_unref(pipeline_);
    pipeline_ = nullptr;
  }
  bool seen = false;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    seen = frame_seen_;
    frame_seen_ = false;
    // The last image is not the camera's now: /frame.jpg says so instead of serving it as live.
    jpeg_.reset();
    ++jpeg_seq_;
  }
  const bool fatal = !ever_ran_ && !seen && chain_error_;
  chain_error_ = false;
  if (callbacks_.on_lost) callbacks_.on_lost(why, fatal);
  if (fatal) return;
  GST_INFO("camera restart in %d ms", retry_ms_);
  retry_source_ = g_timeout_add(retry_ms_, on_retry, this);
  retry_ms_ = std::min(retry_ms_ * 2, kMaxRetryMs);
}

gboolean Camera::on_retry(gpointer data) {
  auto* self = static_cast<Camera*>(data);
  std::string error;
  if (!self->start(error)) self->lost(error);
  return G_SOURCE_REMOVE;
}

}  // namespace pyrocam::serve
