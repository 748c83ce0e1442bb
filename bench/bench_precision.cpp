// Per-pixel precision against the limit no estimator can beat: for single pixels of a graybody
// of the model's own camera (no model error, noise only), the scatter of each method's readings
// next to the Cramer-Rao bound of the pixel's band signals (core/precision_limit.h), with shot
// noise only (METHOD.md's shot-noise limit) and with the camera's read and quantisation noise
// of frame and dark as well (what a pixel really has). A ratio near 1 is an efficient
// estimator; above 1, information it leaves unused. Pixels are band signals drawn from the
// noise model (Gaussian, independent bands: no demosaicking, which averages samples and shares
// them between pixels), the brightest band at --level DN above dark. Not a test.
//
// Usage: bench_precision --model M.json [--model N.json ...] [--pixels N] [--level DN]
//                        [--temperatures 700,1000,...]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/precision_limit.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"

namespace {

struct Scatter {
  double median = NAN, robust_sd = NAN;  // robust: 1.4826 x the median absolute deviation
  double read_fraction = 0;
};

Scatter scatter_of(std::vector<float> readings) {
  Scatter s;
  const std::size_t all = readings.size();
  readings.erase(
      std::remove_if(readings.begin(), readings.end(), [](float t) { return !std::isfinite(t); }),
      readings.end());
  s.read_fraction = all ? static_cast<double>(readings.size()) / static_cast<double>(all) : 0;
  if (readings.size() < 10) return s;
  const auto median = [](std::vector<float> v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return static_cast<double>(*mid);
  };
  s.median = median(readings);
  std::vector<float> deviation(readings.size());
  for (std::size_t i = 0; i < readings.size(); ++i)
    deviation[i] = static_cast<float>(std::abs(readings[i] - s.median));
  s.robust_sd = 1.4826 * median(deviation);
  return s;
}

void run_model(const std::string& path, const std::vector<double>& temperatures_c, int pixels,
               double level_dn) {
  const auto model = std::make_shared<const pyrocam::ThermalModel>(pyrocam::load_model(path));
  const pyrocam::CameraProfile& p = model->profile();
  const int bands = p.band_count();
  std::vector<pyrocam::Method> methods{pyrocam::Method::kMlp, pyrocam::Method::kLikelihood};
  if (p.normalisation.numerators.size() == 2)
    methods.insert(methods.begin(), pyrocam::Method::kLut);
  std::vector<std::unique_ptr<pyrocam::TemperatureEstimator>> estimators;
  for (pyrocam::Method m : methods) estimators.push_back(pyrocam::make_estimator(model, m));

  std::printf("\n%s (%s, %d bands), single pixels, brightest band %.0f DN, %d pixels each\n",
              p.name.c_str(), path.c_str(), bands, level_dn, pixels);
  std::printf("%7s %9s %9s %9s", "T degC", "electrons", "shot K", "CRB K");
  for (pyrocam::Method m : methods)
    std::printf(" | %-10s %7s %6s %6s", pyrocam::method_name(m).c_str(), "sd K", "/CRB", "bias");
  std::printf("\n");
  std::mt19937_64 rng(20261130);
  std::normal_distribution<double> normal;
  for (double t : temperatures_c) {
    if (t < model->min_temperature_c || t > model->max_temperature_c) continue;
    Eigen::VectorXd mean = model->camera.rates(t);
    mean *= level_dn / mean.maxCoeff();
    const Eigen::VectorXd k = p.dn_per_electron();
    Eigen::VectorXd shot(bands), noise(bands);
    for (int b = 0; b < bands; ++b) {
      shot[b] = k[b] * mean[b];
      noise[b] = pyrocam::signal_variance_dn2(p, b, mean[b]);
    }
    const double shot_limit = pyrocam::temperature_precision_limit_k(model->camera, t, mean, shot);
    const double crb = pyrocam::temperature_precision_limit_k(model->camera, t, mean, noise);
    std::vector<std::vector<float>> planes(static_cast<std::size_t>(bands),
                                           std::vector<float>(static_cast<std::size_t>(pixels)));
    for (int b = 0; b < bands; ++b)
      for (auto& v : planes[static_cast<std::size_t>(b)])
        v = static_cast<float>(mean[b] + std::sqrt(noise[b]) * normal(rng));
    std::vector<const float*> plane_ptrs;
    for (const auto& plane : planes) plane_ptrs.push_back(plane.data());
    std::printf("%7.0f %9.0f %9.2f %9.2f", t, mean.cwiseQuotient(k).sum(), shot_limit, crb);
    for (const auto& e : estimators) {
      std::vector<float> out(static_cast<std::size_t>(pixels));
      e->estimate(plane_ptrs.data(), out.size(), out.data());
      const Scatter s = scatter_of(out);
      if (s.read_fraction < 0.5)
        std::printf(" | %-10s %7s %6s %6s", "", "-", "-", "-");
      else
        std::printf(" | %-10s %7.2f %6.2f %6.2f", "", s.robust_sd, s.robust_sd / crb, s.median - t);
    }
    std::printf("\n");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Per-pixel precision of the estimators against the Cramer-Rao bound"};
  std::vector<std::string> models;
  int pixels = 20000;
  double level_dn = 170;
  std::vector<double> temperatures_c{700, 900, 1100, 1400, 1800, 2200, 2600};
  app.add_option("--model", models, "Calibrated model file(s)")->required();
  app.add_option("--pixels", pixels, "Pixels per temperature")->check(CLI::Range(100, 10000000));
  app.add_option("--level", level_dn, "Brightest band's mean, DN above dark")
      ->check(CLI::Range(1.0, 65535.0));
  app.add_option("--temperatures", temperatures_c, "Temperatures, degC")->delimiter(',');
  CLI11_PARSE(app, argc, argv);
  try {
    std::printf(
        "pyrocam per-pixel precision: the robust sd (1.4826 MAD) of single-pixel readings of a "
        "graybody of the model's own camera, against the Cramer-Rao bound (CRB: shot, read and "
        "quantisation noise of frame and dark) and the shot-noise limit; bias = median - T\n");
    for (const std::string& m : models) run_model(m, temperatures_c, pixels, level_dn);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_precision: %s\n", e.what());
    return 1;
  }
  return 0;
}
