// ratiotemp per-frame cost: one frame of band planes from pyrocamsrc ! darksub ! demosaic25
// (a plate at 1200 degC filling 60 % of the frame) pushed repeatedly through ratiotemp with each
// configuration given on the command line. Prints start-up (model loading, building and
// checking the estimator, first frame) and the mean time per frame. Wall-clock: run it on a
// quiet machine.
// Usage: bench_ratiotemp PROFILE CAPS DARKSUB-OPTIONS MODEL FRAMES "RATIOTEMP-OPTIONS"...
// e.g. (one line) GST_PLUGIN_PATH=build/plugins PYROCAM_PROFILE_DIR=profiles
//   build/bench/bench_ratiotemp rgb-reference video/x-bayer,width=320,height=240 ""
//   build/tests/data/test-model-rgb.json 10 method=likelihood method=mlp
//   "method=likelihood output=uncertainty"
#include <gst/check/gstharness.h>
#include <gst/gst.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  if (argc < 7) {
    std::fprintf(stderr,
                 "usage: %s PROFILE CAPS DARKSUB-OPTIONS MODEL FRAMES RATIOTEMP-OPTIONS...\n",
                 argv[0]);
    return 2;
  }
  const std::string profile = argv[1], caps = argv[2], darksub = argv[3], model = argv[4];
  const int frames = std::atoi(argv[5]);
  GstElementFactory* factory = gst_element_factory_find("ratiotemp");
  if (!factory) {
    std::fprintf(stderr, "ratiotemp is not registered: set GST_PLUGIN_PATH to build/plugins\n");
    return 1;
  }
  gst_object_unref(factory);
  GstHarness* source =
      gst_harness_new_parse(("pyrocamsrc scene=plate temperature=1200 profile=" + profile + " ! " +
                             caps + " ! darksub dark-level=50 " + darksub + " ! demosaic25")
                                .c_str());
  gst_harness_play(source);
  GstBuffer* bands = gst_harness_pull(source);
  GstCaps* bands_caps = gst_pad_get_current_caps(source->sinkpad);
  gchar* caps_text = gst_caps_to_string(bands_caps);
  std::printf("%s, %d frames, %u threads\n", caps_text, frames, g_get_num_processors());
  g_free(caps_text);
  for (int a = 6; a < argc; ++a) {
    const std::string launch = "ratiotemp stats-interval=0 model=" + model + " " + argv[a];
    // A configuration the element refuses would abort the harness: try it alone first.
    GstElement* probe = gst_parse_launch(launch.c_str(), nullptr);
    GstBus* bus = gst_bus_new();
    gst_element_set_bus(probe, bus);
    const bool starts = gst_element_set_state(probe, GST_STATE_PAUSED) != GST_STATE_CHANGE_FAILURE;
    if (!starts) {
      GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
      GError* error = nullptr;
      if (m) gst_message_parse_error(m, &error, nullptr);
      std::printf("%-40s refused: %s\n", argv[a], error ? error->message : "?");
      if (error) g_error_free(error);
      if (m) gst_message_unref(m);
    }
    gst_element_set_state(probe, GST_STATE_NULL);
    gst_element_set_bus(probe, nullptr);
    gst_object_unref(bus);
    gst_object_unref(probe);
    if (!starts) continue;
    const auto t0 = std::chrono::steady_clock::now();
    GstHarness* h = gst_harness_new_parse(launch.c_str());
    gst_harness_set_src_caps(h, gst_caps_ref(bands_caps));
    bool ok = gst_harness_push(h, gst_buffer_ref(bands)) == GST_FLOW_OK;
    if (ok) gst_buffer_unref(gst_harness_pull(h));
    const auto t1 = std::chrono::steady_clock::now();
    for (int i = 0; ok && i < frames; ++i) {
      ok = gst_harness_push(h, gst_buffer_ref(bands)) == GST_FLOW_OK;
      if (ok) gst_buffer_unref(gst_harness_pull(h));
    }
    const auto t2 = std::chrono::steady_clock::now();
    if (ok)
      std::printf("%-40s start-up %6.2f s  %9.2f ms/frame\n", argv[a],
                  std::chrono::duration<double>(t1 - t0).count(),
                  std::chrono::duration<double, std::milli>(t2 - t1).count() / frames);
    else
      std::printf("%-40s failed (see GST_DEBUG=ratiotemp:4)\n", argv[a]);
    gst_harness_teardown(h);
  }
  gst_caps_unref(bands_caps);
  gst_buffer_unref(bands);
  gst_harness_teardown(source);
  return 0;
}
