// Trains the temperature MLP on the noise-free Planckian locus of a camera and prints how well it
// fits (max and rms error over the whole locus, per temperature range) and how long training
// took: the figures behind the defaults of MlpTrainingOptions.
//
//   bench-mlp-locus                                  both shipped profiles, datasheet QE
//   bench-mlp-locus --model m.json --model n.json    the optimised QE of calibrated models
//   bench-mlp-locus --profile rgb-reference --epochs 200 --polish 400 --seed 3
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pyrocam/locus.h"
#include "pyrocam/mlp.h"
#include "pyrocam/model.h"
#include "pyrocam/profile.h"

namespace {

using pyrocam::Locus;

void bench(const std::string& name, const Locus& locus, const pyrocam::MlpTrainingOptions& o) {
  pyrocam::MlpTrainingReport report;
  const pyrocam::Mlp model = pyrocam::Mlp::train(locus.ratios, locus.temperature_c, o, &report);
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
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Fit of the temperature MLP to the noise-free Planckian locus"};
  std::vector<std::string> models, profiles;
  double min_c = 500, max_c = 3500, step_c = 1;
  pyrocam::MlpTrainingOptions options;
  app.add_option("--model", models, "Calibrated model file: the locus of its optimised QE");
  app.add_option("--profile", profiles, "Camera profile: the locus of its datasheet QE");
  app.add_option("--min-temperature", min_c, "Locus start, degC")->capture_default_str();
  app.add_option("--max-temperature", max_c, "Locus end, degC")->capture_default_str();
  app.add_option("--step", step_c, "Locus step, degC")->capture_default_str();
  app.add_option("--epochs", options.epochs, "Adam epochs")->capture_default_str();
  app.add_option("--polish", options.polish_iterations, "L-BFGS iterations")->capture_default_str();
  app.add_option("--seed", options.seed, "Seed")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (models.empty() && profiles.empty()) profiles = {"rgb-reference", "nir5x5-reference"};
  try {
    for (const auto& path : models) {
      const pyrocam::ThermalModel m = pyrocam::load_model(path);
      bench(path, pyrocam::make_locus(m.camera, min_c, max_c, step_c), options);
    }
    for (const auto& name : profiles) {
      const pyrocam::CameraProfile p = pyrocam::load_profile_by_name(name);
      const pyrocam::CameraModel camera{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
      bench(name + " (datasheet QE)", pyrocam::make_locus(camera, min_c, max_c, step_c), options);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench-mlp-locus: %s\n", e.what());
    return 1;
  }
  return 0;
}
