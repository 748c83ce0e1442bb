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
// One scene (--scene): every stage and method of both chains. Several (--scenes a,b,...): per
// scene bayer2rgb and each camera's own method (colour: lut, 5x5: likelihood), with the chain's
// rate as a multiple of bayer2rgb's on the same frames, then a table of all scenes.
//
// Soak mode (--soak N): the resident memory of each chain over N frames of the simulated camera,
// whose frames all differ (a moving melt pool, new noise):
//   colour: pyrocamsrc scene=melt-pool (8-bit RGGB, 320x240 or --soak-size) ! darksub !
//           demosaic25 ! ratiotemp method=lut ! fakesink
//   5x5:    pyrocamsrc profile=nir5x5-reference scene=melt-pool (GRAY8, the same size) ! darksub
//           pattern=5x5 ! demosaic25 ! ratiotemp method=likelihood ! fakesink (with --nir-model)
// printing the resident memory at frames 1k, 2k, 5k, 10k, 20k, 50k, 100k, ... and at the last,
// and its growth from frame 1000 (a tenth of a shorter soak) to the last.
//
// Usage: bench_chain --rgb-model M.json --nir-model N.json [--frames N] [--mlp-frames N]
//                    [--scene plate:T[:P]|filament:T|melt-pool[@F] | --scenes S1,S2,...] [--queues]
//                    [--only colour|5x5] [--methods lut,likelihood,mlp] [--misfit-probability P]
//                    [--brightness-radius R]
//        bench_chain --rgb-model M.json [--nir-model N.json] --soak N [--soak-size WxH]
//                    [--only colour|5x5]
// (scripts/bench.sh builds the models and runs this.)
#include <gst/gst.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "bench_support.h"
#include "chain_runs.h"
#include "pyrocam/runtime/model.h"

namespace {

using pyrocam::bench::Run;
using pyrocam::bench::run_chain;
using pyrocam::bench::status_kb;

struct Options {
  std::string rgb_model, nir_model, scene = "plate:1500";
  std::vector<std::string> scenes;  // --scenes: the per-scene table
  int frames = 600, mlp_frames = 3, warmup = 20;
  bool queues = false;
  std::string only;                            // "colour" or "5x5": one chain
  std::string methods = "lut,likelihood,mlp";  // ratiotemp methods to run
  std::string misfit_probability = "0";        // ratiotemp's band-consistency check (0: off)
  std::string brightness_radius = "0";         // ratiotemp's brightness readings (0: off)
  int soak = 0;                                // frames of the soak run (0: no soak)
  int soak_width = 320, soak_height = 240;

