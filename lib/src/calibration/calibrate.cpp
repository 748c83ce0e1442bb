#include "pyrocam/calibration/calibrate.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <memory>
#include <sstream>

#include "calibration/stage_support.h"
#include "pyrocam/calibration/calibration_qe.h"
#include "pyrocam/calibration/calibration_uncertainty.h"
#include "pyrocam/calibration/noisy_locus.h"
#include "pyrocam/core/error.h"
#include "pyrocam/runtime/estimator_check.h"

namespace pyrocam {
namespace {

using calibration_detail::Clock;
using calibration_detail::report_stage;
using calibration_detail::since;

// Throws InputError unless the dataset fits the profile and the model's range.
void check_calibration_inputs(const Dataset& dataset, const CameraProfile& profile,
                              const CalibrationOptions& opt) {
  // The model must cover what it is calibrated on: the locus, the network and Table 4 too.
  if (!dataset.mosaic_pattern().empty()) {
    std::string profile_pattern = profile.mosaic.pattern;
    std::transform(profile_pattern.begin(), profile_pattern.end(), profile_pattern.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (profile_pattern != dataset.mosaic_pattern())
      throw InputError((dataset.folder() / kMosaicFile).string() + ": the images are " +
                       dataset.mosaic_pattern() + ", the profile " + profile.name +
                       " describes a " + profile_pattern + " mosaic");
  }
  const std::vector<double> nominal_c = dataset.temperatures_c();
  if (nominal_c.empty()) throw InputError(dataset.folder().string() + ": no frames to calibrate");
  if (nominal_c.size() < 2) {
    std::ostringstream m;
    m << dataset.folder().string() << ": every frame in manifest.csv is at one temperature ("
      << nominal_c.front() << " degC); calibration needs frames at 2 or more temperatures";
    throw InputError(m.str());
  }
  if (!(opt.min_temperature_c >= kModelMinTemperatureC &&
        opt.max_temperature_c <= kModelMaxTemperatureC)) {
    std::ostringstream m;
    m << "the model's range " << opt.min_temperature_c << "-" << opt.max_temperature_c
      << " degC leaves the range a model file may hold, " << kModelMinTemperatureC << "-"
      << kModelMaxTemperatureC << " degC";
    throw InputError(m.str());
  }
  const auto [coolest, hottest] = std::minmax_element(nominal_c.begin(), nominal_c.end());
  if (!(opt.min_temperature_c < opt.max_temperature_c) || *coolest < opt.min_temperature_c ||
      *hottest > opt.max_temperature_c) {
    std::ostringstream m;
    m << dataset.folder().string() << ": calibration temperatures " << *coolest << "-" << *hottest
      << " degC are outside the model's range " << opt.min_temperature_c << "-"
      << opt.max_temperature_c << " degC (--min-temperature, --max-temperature)";
    throw InputError(m.str());
  }
  // A reference the model cannot read would pull the QE towards a temperature it never serves.
  for (const FrameGroup& r : dataset.references())
    if (r.temperature_c < opt.min_temperature_c || r.temperature_c > opt.max_temperature_c) {
      std::ostringstream m;
      m << (dataset.folder() / "manifest.csv").string() << " line " << r.line << ": reference at "
        << r.temperature_c << " degC is outside the model's range " << opt.min_temperature_c << "-"
        << opt.max_temperature_c << " degC (--min-temperature, --max-temperature)";
      throw InputError(m.str());
    }
  // A fitted QE is cross-validated on folds that each leave out some temperatures, and a fold
  // of one temperature gives each band one rate.
  if (nominal_c.size() < 3 && opt.qe_solver != "datasheet") {
    std::ostringstream m;
    m << dataset.folder().string() << ": frames at " << nominal_c.size()
      << " temperatures; fitting the QE needs 3 or more (its cross-validation fits it without "
         "each group of them): add furnace temperatures, or --solver datasheet";
    throw InputError(m.str());
  }
}

// The network on the model camera's locus (and on noisy copies of it when asked for): sets
// out.model.mlp, out.mlp_report and the network's error on the noise-free locus.
void train_network(const Locus& locus, const CalibrationOptions& opt, const StageProgress& progress,
                   CalibrationOutcome& out) {
  ThermalModel& m = out.model;
  MlpTrainingOptions mo = opt.mlp;
  mo.seed = opt.seed;
  NoisyLocusOptions no = opt.noisy_locus;
  std::unique_ptr<NoisyLocus> noisy;
  if (no.copies > 0) {
    noisy = std::make_unique<NoisyLocus>(m, locus, no);
    mo.augment = [&noisy](const std::vector<Eigen::Index>& rows, std::uint64_t seed) {
      return noisy->sample(rows, seed);
    };
  }
  auto user_progress = opt.mlp.progress;
  // One pass per Adam epoch or polish iteration; the polish may stop early.
  const auto passes = static_cast<std::size_t>(mo.epochs + mo.polish_iterations);
  mo.progress = [&](int pass, double train, double test) {
    report_stage(progress, "training MLP", std::min(static_cast<std::size_t>(pass), passes),
                 passes);
    if (user_progress) user_progress(pass, train, test);
  };
  m.mlp = train_mlp(locus.ratios, locus.temperature_c, mo, &out.mlp_report);
  report_stage(progress, "training MLP", passes, passes);
  const Eigen::VectorXd locus_error = m.mlp.predict(locus.ratios) - locus.temperature_c;
  out.mlp_locus_max_error_c = locus_error.cwiseAbs().maxCoeff();
  out.mlp_locus_rms_error_c = std::sqrt(locus_error.squaredNorm() / locus_error.size());
}

}  // namespace

CalibrationOutcome calibrate(const Dataset& dataset, const CameraProfile& profile,
                             const CalibrationOptions& opt, const StageProgress& progress) {
  const auto t_start = Clock::now();
  check_calibration_inputs(dataset, profile, opt);
  CalibrationOutcome out;
  ExtractOptions eo;
  eo.threads = opt.threads;
  eo.offsets = opt.rate_offsets;
  out.rates = extract_rates(dataset, profile, eo, [&](std::size_t d, std::size_t t) {
    report_stage(progress, "reading frames", d, t);
  });
  out.warnings = out.rates.warnings;
  const std::vector<double>& t_c = out.rates.temperatures_c;
  const Eigen::MatrixXd rates = out.rates.rates();
  const Eigen::MatrixXd datasheet = profile.system_qe();

  // Reference sources beyond the furnace: scale-free constraints on the band ratios.
  const std::vector<ReferenceRates> references = out.rates.reference_rates();
  QeChoice qe = choose_system_qe(profile, datasheet, t_c, rates, opt.qe_solver, progress,
                                 references, opt.fit_choices);
  out.solvers = std::move(qe.reports);
  out.qe_spread = std::move(qe.qe_spread);
  ThermalModel& m = out.model;
  m.datasheet_qe = datasheet;
  m.qe_solver = qe.solver;
  m.min_temperature_c = opt.min_temperature_c;
  m.max_temperature_c = opt.max_temperature_c;
  m.camera = CameraModel{profile, qe.system_qe, qe.band_scale};
  const double hottest_furnace_c = *std::max_element(t_c.begin(), t_c.end());
  m.calibrated_up_to_c = hottest_furnace_c;
  for (const ReferenceRates& r : references)
    m.calibrated_up_to_c = std::max(m.calibrated_up_to_c, r.temperature_c);
  const CameraModel sheet_camera{profile, datasheet, band_scale(profile, datasheet, t_c, rates)};
  out.rate_residual_datasheet = rate_residuals(sheet_camera, t_c, rates);
  out.rate_residual_optimised = rate_residuals(m.camera, t_c, rates);

  // The synthetic locus and the network on it.
  const Locus locus =
      make_locus(m.camera, opt.min_temperature_c, opt.max_temperature_c, opt.locus_step_c);
  train_network(locus, opt, progress, out);

  report_stage(progress, "evaluating", 0, 1);
  out.table4 = evaluate_estimators(m, out.rates, locus, sheet_camera, opt.locus_step_c);
  report_stage(progress, "evaluating", 1, 1);
  for (std::string& w : calibration_quality_warnings(out)) out.warnings.push_back(std::move(w));
  // A network that reads graybodies hotter than the range inside it (a narrow range: the colour
  // camera's ratios turn over) makes such surfaces read wrong rather than not at all.
  const AboveRangeFold fold =
      fold_above_range(m, *make_estimator(std::make_shared<const ThermalModel>(m), Method::kMlp));
  if (fold.read_inside > 0) {
    char text[400];
    std::snprintf(text, sizeof text,
                  "the network reads graybodies hotter than the model's range inside it (%.0f "
                  "degC as %.0f degC): with ratiotemp method lut, mlp or auto (colour) a surface "
                  "hotter than %.0f degC reads wrong, not as no reading; use method=likelihood "
                  "with this model, or calibrate to a higher --max-temperature",
                  fold.worst_true_c, fold.worst_read_c, m.max_temperature_c);
    out.warnings.emplace_back(text);
  }

  m.uncertainty = uncertainty_model(m, t_c, rates, opt, progress, references, qe.fit_choices);
  m.uncertainty.u_qe_model_c =
      qe_model_uncertainty(m.camera, qe.posterior, m.uncertainty.temperature_c, qe.prior_fits,
                           hottest_furnace_c, m.calibrated_up_to_c, m.max_temperature_c);
  for (std::size_t r = 0; r < references.size(); ++r) {
    ReferenceCheck check{references[r].name, references[r].temperature_c,
                         references[r].temperature_uncertainty_c};
    if (r < qe.reference_error_after_c.size())
      check.error_datasheet_c = qe.reference_error_before_c[r],
      check.error_fitted_c = qe.reference_error_after_c[r];
    out.references.push_back(check);
  }
  m.provenance = model_provenance(dataset, profile, opt.seed);
  out.seconds = since(t_start);
  out.verdict = calibration_verdict(out);
  m.summary = outcome_summary(out);
  return out;
}

}  // namespace pyrocam
