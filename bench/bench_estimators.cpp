// The per-pixel estimators at camera sizes, library level (no GStreamer): frames per second of
// PlaneEstimator::estimate (and estimate_codes, what ratiotemp runs) for each method on the band
// planes of one simulated frame, and, on the same pixels, how the fast methods agree with their
// references: the lookup table with the network (|T_lut - T_mlp| distribution, no-reading
// decisions), the fast likelihood fit with the exhaustive one.
//   colour: 2048x2048 RGGB, bilinear demosaic (4.2 M pixels of 3 bands)
//   5x5:    2045x1085 (the whole periods of a 2048x1088 sensor): 409x217 pixels of 25 bands
// Wall-clock and process CPU time: run on a quiet machine. Not a test.
//
// Usage: bench_estimators --rgb-model M.json --nir-model N.json [--frames N]
//                         [--scene plate:T[:P]|filament:T|melt-pool[@F]] [--only colour|5x5]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "bench_support.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/plane_estimator.h"

namespace {

using Clock = std::chrono::steady_clock;

struct Timing {
  double first_s = 0;  // the first frame (the lookup table fills its blocks)
  double fps = 0, cpu_ms = 0;
  int frames = 0;
};

// The first call, then `frames` more timed.
Timing time_frames(int frames, const std::function<void()>& run) {
  Timing t;
  auto start = Clock::now();
  run();
  t.first_s = std::chrono::duration<double>(Clock::now() - start).count();
  if (frames <= 0) {
    t.frames = 1;
    t.fps = 1 / t.first_s;
    return t;
  }
  const double cpu0 = pyrocam::bench::process_cpu_seconds();
  start = Clock::now();
  for (int i = 0; i < frames; ++i) run();
  const double wall = std::chrono::duration<double>(Clock::now() - start).count();
  t.frames = frames;
  t.fps = frames / wall;
  t.cpu_ms = 1e3 * (pyrocam::bench::process_cpu_seconds() - cpu0) / frames;
  return t;
}

void print_timing(const std::string& what, const Timing& t) {
  if (t.cpu_ms > 0)
    std::printf("%-46s %8.1f frames/s %7.1f CPU ms/frame  (%d frames; first frame %.3f s)\n",
                what.c_str(), t.fps, t.cpu_ms, t.frames, t.first_s);
  else
    std::printf("%-46s %8.2f frames/s                    (one frame, %.2f s)\n", what.c_str(),
                t.fps, t.first_s);
  std::fflush(stdout);
}

// Agreement of a fast estimate with its reference over the pixels of a frame.
void print_agreement(const std::string& what, const cv::Mat& reference, const cv::Mat& fast,
                     double tolerance_c) {
  std::vector<double> d;
  long only_reference = 0, only_fast = 0, neither = 0;
  for (int y = 0; y < reference.rows; ++y)
    for (int x = 0; x < reference.cols; ++x) {
      const float r = reference.at<float>(y, x), f = fast.at<float>(y, x);
      const bool rr = std::isfinite(r), ff = std::isfinite(f);
      if (rr && ff)
        d.push_back(std::abs(static_cast<double>(r) - f));
      else if (rr)
        ++only_reference;
      else if (ff)
        ++only_fast;
      else
        ++neither;
    }
  std::sort(d.begin(), d.end());
  auto q = [&](double p) {
    return d.empty() ? NAN : d[std::min(d.size() - 1, static_cast<std::size_t>(p * d.size()))];
  };
  const auto over = static_cast<long>(d.end() - std::upper_bound(d.begin(), d.end(), tolerance_c));
  std::printf(
      "%s: %zu pixels read by both, %ld by neither; read by one only: %ld (reference), %ld "
      "(fast)\n    |difference| degC: median %.4f, p99 %.4f, p99.9 %.4f, max %.4f; over %.2f "
      "degC: %ld (%.4f %%)\n",
      what.c_str(), d.size(), neither, only_reference, only_fast, q(0.5), q(0.99), q(0.999),
      d.empty() ? NAN : d.back(), tolerance_c, over,
      d.empty() ? 0.0 : 100.0 * static_cast<double>(over) / static_cast<double>(d.size()));
  std::fflush(stdout);
}

std::vector<cv::Mat> band_planes(const pyrocam::ThermalModel& m, const cv::Mat& raw) {
  cv::Mat signal;
  pyrocam::subtract_dark_level(raw, m.profile().dark_offset_dn,
                               m.profile().thresholds.inference_saturation_dn, signal);
  std::vector<cv::Mat> planes;
  std::vector<pyrocam::SignalNoise> noise;  // as demosaic25 with the profile
  for (int b = 0; b < m.profile().band_count(); ++b)
    noise.push_back(pyrocam::signal_noise(m.profile(), b));
  pyrocam::demosaic(signal, m.profile().mosaic, pyrocam::DemosaicMethod::kAuto, planes,
                    static_cast<float>(pyrocam::no_signal_level_dn(noise)));
  return planes;
}

}  // namespace

