// Start-up time of ratiotemp: from PLAYING to its first output buffer, for a chain of the
// simulated camera, cold (no table cache) and warm (the cache the previous run wrote), and the
// library's share of it step by step (model load, estimator build, cache load, lookup table's
// check; the prebuilt table beside the model, <model>.lut, when there is one). Prints figures;
// never a test.
//
// Usage: bench_startup --model M.json [--profile P] [--pattern 5x5] [--runs N] [--library-only]
//        [--cache-dir DIR]
//        (--pattern 5x5 without --profile simulates the nir5x5-reference sensor; a pipeline
//        that gives no reading prints the error and exits 1)
//        (GST_PLUGIN_PATH and PYROCAM_PROFILE_DIR as for the chains; the cache goes to a
//        temporary folder, emptied before the cold run, or to DIR, kept: a second invocation
//        then measures a warm start in a fresh process)
#include <gst/gst.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/runtime/prebuilt_tables.h"

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct FirstBuffer {
  GMutex lock;
  GCond cond;
  bool seen = false;
  Clock::time_point at;
};

GstPadProbeReturn on_buffer(GstPad*, GstPadProbeInfo*, gpointer data) {
  auto* f = static_cast<FirstBuffer*>(data);
  g_mutex_lock(&f->lock);
  if (!f->seen) {
    f->seen = true;
    f->at = Clock::now();
    g_cond_signal(&f->cond);
  }
  g_mutex_unlock(&f->lock);
  return GST_PAD_PROBE_REMOVE;
}

// Milliseconds from set_state(PLAYING) to ratiotemp's first buffer; negative on failure.
double first_reading_ms(const std::string& description) {
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  if (!pipeline) {
    std::fprintf(stderr, "pipeline: %s\n", error ? error->message : "?");
    g_clear_error(&error);
    return -1;
  }
  GstElement* rt = gst_bin_get_by_name(GST_BIN(pipeline), "rt");
  GstPad* src = gst_element_get_static_pad(rt, "src");
  FirstBuffer f;
  g_mutex_init(&f.lock);
  g_cond_init(&f.cond);
  gst_pad_add_probe(src, GST_PAD_PROBE_TYPE_BUFFER, on_buffer, &f, nullptr);
  const Clock::time_point t0 = Clock::now();
  double ms = -1;
  if (gst_element_set_state(pipeline, GST_STATE_PLAYING) != GST_STATE_CHANGE_FAILURE) {
    const gint64 deadline = g_get_monotonic_time() + 30 * G_TIME_SPAN_SECOND;
    g_mutex_lock(&f.lock);
    while (!f.seen && g_cond_wait_until(&f.cond, &f.lock, deadline)) {
    }
    if (f.seen) ms = std::chrono::duration<double, std::milli>(f.at - t0).count();
    g_mutex_unlock(&f.lock);
  }
  if (ms < 0) {  // say why: a pipeline that never reads must not print as a time
    GstBus* bus = gst_element_get_bus(pipeline);
    if (GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
      GError* err = nullptr;
      gchar* debug = nullptr;
      gst_message_parse_error(m, &err, &debug);
      std::fprintf(stderr, "pipeline failed: %s (%s)\n", err ? err->message : "?",
                   debug ? debug : "");
      g_clear_error(&err);
      g_free(debug);
      gst_message_unref(m);
    } else {
      std::fprintf(stderr, "pipeline failed: no reading within 30 s\n");
    }
    gst_object_unref(bus);
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);  // writes the table cache
  gst_object_unref(src);
  gst_object_unref(rt);
  gst_object_unref(pipeline);
  g_cond_clear(&f.cond);
  g_mutex_clear(&f.lock);
  return ms;
}