  bool wanted(const std::string& method) const { return methods.find(method) != std::string::npos; }
  bool colour() const { return only.empty() || only == "colour"; }
  bool nir() const { return only.empty() || only == "5x5"; }
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> parts;
  for (std::size_t from = 0; from <= s.size();) {
    const std::size_t comma = std::min(s.find(',', from), s.size());
    if (comma > from) parts.push_back(s.substr(from, comma - from));
    from = comma + 1;
  }
  return parts;
}

// `bayer`: bayer2rgb on the same frames in the same run, for the ratio of the rates.
void print_run(const std::string& what, const Run& r, const Run* bayer = nullptr) {
  if (!r.ok) {
    std::printf("%-52s FAILED: %s\n", what.c_str(), r.error.c_str());
    return;
  }
  char ratio[32] = "";
  if (bayer && bayer->ok)
    std::snprintf(ratio, sizeof ratio, "%6.2fx bayer2rgb", r.fps / bayer->fps);
  std::printf(
      "%-52s %7.1f frames/s %7.1f CPU ms/frame %16s  (%4d frames timed, first after %.2f s, RSS "
      "%ld -> %ld MB)\n",
      what.c_str(), r.fps, r.cpu_ms, ratio, r.frames, r.first_frame_s, r.rss_warm_kb / 1024,
      r.rss_end_kb / 1024);
  std::fflush(stdout);
}

// One scene's figures for the table.
struct SceneRow {
  std::string scene;
  double hot = 0;
  Run colour_bayer, colour_lut, nir_bayer, nir_likelihood;
};

// The colour chain on one scene; `detailed`: every stage and method, else bayer2rgb and lut.
void bench_colour(const Options& o, const pyrocam::ThermalModel& m, const std::string& spec,
                  bool detailed, SceneRow& row) {
  const std::string q = o.queues ? " ! queue" : "";
  const auto scene = pyrocam::bench::make_scene(spec, 2048, 2048);
  row.hot = pyrocam::bench::hot_fraction(scene);
  const cv::Mat raw = pyrocam::bench::render(m, scene);
  const std::string caps = "video/x-bayer,format=rggb,width=2048,height=2048,framerate=30/1";
  std::printf(
      "\n%s: colour camera, 2048x2048 8-bit RGGB, %.0f %% of the pixels on the hot object, "
      "model %s\n",
      spec.c_str(), 100 * row.hot, o.rgb_model.c_str());
  row.colour_bayer = run_chain("bayer2rgb", caps, raw, o.frames, o.warmup);
  print_run("bayer2rgb alone", row.colour_bayer);
  const Run* bayer = &row.colour_bayer;
  if (detailed) {
    print_run(
        "darksub ! demosaic25 (no ratiotemp)",
        run_chain("darksub dark-level=50" + q + " ! demosaic25", caps, raw, o.frames, o.warmup),
        bayer);
    print_run(
        "the same, demosaic25 method=bilinear mixed-pixels=0.5",
        run_chain("darksub dark-level=50" + q + " ! demosaic25 method=bilinear mixed-pixels=0.5",
                  caps, raw, o.frames, o.warmup),
        bayer);
  }
  const std::string chain = "darksub dark-level=50" + q + " ! demosaic25" + q +
                            " ! ratiotemp stats-interval=0 model=" + o.rgb_model +
                            " misfit-probability=" + o.misfit_probability +
                            " brightness-radius=" + o.brightness_radius;
  if (o.wanted("lut")) {
    row.colour_lut = run_chain(chain + " method=lut", caps, raw, o.frames, o.warmup);
    print_run("darksub ! demosaic25 ! ratiotemp method=lut", row.colour_lut, bayer);
    if (detailed) {
      // What reading each pixel from its own sample costs (ratiotemp brightness-radius).
      print_run("the same, ratiotemp brightness-radius=2",
                run_chain(chain + " method=lut brightness-radius=2", caps, raw, o.frames, o.warmup),
                bayer);
      // The same with bilinear demosaicking (the default is matched), without and with the
      // mixed-pixel check: what matched and the check cost.
      const auto with = [&](const std::string& demosaic) {
        return "darksub dark-level=50" + q + " ! demosaic25 " + demosaic + q +
               " ! ratiotemp stats-interval=0 model=" + o.rgb_model +
               " misfit-probability=" + o.misfit_probability +
               " brightness-radius=" + o.brightness_radius + " method=lut";
      };
      print_run("the same, demosaic25 method=bilinear",
                run_chain(with("method=bilinear"), caps, raw, o.frames, o.warmup), bayer);
      print_run("the same, demosaic25 method=bilinear mixed-pixels=0.5",
                run_chain(with("method=bilinear mixed-pixels=0.5"), caps, raw, o.frames, o.warmup),
                bayer);
    }
  }
  if (!detailed) return;
  if (o.wanted("likelihood"))
    print_run("darksub ! demosaic25 ! ratiotemp method=likelihood",
              run_chain(chain + " method=likelihood", caps, raw, std::max(o.frames / 50, 8), 2),
              bayer);
  if (o.wanted("mlp"))
    print_run("darksub ! demosaic25 ! ratiotemp method=mlp",
              run_chain(chain + " method=mlp", caps, raw, o.mlp_frames, 1), bayer);
}

// The 5x5 chain on one scene; `detailed`: every stage and method, else bayer2rgb and likelihood.
void bench_5x5(const Options& o, const pyrocam::ThermalModel& m, const std::string& spec,
               bool detailed, SceneRow& row) {
  const std::string q = o.queues ? " ! queue" : "";
  // The sensor's frame; the chain reads its whole 5x5 periods, 2045x1085 (gray video rows are
  // padded to a multiple of 4 bytes: the same 2048 bytes per row). bayer2rgb (which crashes on
  // odd sizes) reads the whole frame.
  const auto scene = pyrocam::bench::make_scene(spec, 2048, 1088);
  const double hot = pyrocam::bench::hot_fraction(scene);
  if (!o.colour()) row.hot = hot;
  const cv::Mat sensor = pyrocam::bench::render(m, scene);
  const cv::Mat raw = sensor(cv::Rect(0, 0, 2048, 1085)).clone();
  const std::string caps = "video/x-raw,format=GRAY8,width=2045,height=1085,framerate=30/1";
  std::printf(
      "\n%s: 5x5 camera, 2045x1085 GRAY8 5x5 mosaic (409x217 macro-pixels), %.0f %% of the "
      "pixels on the hot object, model %s\n",
      spec.c_str(), 100 * hot, o.nir_model.c_str());
  row.nir_bayer =
      run_chain("bayer2rgb", "video/x-bayer,format=rggb,width=2048,height=1088,framerate=30/1",
                sensor, o.frames, o.warmup);
  print_run("bayer2rgb alone (2048x1088, bytes as RGGB)", row.nir_bayer);
  const Run* bayer = &row.nir_bayer;
  if (detailed)
    print_run("darksub ! demosaic25 (no ratiotemp)",
              run_chain("darksub dark-level=50 pattern=5x5" + q + " ! demosaic25", caps, raw,
                        o.frames, o.warmup),
              bayer);
  const std::string chain = "darksub dark-level=50 pattern=5x5" + q + " ! demosaic25" + q +
                            " ! ratiotemp stats-interval=0 model=" + o.nir_model +
                            " misfit-probability=" + o.misfit_probability +
                            " brightness-radius=" + o.brightness_radius;
  if (o.wanted("likelihood")) {
    // Half the frames (the slower chain), but never fewer than 10 timed past the warm-up.
    row.nir_likelihood = run_chain(chain + " method=likelihood", caps, raw,
                                   std::max(o.frames / 2, o.warmup + 11), o.warmup);
    print_run("darksub ! demosaic25 ! ratiotemp method=likelihood", row.nir_likelihood, bayer);
    if (detailed)  // what reading each cell from its own bands costs
      print_run("the same, ratiotemp brightness-radius=2",
                run_chain(chain + " method=likelihood brightness-radius=2", caps, raw,
                          std::max(o.frames / 2, o.warmup + 11), o.warmup),
                bayer);
  }
  if (detailed && o.wanted("mlp"))
    print_run("darksub ! demosaic25 ! ratiotemp method=mlp",
              run_chain(chain + " method=mlp", caps, raw, o.mlp_frames, 1), bayer);
}

std::string cell(const Run& r) {
  char s[48];
  if (r.ok)
    std::snprintf(s, sizeof s, "%8.1f %7.1f", r.fps, r.cpu_ms);
  else
    std::snprintf(s, sizeof s, "%16s", r.error.empty() ? "-" : "FAILED");
  return s;
}

std::string ratio(const Run& chain, const Run& bayer) {
  char s[16] = "      -";
  if (chain.ok && bayer.ok) std::snprintf(s, sizeof s, "%6.2fx", chain.fps / bayer.fps);
  return s;
}

void print_table(const std::vector<SceneRow>& rows) {
  std::printf(
      "\nper scene: frames/s and CPU ms/frame (all threads); ratio: the chain's frames/s over "
      "bayer2rgb's on the same frames in this run\n"
      "%24s | %-41s | %s\n%24s | %-16s %-24s | %-16s %s\n"
      "%-18s %5s | %8s %7s %8s %7s %7s | %8s %7s %8s %7s %7s\n",
      "", "colour 2048x2048 8-bit RGGB", "5x5 2045x1085 GRAY8", "", "bayer2rgb",
      "ratiotemp method=lut", "bayer2rgb", "ratiotemp method=likelihood", "scene", "hot",
      "frames/s", "CPU ms", "frames/s", "CPU ms", "ratio", "frames/s", "CPU ms", "frames/s",
      "CPU ms", "ratio");
  for (const SceneRow& r : rows)
    std::printf("%-18s %3.0f %% | %s %s %s | %s %s %s\n", r.scene.c_str(), 100 * r.hot,
                cell(r.colour_bayer).c_str(), cell(r.colour_lut).c_str(),
                ratio(r.colour_lut, r.colour_bayer).c_str(), cell(r.nir_bayer).c_str(),
                cell(r.nir_likelihood).c_str(), ratio(r.nir_likelihood, r.nir_bayer).c_str());
  std::fflush(stdout);
}

int run_soaks(const Options& o) {
  const std::string n = std::to_string(o.soak);
  const std::string size = ",width=" + std::to_string(o.soak_width) +
                           ",height=" + std::to_string(o.soak_height) + ",framerate=30/1";
  const std::string sink = " ! fakesink name=sink sync=false signal-handoffs=true";
  int rc = 0;
  if (o.colour())
    rc |= pyrocam::bench::run_soak(
        "colour chain, lookup table",
        "pyrocamsrc scene=melt-pool num-buffers=" + n + " ! video/x-bayer,format=rggb" + size +
            " ! darksub dark-level=50 ! demosaic25 ! ratiotemp stats-interval=0 method=lut model=" +
            o.rgb_model + sink,
        o.soak);
  if (o.nir() && !o.nir_model.empty())
    rc |= pyrocam::bench::run_soak(
        "5x5 chain, likelihood fit",
        "pyrocamsrc profile=nir5x5-reference scene=melt-pool num-buffers=" + n +
            " ! video/x-raw,format=GRAY8" + size +
            " ! darksub dark-level=50 pattern=5x5 ! demosaic25 ! ratiotemp stats-interval=0 "
            "method=likelihood model=" +
            o.nir_model + sink,
        o.soak);
  return rc;
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
    else if (a == "--scenes")
      o.scenes = split(value());
    else if (a == "--queues")
      o.queues = true;
    else if (a == "--only")
      o.only = value();
    else if (a == "--methods")
      o.methods = value();
    else if (a == "--misfit-probability")
      o.misfit_probability = value();
    else if (a == "--brightness-radius")
      o.brightness_radius = value();
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
  const bool only_ok = o.only.empty() || o.only == "colour" || o.only == "5x5";
  if (o.rgb_model.empty() || (o.nir_model.empty() && o.soak == 0 && o.nir()) || o.soak < 0 ||
      !only_ok) {
    std::fprintf(
        stderr,
        "usage: %s --rgb-model M.json --nir-model N.json [--frames N] [--mlp-frames N]\n"
        "         [--scene plate:T[:P]|filament:T|melt-pool[@F] | --scenes S1,S2,...] [--queues]\n"
        "         [--only colour|5x5] [--methods lut,likelihood,mlp] [--misfit-probability P]\n"
        "         [--brightness-radius R]\n"
        "       %s --rgb-model M.json [--nir-model N.json] --soak FRAMES [--soak-size WxH]\n"
        "         [--only colour|5x5]\n",
        argv[0], argv[0]);
    return 2;
  }
  GstElementFactory* f = gst_element_factory_find("ratiotemp");
  if (!f) {
    std::fprintf(stderr, "ratiotemp is not registered: set GST_PLUGIN_PATH to build/plugins\n");
    return 1;
  }
  gst_object_unref(f);
  if (o.soak > 0) return run_soaks(o);
  const bool table = !o.scenes.empty();
  if (!table) o.scenes = {o.scene};
  for (const std::string& spec : o.scenes) {
    try {
      pyrocam::bench::make_scene(spec, 64, 64);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 2;
    }
  }
  std::string names;
  for (const std::string& spec : o.scenes) names += (names.empty() ? "" : ", ") + spec;
  std::printf("pyrocam chain benchmark: %u CPU cores, scene%s %s%s\n", g_get_num_processors(),
              o.scenes.size() > 1 ? "s" : "", names.c_str(),
              o.queues ? ", queues between elements" : "");
  pyrocam::ThermalModel rgb, nir;
  if (o.colour()) rgb = pyrocam::load_model(o.rgb_model);
  if (o.nir()) nir = pyrocam::load_model(o.nir_model);
  std::vector<SceneRow> rows;
  for (const std::string& spec : o.scenes) {
    SceneRow row;
    row.scene = spec;
    if (o.colour()) bench_colour(o, rgb, spec, !table, row);
    if (o.nir()) bench_5x5(o, nir, spec, !table, row);
    rows.push_back(row);
  }
  if (table) print_table(rows);
  std::printf("\npeak resident memory of the run: %ld MB\n", status_kb("VmHWM") / 1024);
  return 0;
}
