// pyrocam-serve's RTSP side: two shared mount points fed from the one camera pipeline.
//   /thermal      the colour-mapped overlay, H.264 (x264enc tune=zerolatency)
//   /temperature  the 0.1 K codes, lossless H.264 4:4:4 (quantiser 0): the high byte in Y, the
//                 low byte in U, V = 128, so that any H.264 decoder gives them back exactly.
#pragma once

#include <gst/gst.h>
#include <gst/rtsp-server/rtsp-server.h>

#include <mutex>
#include <string>
#include <vector>

namespace pyrocam::serve {

struct RtspConfig {
  std::string address = "0.0.0.0";
  int port = 8554;
  int bitrate_kbit = 2000;
  int key_frames = 30;  // frames between key frames: how long a joining client waits
};

// Packs GRAY16_LE codes into a Y444 frame (Y = high byte, U = low byte, V = 128); `stride` in
// bytes of the source rows. Returns the frame in GstVideoInfo's Y444 layout for width x height.
GstBuffer* pack_temperature_y444(const guint8* gray16, int stride, int width, int height);

class RtspOut {
 public:
  explicit RtspOut(RtspConfig config);
  ~RtspOut();
  RtspOut(const RtspOut&) = delete;
  RtspOut& operator=(const RtspOut&) = delete;

  // Binds the port and attaches to the default main context; false with `error` set.
  bool start(std::string& error);
  int bound_port() const { return bound_port_; }

  // Streaming threads: a frame from the camera to every client of the mount point.
  void push_overlay(GstSample* sample);
  void push_temperature(GstSample* sample);
  // Main context: the camera stopped. Its clients get an end of stream; the next client gets a
  // fresh media, fed when the camera returns.
  void camera_lost();

 private:
  struct Feed {
    GstRTSPMedia* media;
    GstElement* appsrc;
    bool temperature;
  };
  static void on_media_configure(GstRTSPMediaFactory* factory, GstRTSPMedia* media, gpointer self);
  static void on_media_unprepared(GstRTSPMedia* media, gpointer self);
  void push(GstSample* sample, bool temperature);

  RtspConfig config_;
  GstRTSPServer* server_ = nullptr;
  guint source_ = 0;
  std::vector<GstRTSPMediaFactory*> factories_;  // owned by the mount points
  int bound_port_ = 0;
  std::mutex mutex_;  // guards feeds_
  std::vector<Feed> feeds_;
};

}  // namespace pyrocam::serve