// The library's steps of ratiotemp's start(), timed one by one with the cache in `dir`.
void breakdown(const std::string& model_path, const std::string& dir) {
  Clock::time_point t0 = Clock::now();
  auto model = std::make_shared<const pyrocam::ThermalModel>(pyrocam::load_model(model_path));
  const double load = ms_since(t0);
  t0 = Clock::now();
  pyrocam::EstimatorSelector selector(model);
  const std::string prebuilt = pyrocam::prebuilt_tables_file(model_path);
  selector.set_prebuilt_tables(prebuilt);
  selector.set_table_cache(pyrocam::table_cache_file(*model, dir));
  const pyrocam::EstimatorSelector::Choice c = selector.select(pyrocam::MethodRequest::kAuto);
  const double select = ms_since(t0);
  std::printf(
      "  library: load_model %.1f ms, select(auto) -> %s %.1f ms (%zu prebuilt blocks, %zu "
      "cached blocks%s)\n",
      load, pyrocam::method_name(c.method).c_str(), select, selector.prebuilt_blocks_read(),
      selector.cache_blocks_read(),
      selector.lut_check_skipped() ? ", check verdict from the files" : "");
  const pyrocam::Method kinds[] = {pyrocam::Method::kLut, pyrocam::Method::kLikelihood,
                                   pyrocam::Method::kMlp};
  for (pyrocam::Method m : kinds) {
    try {
      t0 = Clock::now();
      pyrocam::PlaneEstimator e(model, m);
      const double build = ms_since(t0);
      double cache = 0, check = 0, prebuilt_ms = 0;
      std::size_t blocks = 0, prebuilt_blocks = 0;
      if (m == pyrocam::Method::kLut) {
        t0 = Clock::now();
        if (std::filesystem::exists(prebuilt))
          prebuilt_blocks = e.estimator().load_tables(prebuilt);
        prebuilt_ms = ms_since(t0);
        const std::string file = pyrocam::table_cache_file(*model, dir);
        t0 = Clock::now();
        if (std::filesystem::exists(file)) blocks = e.estimator().load_tables(file);
        cache = ms_since(t0);
        t0 = Clock::now();
        const auto mlp = pyrocam::make_estimator(model, pyrocam::Method::kMlp);
        pyrocam::compare_on_locus(*model, e.estimator(), *mlp);
        check = ms_since(t0);
      }
      std::printf("    %-10s build %.1f ms", pyrocam::method_name(m).c_str(), build);
      if (m == pyrocam::Method::kLut)
        std::printf(
            ", prebuilt load %.1f ms (%zu blocks), cache load %.1f ms (%zu blocks), check %.1f ms",
            prebuilt_ms, prebuilt_blocks, cache, blocks, check);
      std::printf("\n");
    } catch (const std::exception& e) {
      std::printf("    %-10s not for this model (%s)\n", pyrocam::method_name(m).c_str(), e.what());
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  std::string model, profile, pattern, cache_dir;
  int runs = 3;
  bool library_only = false;  // the breakdown alone (for a profiler)
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--model")
      model = value();
    else if (a == "--profile")
      profile = value();
    else if (a == "--pattern")
      pattern = value();
    else if (a == "--runs")
      runs = std::stoi(value());
    else if (a == "--cache-dir")
      cache_dir = value();
    else if (a == "--library-only")
      library_only = true;
  }
  if (model.empty()) {
    std::fprintf(
        stderr,
        "usage: %s --model M.json [--profile P] [--pattern 5x5] [--runs N] [--library-only]\n"
        "       [--cache-dir DIR]\n",
        argv[0]);
    return 2;
  }
  // The simulated camera's default profile is a colour one: a 5x5 chain needs the 5x5 sensor.
  if (pattern == "5x5" && profile.empty()) profile = "nir5x5-reference";
  const bool own_dir = cache_dir.empty();
  const std::filesystem::path dir = own_dir ? std::filesystem::temp_directory_path() /
                                                  ("bench-startup-" + std::to_string(getpid()))
                                            : std::filesystem::path(cache_dir);
  if (own_dir) std::filesystem::remove_all(dir);
  const std::string description = "pyrocamsrc" + (profile.empty() ? "" : " profile=" + profile) +
                                  " ! darksub dark-level=50" +
                                  (pattern.empty() ? "" : " pattern=" + pattern) +
                                  " ! demosaic25 ! ratiotemp name=rt model=" + model +
                                  " table-cache=" + dir.string() + " ! fakesink";
  if (library_only) {
    for (int r = 0; r < runs; ++r) breakdown(model, dir.string());
    return 0;
  }
  std::printf("%s\n", description.c_str());
  for (int r = 0; r <= runs; ++r) {
    const double ms = first_reading_ms(description);
    if (ms < 0) {
      if (own_dir) std::filesystem::remove_all(dir);
      return 1;
    }
    if (r == 0)
      std::printf("  %s: first reading %.1f ms after PLAYING\n",
                  own_dir ? "cold (no cache)" : "first run", ms);
    else
      std::printf("  warm run %d: first reading %.1f ms after PLAYING\n", r, ms);
  }
  breakdown(model, dir.string());
  if (own_dir) std::filesystem::remove_all(dir);
  return 0;
}
