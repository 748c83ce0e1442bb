// Trains the temperature MLP on the noise-free Planckian locus of a camera and prints how well it
// fits (max and rms error over the whole locus, per temperature range) and how long training
// took: the figures behind the defaults of MlpTrainingOptions.
//
//   bench-mlp-locus                                  both shipped profiles, datasheet QE
//   bench-mlp-locus --model m.json --model n.json    the optimised QE of calibrated models
//   bench-mlp-locus --profile rgb-reference --epochs 200 --polish 400 --seed 3
//
// With --model, the network is also judged off the locus, where every real pixel lies: on
// single-pixel noisy copies of the locus (NoisyLocus at full noise, fresh seed), the reading
// against the likelihood fit of the same signals and against the true temperature (median per
// 100 degC, as a region's median reading). --noisy-copies trains on noisy copies as calibrate
// does.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "pyrocam/calibration/mlp_training.h"
#include "pyrocam/calibration/noisy_locus.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/model.h"

namespace {

using pyrocam::Locus;

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  const auto middle = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), middle, v.end());
  return *middle;
}

// The network's readings of single-pixel noisy copies of the locus, every 10 degC.
void off_locus(const pyrocam::Mlp& model, const pyrocam::ThermalModel& thermal,
               const Locus& locus) {
  pyrocam::NoisyLocusOptions noise;
  noise.copies = 20;
  noise.min_noise_scale = noise.max_noise_scale = 1;
  const pyrocam::NoisyLocus noisy(thermal, locus, noise);
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < locus.size(); i += 10) rows.push_back(i);
  Eigen::VectorXd truth;
  const pyrocam::MlpSamples samples = noisy.sample(rows, 12345, &truth);
  const Eigen::VectorXd reading = model.predict(samples.inputs);
  const double low = locus.temperature_c[0], high = locus.temperature_c[locus.size() - 1];
  std::printf(
      "  single-pixel noisy copies (%d), reading - likelihood fit | median reading - truth\n",
      static_cast<int>(samples.targets.size()));
  for (int part = 0; part < 3; ++part) {
    const double from = low + (high - low) * part / 3, to = low + (high - low) * (part + 1) / 3;
    double vs_fit = 0, fit_vs_truth = 0, median_sq = 0;
    int n = 0, bins = 0, unread = 0;
    for (double bin = from; bin < to - 1e-9; bin += 100) {
      std::vector<double> errors;
      for (Eigen::Index i = 0; i < truth.size(); ++i) {
        if (truth[i] < bin || truth[i] >= bin + 100) continue;
        if (!std::isfinite(reading[i])) {
          ++unread;
          continue;
        }
        vs_fit += (reading[i] - samples.targets[i]) * (reading[i] - samples.targets[i]);
        fit_vs_truth += (samples.targets[i] - truth[i]) * (samples.targets[i] - truth[i]);
        errors.push_back(reading[i] - truth[i]);
        ++n;
      }
      if (errors.empty()) continue;
      const double m = median(errors);
      median_sq += m * m;
      ++bins;
    }
    if (n == 0) {
      std::printf("    %4.0f-%4.0f degC: no copies inside the inference window\n", from, to);
      continue;
    }
    std::printf(
        "    %4.0f-%4.0f degC: rms %6.2f degC (fit vs truth %6.2f) | rms over 100 degC bins %5.2f "
        "degC (%d copies%s)\n",
        from, to, std::sqrt(vs_fit / n), std::sqrt(fit_vs_truth / n), std::sqrt(median_sq / bins),
        n, unread ? ", some unread" : "");
  }
}

