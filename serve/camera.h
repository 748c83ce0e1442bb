// The camera pipeline of pyrocam-serve: one camera and one thermal chain (as
// pipelines/lib/camera.sh) whose outputs fan out to the RTSP mount points and the web page. It
// restarts itself with back-off when the camera ends or fails, so that the server outlives it.
#pragma once

#include <gst/gst.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace pyrocam::serve {

struct CameraConfig {
  std::string camera = "pyrocamsrc is-live=true scene=melt-pool";
  std::string caps = "video/x-bayer,width=320,height=240,framerate=30/1";
  std::string dark = "dark-level=50";
  bool exposure_control = false;  // autoexposure after the camera
  std::string model;
  std::string profile;
  std::string region;
  bool region_tracks_peak = false;  // ratiotemp region-tracks-peak
  int peak_window = 5;
  int stats_interval_ms = 500;
  int watchdog_ms = 5000;
  int latency_ms = 100;
  int jpeg_fps = 5;
  // thermalalarm's properties, "name=value" each; empty: no alarm element.
  std::vector<std::string> alarm;
  // A snapshot (5x5) camera's frame size from its caps: the temperatures (one per macro-pixel)
  // are scaled up to it by nearest neighbour under the overlay. 0: not known (a Bayer camera's
  // temperatures have the frame's size).
  int sensor_width = 0, sensor_height = 0;
};

// The gst-launch description of the camera pipeline (also printed with --print-pipeline).
std::string camera_description(const CameraConfig& config);

class Camera {
 public:
  struct Callbacks {
    // Streaming threads: an RGBA overlay frame, a GRAY16_LE temperature frame (0.1 K).
    std::function<void(GstSample*)> on_overlay;
    std::function<void(GstSample*)> on_temperature;
    // Main context: ratiotemp's statistics and thermalalarm's messages.
    std::function<void(const GstStructure*)> on_message;
    // Main context: the camera stopped (EOS or error); `fatal` when the thermal chain failed
    // before the first frame ever (a bad model or settings: the server exits). A camera that
    // fails or is silent is retried, also at the start.
    std::function<void(const std::string& why, bool fatal)> on_lost;
    // Main context: the first frame after a (re)start.
    std::function<void()> on_running;
    // Main context: a warning an element posted (a dark that is not the camera's, a model
    // whose network reads hotter surfaces inside its range, ...): the element's name and text.
    std::function<void(const std::string& source, const std::string& text)> on_warning;
  };

  Camera(CameraConfig config, Callbacks callbacks);
  ~Camera();
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  // Builds and starts the pipeline; false with `error` set when the description does not parse.
  bool start(std::string& error);
  void stop();

  // The latest JPEG of the overlay and its sequence number (0: none yet).
  std::shared_ptr<const std::vector<std::uint8_t>> latest_jpeg(std::uint64_t& seq) const;
  bool running() const;

 private:
  static gboolean on_bus(GstBus* bus, GstMessage* message, gpointer self);
  static gboolean on_retry(gpointer self);
  static gboolean on_first_frame(gpointer self);
  void lost(const std::string& why);
  void store_jpeg(GstSample* sample);

  CameraConfig config_;
  Callbacks callbacks_;
  GstElement* pipeline_ = nullptr;
  guint bus_watch_ = 0;
  guint retry_source_ = 0;
  int retry_ms_ = 1000;
  bool ever_ran_ = false;
  bool chain_error_ = false;  // the last error came from the thermal chain, not the camera
  std::function<void(GstSample*)> jpeg_handler_;

  mutable std::mutex mutex_;  // guards the fields below (streaming threads write them)
  std::shared_ptr<const std::vector<std::uint8_t>> jpeg_;
  std::uint64_t jpeg_seq_ = 0;
  bool frame_seen_ = false;
};

}  // namespace pyrocam::serve
