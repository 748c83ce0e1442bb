// What a calibration is asked for and what it gives back: the options, the stages' reports and
// the outcome that calibrate() (calibrate.h) assembles stage by stage.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "pyrocam/calibration/noisy_locus.h"
#include "pyrocam/calibration/qe_fit.h"
#include "pyrocam/calibration/rate_extraction.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

struct CalibrationOptions {
  std::string qe_solver = "auto";  // paper, regularised, auto (lower held-out error), datasheet
  // The regularised fit's leak terms and prior widths: chosen by the furnace data
  // (RegularisedOptions::leak_terms, prior_scales), or as given.
  QeFitChoices fit_choices;
  // The furnace lines' offsets (ExtractOptions::offsets): tested, or one per band or per
  // temperature as asked.
  RateOffsets rate_offsets = RateOffsets::kSelect;
  double min_temperature_c = 500, max_temperature_c = 3500, locus_step_c = 1;
  MlpTrainingOptions mlp;
  // Noisy copies of the locus the network is trained on besides it (copies 0: none).
  NoisyLocusOptions noisy_locus;
  int monte_carlo_refits = 8;
  double thermocouple_tolerance_c = 4.4;
  std::uint64_t seed = 1;
  unsigned threads = 2;
};

// Temperature errors of one estimator over the calibration settings (paper Table 4).
struct EstimatorScore {
  std::string name;
  std::vector<double> true_c, estimate_c;  // settings where the estimator gave a reading
  int missing = 0;                         // settings with all bands valid but no reading
  double mean = NAN, std = NAN, rms = NAN;
  // Mean over temperatures of the spread across exposures (paper Table 3).
  double exposure_spread = NAN;
};

struct QeSolverReport {
  std::string solver;
  double calibration_residual = NAN;  // rms relative error of normalised rates, all T
  double held_out_residual = NAN;     // the same on temperatures left out of the fit
  double qe_change_rms = NAN;         // rms(Q - Q_datasheet)
  double seconds = 0;
  // The regularised fit's leak terms: "kept" or "dropped", with the test's figures when it chose
  // (RegularisedOptions::leak_terms); empty for other solvers.
  std::string leak_terms;
  // Its priors' widths (prior_widths_summary); empty for other solvers.
  std::string prior_widths;
  // The chosen fit's prior-sensitivity fits and which of them the uncertainty counts
  // (prior_sensitivity_summary); empty for other solvers and fits not chosen.
  std::string prior_sensitivity;
};

// A reference row (a source beyond the furnace) against the model: its reading by the scale-free
// fit of its rates minus its temperature, with the datasheet QE and with the chosen QE.
struct ReferenceCheck {
  std::string name;
  double temperature_c = NAN, uncertainty_c = NAN;
  double error_datasheet_c = NAN, error_fitted_c = NAN;
};

struct CalibrationOutcome {
  ThermalModel model;
  RateTable rates;
  std::vector<QeSolverReport> solvers;  // every solver tried; model.qe_solver is the choice
  Eigen::MatrixXd qe_spread;            // bands x wavelengths, cross-validation std (may be empty)
  Eigen::MatrixXd rate_residual_datasheet, rate_residual_optimised;  // T x bands, relative
  MlpTrainingReport mlp_report;
  double mlp_locus_max_error_c = NAN;  // over the whole noise-free locus
  double mlp_locus_rms_error_c = NAN;
  std::vector<EstimatorScore> table4;
  std::vector<ReferenceCheck> references;
  std::vector<std::string> warnings;
  std::string verdict;
  double seconds = 0;
};

using StageProgress =
    std::function<void(const std::string& stage, std::size_t done, std::size_t total)>;

}  // namespace pyrocam
