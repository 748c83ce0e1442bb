// The pipelines that bench_chain times: an appsrc chain on one repeated frame, and the soak on
// the simulated camera's ever new frames.
#pragma once

#include <gst/app/gstappsrc.h>
#include <gst/gst.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <opencv2/core.hpp>
#include <string>
#include <thread>
#include <vector>

namespace pyrocam::bench {

using Clock = std::chrono::steady_clock;

// kB from /proc/self/status ("VmRSS", "VmHWM").
inline long status_kb(const char* key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::size_t n = std::strlen(key);
  while (std::getline(in, line))
    if (line.compare(0, n, key) == 0 && line.size() > n && line[n] == ':')
      return std::atol(line.c_str() + n + 1);
  return -1;
}

struct Run {
  bool ok = false;
  std::string error;
  int frames = 0;            // frames timed (after the warm-up)
  double fps = 0;            // over the timed frames
  double first_frame_s = 0;  // from PLAYING to the first frame at the sink
  double cpu_ms = 0;         // process CPU time per timed frame (all threads)
  long rss_warm_kb = 0, rss_end_kb = 0;
};

// Process CPU time (user + system), s.
inline double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Handoffs {
  std::vector<Clock::time_point> at;
  std::vector<double> cpu;
  std::size_t warmup = 0;
  long rss_warm_kb = 0;  // when the last warm-up frame reached the sink
};

inline void on_handoff(GstElement*, GstBuffer*, GstPad*, gpointer data) {
  auto* h = static_cast<Handoffs*>(data);
  h->at.push_back(Clock::now());
  h->cpu.push_back(cpu_seconds());
  if (h->at.size() == h->warmup + 1) h->rss_warm_kb = status_kb("VmRSS");
}

// Pushes `frames` timestamped references to `raw` through `chain` (a launch fragment between
// appsrc and fakesink) and times the frames after `warmup`.
inline Run run_chain(const std::string& chain, const std::string& caps, const cv::Mat& raw,
                     int frames, int warmup) {
  Run r;
  const std::string launch = "appsrc name=src format=time is-live=false block=true ! " + chain +
                             " ! fakesink name=sink sync=false signal-handoffs=true";
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(launch.c_str(), &error);
  if (!pipeline || error) {
    r.error = error ? error->message : "could not build the pipeline";
    if (error) g_error_free(error);
    if (pipeline) gst_object_unref(pipeline);
    return r;
  }
  GstElement* src = gst_bin_get_by_name(GST_BIN(pipeline), "src");
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  GstCaps* src_caps = gst_caps_from_string(caps.c_str());
  const guint64 frame_bytes = static_cast<guint64>(raw.total() * raw.elemSize());
  g_object_set(src, "caps", src_caps, "max-bytes", 2 * frame_bytes, nullptr);
  gst_caps_unref(src_caps);
  Handoffs handoffs;
  handoffs.at.reserve(static_cast<std::size_t>(frames) + 1);
  handoffs.cpu.reserve(static_cast<std::size_t>(frames) + 1);
  handoffs.warmup = static_cast<std::size_t>(warmup);
  g_signal_connect(sink, "handoff", G_CALLBACK(on_handoff), &handoffs);

  // One buffer wrapping the frame; each push is a metadata copy sharing its memory.
  GstBuffer* frame = gst_buffer_new_wrapped_full(GST_MEMORY_FLAG_READONLY, raw.data, frame_bytes, 0,
                                                 frame_bytes, nullptr, nullptr);
  const GstClockTime duration = GST_SECOND / 30;
  const auto started = Clock::now();
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  // Pushing blocks while appsrc holds two frames: from a thread of its own, so that an error
  // (which stops the stream) cannot leave this one waiting.
  std::thread pusher([&] {
    for (int i = 0; i < frames; ++i) {
      GstBuffer* b = gst_buffer_copy(frame);
      GST_BUFFER_PTS(b) = static_cast<GstClockTime>(i) * duration;
      GST_BUFFER_DURATION(b) = duration;
      if (gst_app_src_push_buffer(GST_APP_SRC(src), b) != GST_FLOW_OK) return;
    }
    gst_app_src_end_of_stream(GST_APP_SRC(src));
  });
  GstBus* bus = gst_element_get_bus(pipeline);
  GstMessage* m = gst_bus_timed_pop_filtered(
      bus, GST_CLOCK_TIME_NONE, static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  if (m && GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
    GError* e = nullptr;
    gst_message_parse_error(m, &e, nullptr);
    r.error = e ? e->message : "error";
    if (e) g_error_free(e);
    gst_element_set_state(pipeline, GST_STATE_NULL);  // unblocks the pusher
  }
  if (m) gst_message_unref(m);
  pusher.join();
  r.rss_end_kb = status_kb("VmRSS");
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_buffer_unref(frame);
  gst_object_unref(src);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  if (!r.error.empty()) return r;
  const int got = static_cast<int>(handoffs.at.size());
  if (got < 2) {
    r.error = "fewer than two frames reached the sink";
    return r;
  }
  r.first_frame_s = std::chrono::duration<double>(handoffs.at.front() - started).count();
  const int first = std::min(warmup, got - 2);
  r.frames = got - 1 - first;
  const auto f = static_cast<std::size_t>(first);
  r.fps = r.frames / std::chrono::duration<double>(handoffs.at.back() - handoffs.at[f]).count();
  r.cpu_ms = 1e3 * (handoffs.cpu.back() - handoffs.cpu[f]) / r.frames;
  r.rss_warm_kb = handoffs.rss_warm_kb ? handoffs.rss_warm_kb : r.rss_end_kb;
  r.ok = true;
  return r;
}

// The soak: resident memory at checkpoints (1, 2, 5 x 10^k frames from 1000 on, and the last),
// and its growth from `baseline` (a frame past the warm-up) to the last frame.
struct Soak {
  int frames = 0, baseline = 0;
  int count = 0;
  long rss_baseline_kb = 0, rss_last_kb = 0;
  Clock::time_point started;
  double cpu_started = 0;
};

inline bool soak_checkpoint(int frame, int last, int baseline) {
  if (frame == last || frame == baseline) return true;
  for (int decade = 1000; decade > 0 && decade <= frame; decade *= 10)
    if (frame == decade || frame == 2 * decade || frame == 5 * decade) return true;
  return false;
}

inline void on_soak_handoff(GstElement*, GstBuffer*, GstPad*, gpointer data) {
  auto* s = static_cast<Soak*>(data);
  if (!soak_checkpoint(++s->count, s->frames, s->baseline)) return;
  const long rss = status_kb("VmRSS");
  if (s->count == s->baseline) s->rss_baseline_kb = rss;
  s->rss_last_kb = rss;
  const double wall = std::chrono::duration<double>(Clock::now() - s->started).count();
  std::printf(
      "  frame %7d: resident %6.1f MB (peak %6.1f MB), %6.0f s, %6.1f frames/s, %.2f CPU "
      "ms/frame\n",
      s->count, rss / 1024.0, status_kb("VmHWM") / 1024.0, wall, s->count / wall,
      1e3 * (cpu_seconds() - s->cpu_started) / s->count);
  std::fflush(stdout);
}

// Runs `launch` (ending in a fakesink named sink) for its `frames` frames; 0 if all arrived.
inline int run_soak(const std::string& what, const std::string& launch, int frames) {
  std::printf("\nsoak, %s: %s\n", what.c_str(), launch.c_str());
  const long rss_start_kb = status_kb("VmRSS");
  std::printf("  start:         resident %6.1f MB\n", rss_start_kb / 1024.0);
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(launch.c_str(), &error);
  if (!pipeline || error) {
    std::fprintf(stderr, "soak: %s\n", error ? error->message : "could not build the pipeline");
    if (error) g_error_free(error);
    if (pipeline) gst_object_unref(pipeline);
    return 1;
  }
  Soak soak;
  soak.frames = frames;
  // Growth is measured from frame 1000 (the lookup table's first fill is over by then), or from
  // a tenth of a shorter run.
  soak.baseline = std::max(1, std::min(1000, frames / 10));
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_signal_connect(sink, "handoff", G_CALLBACK(on_soak_handoff), &soak);
  soak.started = Clock::now();
  soak.cpu_started = cpu_seconds();
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstBus* bus = gst_element_get_bus(pipeline);
  GstMessage* m = gst_bus_timed_pop_filtered(
      bus, GST_CLOCK_TIME_NONE, static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  int rc = 0;
  if (m && GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR) {
    GError* e = nullptr;
    gst_message_parse_error(m, &e, nullptr);
    std::fprintf(stderr, "soak: %s\n", e ? e->message : "error");
    if (e) g_error_free(e);
    rc = 1;
  }
  if (m) gst_message_unref(m);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  if (rc == 0 && soak.count != frames) {
    std::fprintf(stderr, "soak: %d frames of %d reached the sink\n", soak.count, frames);
    rc = 1;
  }
  if (rc == 0)
    std::printf("  growth: %+.1f MB from frame %d to frame %d, %+.1f MB from the start\n",
                (soak.rss_last_kb - soak.rss_baseline_kb) / 1024.0, soak.baseline, frames,
                (soak.rss_last_kb - rss_start_kb) / 1024.0);
  std::fflush(stdout);
  return rc;
}

}  // namespace pyrocam::bench