void bench(const std::string& name, const Locus& locus, pyrocam::MlpTrainingOptions o,
           const pyrocam::ThermalModel* thermal, const pyrocam::NoisyLocusOptions& noise) {
  std::unique_ptr<pyrocam::NoisyLocus> noisy;
  if (thermal && noise.copies > 0) {
    noisy = std::make_unique<pyrocam::NoisyLocus>(*thermal, locus, noise);
    o.augment = [&noisy](const std::vector<Eigen::Index>& rows, std::uint64_t seed) {
      return noisy->sample(rows, seed);
    };
  }
  pyrocam::MlpTrainingReport report;
  const pyrocam::Mlp model = pyrocam::train_mlp(locus.ratios, locus.temperature_c, o, &report);
  const Eigen::VectorXd error = model.predict(locus.ratios) - locus.temperature_c;
  Eigen::Index worst = 0;
  const double max_error = error.cwiseAbs().maxCoeff(&worst);
  std::printf("%s: %d inputs, %d samples (%d trained on), %.1f s\n", name.c_str(),
              model.input_size(), static_cast<int>(locus.size()), report.train_samples,
              report.seconds);
  std::printf("  locus: max |error| %.3f degC at %.0f degC, rms %.4f degC\n", max_error,
              locus.temperature_c[worst], std::sqrt(error.squaredNorm() / error.size()));
  const double low = locus.temperature_c[0], high = locus.temperature_c[locus.size() - 1];
  for (int part = 0; part < 3; ++part) {
    const double from = low + (high - low) * part / 3, to = low + (high - low) * (part + 1) / 3;
    double part_max = 0;
    for (Eigen::Index i = 0; i < error.size(); ++i) {
      const double t = locus.temperature_c[i];
      if (t >= from && (t < to || part == 2)) part_max = std::max(part_max, std::abs(error[i]));
    }
    std::printf("  %4.0f-%4.0f degC: max |error| %.3f degC\n", from, to, part_max);
  }
  const double after_adam =
      report.epochs > 0 ? report.test_rmse[static_cast<std::size_t>(report.epochs - 1)] : NAN;
  std::printf(
      "  held-out: rmse %.4f degC, max %.3f degC; rmse %.3f degC after %d Adam epochs, "
      "then %d polish iterations\n",
      report.final_test_rmse, report.max_abs_test_error, after_adam, report.epochs,
      report.polish_iterations_done);
  if (report.augmented_samples > 0) {
    std::printf("  trained on %d noisy copies besides: rmse %.3f degC, median |error| %.3f degC\n",
                report.augmented_samples, report.augmented_rmse, report.augmented_median_abs_error);
  }
  if (thermal) off_locus(model, *thermal, locus);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Fit of the temperature MLP to the noise-free Planckian locus"};
  std::vector<std::string> models, profiles;
  double min_c = 500, max_c = 3500, step_c = 1;
  pyrocam::MlpTrainingOptions options;
  pyrocam::NoisyLocusOptions noise;
  noise.copies = 0;
  bool true_target = false;
  app.add_option("--model", models, "Calibrated model file: the locus of its optimised QE");
  app.add_option("--profile", profiles, "Camera profile: the locus of its datasheet QE");
  app.add_option("--min-temperature", min_c, "Locus start, degC")->capture_default_str();
  app.add_option("--max-temperature", max_c, "Locus end, degC")->capture_default_str();
  app.add_option("--step", step_c, "Locus step, degC")->capture_default_str();
  app.add_option("--epochs", options.epochs, "Adam epochs")->capture_default_str();
  app.add_option("--polish", options.polish_iterations, "L-BFGS iterations")->capture_default_str();
  app.add_option("--seed", options.seed, "Seed")->capture_default_str();
  app.add_option("--noisy-copies", noise.copies, "Noisy copies per locus sample (--model only)")
      ->capture_default_str();
  app.add_option("--noise-scale", noise.max_noise_scale, "Largest noise scale of the copies")
      ->capture_default_str();
  app.add_option("--noisy-weight", options.augmented_weight, "Loss weight of a noisy copy")
      ->capture_default_str();
  app.add_flag("--true-target", true_target, "Train noisy copies towards their true temperature");
  app.add_option("--polish-decay", options.polish_weight_decay, "Polish weight penalty")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (true_target) noise.target = pyrocam::NoisyLocusTarget::kTrueTemperature;
  if (models.empty() && profiles.empty()) profiles = {"rgb-reference", "nir5x5-reference"};
  try {
    for (const auto& path : models) {
      const pyrocam::ThermalModel m = pyrocam::load_model(path);
      bench(path, pyrocam::make_locus(m.camera, min_c, max_c, step_c), options, &m, noise);
    }
    for (const auto& name : profiles) {
      const pyrocam::CameraProfile p = pyrocam::load_profile_by_name(name);
      const pyrocam::CameraModel camera{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
      bench(name + " (datasheet QE)", pyrocam::make_locus(camera, min_c, max_c, step_c), options,
            nullptr, noise);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench-mlp-locus: %s\n", e.what());
    return 1;
  }
  return 0;
}
