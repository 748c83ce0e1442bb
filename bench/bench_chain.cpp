// Frames per second of the element chains at camera sizes, and of bayer2rgb alone on the same
// input in the same run (the ceiling of a plain debayer):
//   colour: appsrc (8-bit RGGB, 2048x2048) ! darksub ! demosaic25 ! ratiotemp ! fakesink
//   5x5:    appsrc (GRAY8 5x5 mosaic, 2045x1085: the whole 5x5 periods of a 2048x1088 sensor,
//           409x217 macro-pixels; darksub takes only whole periods) ! darksub ! demosaic25 !
//           ratiotemp ! fakesink
// appsrc pushes one pre-rendered simulated frame again and again (shared memory, new timestamps),
// so the source costs nothing. The rate counts the frames reaching fakesink after a warm-up (the
// first frames fill the lookup table); the peak resident memory and its growth between the end
// of the warm-up and the end of the run are printed too. Wall-clock figures: run on a quiet
// machine. Not a test.
//
// Soak mode (--soak N): the resident memory of the colour chain with the lookup table over N
// frames of the simulated camera, whose frames all differ (a moving melt pool, new noise):
//   pyrocamsrc scene=melt-pool (8-bit RGGB, 320x240 or --soak-size) ! darksub ! demosaic25 !
//   ratiotemp method=lut ! fakesink
// printing the resident memory at frames 1k, 2k, 5k, 10k, 20k, 50k, 100k, ... and at the last.
//
// Usage: bench_chain --rgb-model M.json --nir-model N.json [--frames N] [--mlp-frames N]
//                    [--scene plate:T|filament:T|melt-pool] [--queues] [--only colour|5x5]
//                    [--methods lut,likelihood,mlp]
//        bench_chain --rgb-model M.json --soak N [--soak-size WxH]
// (scripts/bench.sh builds the models and runs this.)
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

#include "bench_support.h"
#include "pyrocam/runtime/model.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Options {
  std::string rgb_model, nir_model, scene = "plate:1500";
  int frames = 600, mlp_frames = 3, warmup = 20;
  bool queues = false;
  std::string only;                            // "colour" or "5x5": one chain
  std::string methods = "lut,likelihood,mlp";  // ratiotemp methods to run
  std::string misfit_probability = "0";        // ratiotemp's band-consistency check (0: off)
  int soak = 0;                                // frames of the soak run (0: no soak)
  int soak_width = 320, soak_height = 240;
};