int main(int argc, char** argv) {
  std::string rgb_model, nir_model, scene_spec = "plate:1500", only;
  int frames = 20;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&] { return i + 1 < argc ? std::string(argv[++i]) : std::string(); };
    if (a == "--rgb-model")
      rgb_model = value();
    else if (a == "--nir-model")
      nir_model = value();
    else if (a == "--frames")
      frames = std::atoi(value().c_str());
    else if (a == "--scene")
      scene_spec = value();
    else if (a == "--only")
      only = value();
    else {
      std::fprintf(stderr, "unknown argument %s\n", a.c_str());
      return 2;
    }
  }
  if (rgb_model.empty() || nir_model.empty()) {
    std::fprintf(stderr,
                 "usage: %s --rgb-model M.json --nir-model N.json [--frames N] "
                 "[--scene plate:T[:P]|filament:T|melt-pool[@F]] [--only colour|5x5]\n",
                 argv[0]);
    return 2;
  }
  std::printf("pyrocam estimator benchmark (library level), scene %s\n", scene_spec.c_str());
  using pyrocam::Method;
  cv::Mat t, codes;

  if (only.empty() || only == "colour") {
    const auto model =
        std::make_shared<const pyrocam::ThermalModel>(pyrocam::load_model(rgb_model));
    const pyrocam::ThermalModel& m = *model;
    const auto scene = pyrocam::bench::make_scene(scene_spec, 2048, 2048);
    const auto planes = band_planes(m, pyrocam::bench::render(m, scene));
    std::printf(
        "\ncolour camera, 2048x2048 band planes (3 bands), %.0f %% of the frame on the hot "
        "object, model %s\n",
        100 * pyrocam::bench::hot_fraction(scene), rgb_model.c_str());
    const pyrocam::PlaneEstimator lut(model, Method::kLut);
    print_timing("lut estimate", time_frames(frames, [&] { lut.estimate(planes, t); }));
    print_timing("lut estimate_codes",
                 time_frames(frames, [&] { lut.estimate_codes(planes, codes); }));
    std::printf("    lookup table in memory: %.1f MB\n",
                static_cast<double>(lut.estimator().memory_bytes()) / 1048576.0);
    const pyrocam::PlaneEstimator likelihood(model, Method::kLikelihood);
    print_timing("likelihood estimate",
                 time_frames(std::max(1, frames / 10), [&] { likelihood.estimate(planes, t); }));
    const pyrocam::PlaneEstimator mlp(model, Method::kMlp);
    cv::Mat t_mlp, t_lut;
    print_timing("mlp estimate", time_frames(0, [&] { mlp.estimate(planes, t_mlp); }));
    lut.estimate(planes, t_lut);
    print_agreement("lut against mlp", t_mlp, t_lut, 0.5);
  }
  if (only.empty() || only == "5x5") {
    const auto model =
        std::make_shared<const pyrocam::ThermalModel>(pyrocam::load_model(nir_model));
    const pyrocam::ThermalModel& m = *model;
    const auto scene = pyrocam::bench::make_scene(scene_spec, 2045, 1085);
    const auto planes = band_planes(m, pyrocam::bench::render(m, scene));
    std::printf(
        "\n5x5 camera, %dx%d band planes (25 bands), %.0f %% of the frame on the hot "
        "object, model %s\n",
        planes[0].cols, planes[0].rows, 100 * pyrocam::bench::hot_fraction(scene),
        nir_model.c_str());
    // Pixels with saturated or dim bands read from the rest where that is safe, as ratiotemp's
    // default partial-bands=safe reads them (an over-exposed plate reads at all).
    constexpr auto kSafe = pyrocam::TemperatureEstimator::PartialBands::kSafe;
    pyrocam::PlaneEstimator likelihood(model, Method::kLikelihood);
    likelihood.set_partial_bands(kSafe);
    cv::Mat t_fast, t_exhaustive, t_mlp;
    print_timing("likelihood estimate (fast)",
                 time_frames(frames, [&] { likelihood.estimate(planes, t_fast); }));
    print_timing("likelihood estimate_codes (fast)",
                 time_frames(frames, [&] { likelihood.estimate_codes(planes, codes); }));
    // The exhaustive scan in the same plane estimator (the same checks before the fit: the
    // saturation edge drops bands near the level on over-exposed frames).
    pyrocam::PlaneEstimator exhaustive(model, pyrocam::make_exhaustive_likelihood_estimator(model),
                                       Method::kLikelihood);
    exhaustive.set_partial_bands(kSafe);
    print_timing("likelihood, exhaustive scan (reference)",
                 time_frames(0, [&] { exhaustive.estimate(planes, t_exhaustive); }));
    const pyrocam::PlaneEstimator mlp(model, Method::kMlp);
    print_timing("mlp estimate", time_frames(0, [&] { mlp.estimate(planes, t_mlp); }));
    print_agreement("fast likelihood against exhaustive", t_exhaustive, t_fast, 0.01);
  }
  return 0;
}