// kB from /proc/self/status ("VmRSS", "VmHWM").
long status_kb(const char* key) {
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
double cpu_seconds() {
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

void on_handoff(GstElement*, GstBuffer*, GstPad*, gpointer data) {
  auto* h = static_cast<Handoffs*>(data);
  h->at.push_back(Clock::now());
  h->cpu.push_back(cpu_seconds());
  if (h->at.size() == h->warmup + 1) h->rss_warm_kb = status_kb("VmRSS");
}

// Pushes `frames` timestamped references to `raw` through `chain` (a launch fragment between
// appsrc and fakesink) and times the frames after `warmup`.
Run run_chain(const std::string& chain, const std::string& caps, const cv::Mat& raw, int frames,
              int warmup) {
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

// The soak: resident memory at checkpoints (1, 2, 5 x 10^k frames from 1000 on, and the last).
struct Soak {
  int frames = 0;
  int count = 0;
  Clock::time_point started;
  double cpu_started = 0;
};

bool soak_checkpoint(int frame, int last) {
  if (frame == last) return true;
  for (int decade = 1000; decade > 0 && decade <= frame; decade *= 10)
    if (frame == decade || frame == 2 * decade || frame == 5 * decade) return true;
  return false;
}

void on_soak_handoff(GstElement*, GstBuffer*, GstPad*, gpointer data) {
  auto* s = static_cast<Soak*>(data);
  if (!soak_checkpoint(++s->count, s->frames)) return;
  const double wall = std::chrono::duration<double>(Clock::now() - s->started).count();
  std::printf(
      "  frame %7d: resident %6.1f MB (peak %6.1f MB), %6.0f s, %6.1f frames/s, %.2f CPU "
      "ms/frame\n",
      s->count, status_kb("VmRSS") / 1024.0, status_kb("VmHWM") / 1024.0, wall, s->count / wall,
      1e3 * (cpu_seconds() - s->cpu_started) / s->count);
  std::fflush(stdout);
}

int run_soak(const Options& o) {
  const std::string size =
      "width=" + std::to_string(o.soak_width) + ",height=" + std::to_string(o.soak_height);
  const std::string launch =
      "pyrocamsrc scene=melt-pool num-buffers=" + std::to_string(o.soak) +
      " ! video/x-bayer,format=rggb," + size +
      ",framerate=30/1 ! darksub dark-level=50 ! demosaic25 ! ratiotemp stats-interval=0 "
      "method=lut model=" +
      o.rgb_model + " ! fakesink name=sink sync=false signal-handoffs=true";
  std::printf("soak: %s\n", launch.c_str());
  std::printf("  start:         resident %6.1f MB\n", status_kb("VmRSS") / 1024.0);
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(launch.c_str(), &error);
  if (!pipeline || error) {
    std::fprintf(stderr, "soak: %s\n", error ? error->message : "could not build the pipeline");
    if (error) g_error_free(error);
    if (pipeline) gst_object_unref(pipeline);
    return 1;
  }
  Soak soak;
  soak.frames = o.soak;
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
  if (rc == 0 && soak.count != o.soak) {
    std::fprintf(stderr, "soak: %d frames of %d reached the sink\n", soak.count, o.soak);
    rc = 1;
  }
  return rc;
}

void print_run(const std::string& what, const Run& r) {
  if (!r.ok) {
    std::printf("%-52s FAILED: %s\n", what.c_str(), r.error.c_str());
    return;
  }
  std::printf(
      "%-52s %7.1f frames/s %7.1f CPU ms/frame  (%4d frames timed, first after %.2f s, RSS %ld "
      "-> %ld MB)\n",
      what.c_str(), r.fps, r.cpu_ms, r.frames, r.first_frame_s, r.rss_warm_kb / 1024,
      r.rss_end_kb / 1024);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--rgb-model")
      o.rgb_model = value();
    else if (a == "--nir-model")
      o.nir_model = value();
    else if (a == "--frames")
      o.frames = std::atoi(value().c_str());
    else if (a == "--mlp-frames")
      o.mlp_frames = std::atoi(value().c_str());
    else if (a == "--scene")
      o.scene = value();
    else if (a == "--queues")
      o.queues = true;
    else if (a == "--only")
      o.only = value();
    else if (a == "--methods")
      o.methods = value();
    else if (a == "--misfit-probability")
      o.misfit_probability = value();
    else if (a == "--soak")
      o.soak = std::atoi(value().c_str());
    else if (a == "--soak-size") {
      const std::string v = value();
      if (std::sscanf(v.c_str(), "%dx%d", &o.soak_width, &o.soak_height) != 2) {
        std::fprintf(stderr, "--soak-size takes WIDTHxHEIGHT, not %s\n", v.c_str());
        return 2;
      }
    } else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (o.rgb_model.empty() || (o.nir_model.empty() && o.soak == 0) || o.soak < 0) {
    std::fprintf(
        stderr,
        "usage: %s --rgb-model M.json --nir-model N.json [--frames N] "
        "[--mlp-frames N] [--scene plate:T|filament:T|melt-pool] [--queues] [--only colour|5x5] "
        "[--methods lut,likelihood,mlp] [--misfit-probability P]\n"
        "       %s --rgb-model M.json --soak FRAMES [--soak-size WxH]\n",
        argv[0], argv[0]);
    return 2;
  }
  GstElementFactory* f = gst_element_factory_find("ratiotemp");
  if (!f) {
    std::fprintf(stderr, "ratiotemp is not registered: set GST_PLUGIN_PATH to build/plugins\n");
    return 1;
  }
  gst_object_unref(f);
  if (o.soak > 0) return run_soak(o);
  const std::string q = o.queues ? " ! queue" : "";
  std::printf("pyrocam chain benchmark: %u CPU cores, scene %s%s\n", g_get_num_processors(),
              o.scene.c_str(), o.queues ? ", queues between elements" : "");

  auto wanted = [&](const std::string& method) {
    return o.methods.find(method) != std::string::npos;
  };
  if (o.only.empty() || o.only == "colour") {
    const pyrocam::ThermalModel m = pyrocam::load_model(o.rgb_model);
    const auto scene = pyrocam::bench::make_scene(o.scene, 2048, 2048);
    const double hot = pyrocam::bench::hot_fraction(scene);
    const cv::Mat raw = pyrocam::bench::render(m, scene);
    const std::string caps = "video/x-bayer,format=rggb,width=2048,height=2048,framerate=30/1";
    std::printf(
        "\ncolour camera, 2048x2048 8-bit RGGB, %.0f %% of the pixels on the hot object, "
        "model %s\n",
        100 * hot, o.rgb_model.c_str());
    print_run("bayer2rgb alone", run_chain("bayer2rgb", caps, raw, o.frames, o.warmup));
    print_run(
        "darksub ! demosaic25 (no ratiotemp)",
        run_chain("darksub dark-level=50" + q + " ! demosaic25", caps, raw, o.frames, o.warmup));
    const std::string chain = "darksub dark-level=50" + q + " ! demosaic25" + q +
                              " ! ratiotemp stats-interval=0 model=" + o.rgb_model +
                              " misfit-probability=" + o.misfit_probability;
    if (wanted("lut")) {
      print_run("darksub ! demosaic25 ! ratiotemp method=lut",
                run_chain(chain + " method=lut", caps, raw, o.frames, o.warmup));
      // The same with demosaic25's mixed-pixel check (off by default): what the check costs.
      const std::string checked = "darksub dark-level=50" + q + " ! demosaic25 mixed-pixels=0.2" +
                                  q + " ! ratiotemp stats-interval=0 model=" + o.rgb_model +
                                  " misfit-probability=" + o.misfit_probability;
      print_run("the same, demosaic25 mixed-pixels=0.2",
                run_chain(checked + " method=lut", caps, raw, o.frames, o.warmup));
    }
    if (wanted("likelihood"))
      print_run("darksub ! demosaic25 ! ratiotemp method=likelihood",
                run_chain(chain + " method=likelihood", caps, raw, std::max(o.frames / 50, 8), 2));
    if (wanted("mlp"))
      print_run("darksub ! demosaic25 ! ratiotemp method=mlp",
                run_chain(chain + " method=mlp", caps, raw, o.mlp_frames, 1));
  }
  if (o.only.empty() || o.only == "5x5") {
    const pyrocam::ThermalModel m = pyrocam::load_model(o.nir_model);
    // The sensor's frame; the chain reads its whole 5x5 periods, 2045x1085 (gray video rows are
    // padded to a multiple of 4 bytes: the same 2048 bytes per row). bayer2rgb (which crashes on
    // odd sizes) reads the whole frame.
    const auto scene = pyrocam::bench::make_scene(o.scene, 2048, 1088);
    const double hot = pyrocam::bench::hot_fraction(scene);
    const cv::Mat sensor = pyrocam::bench::render(m, scene);
    const cv::Mat raw = sensor(cv::Rect(0, 0, 2048, 1085)).clone();
    const std::string caps = "video/x-raw,format=GRAY8,width=2045,height=1085,framerate=30/1";
    std::printf(
        "\n5x5 camera, 2045x1085 GRAY8 5x5 mosaic (409x217 macro-pixels), %.0f %% of the pixels "
        "on the hot object, model %s\n",
        100 * hot, o.nir_model.c_str());
    print_run(
        "bayer2rgb alone (2048x1088, bytes as RGGB)",
        run_chain("bayer2rgb", "video/x-bayer,format=rggb,width=2048,height=1088,framerate=30/1",
                  sensor, o.frames, o.warmup));
    print_run("darksub ! demosaic25 (no ratiotemp)",
              run_chain("darksub dark-level=50 pattern=5x5" + q + " ! demosaic25", caps, raw,
                        o.frames, o.warmup));
    const std::string chain = "darksub dark-level=50 pattern=5x5" + q + " ! demosaic25" + q +
                              " ! ratiotemp stats-interval=0 model=" + o.nir_model +
                              " misfit-probability=" + o.misfit_probability;
    if (wanted("likelihood"))
      print_run("darksub ! demosaic25 ! ratiotemp method=likelihood",
                run_chain(chain + " method=likelihood", caps, raw, o.frames / 2, o.warmup));
    if (wanted("mlp"))
      print_run("darksub ! demosaic25 ! ratiotemp method=mlp",
                run_chain(chain + " method=mlp", caps, raw, o.mlp_frames, 1));
  }
  std::printf("\npeak resident memory of the run: %ld MB\n", status_kb("VmHWM") / 1024);
  return 0;
}
