// System QE refinement from furnace signal rates (Sala et al. 2025 section 2.7; METHOD.md
// section 4): the paper's evolutionary coordinate search, and a regularised least-squares solve
// that constrains the correction by physics and by its effect at the temperatures of use.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "pyrocam/core/profile.h"

namespace pyrocam {

// Measured signal rates s_b(T_i) (DN/s after dark subtraction, slopes of ROI mean vs exposure).
// A reference source beyond the furnace (a fixed-point cell, a strip lamp, a source read by a
// reference pyrometer): its temperature is known, its absolute scale (aperture, distance,
// emissivity) is not, so it constrains the band ratios only.
struct ReferenceRates {
  std::string name;                        // for messages and the report, e.g. "Pt-C 1738 degC"
  double temperature_c = 0;                // degC
  double temperature_uncertainty_c = 0.5;  // standard uncertainty (k=1), degC; > 0
  Eigen::VectorXd rates;                   // per band, DN/s; NaN (or <= 0) = no usable points
};

struct CalibrationRates {
  std::vector<double> temperatures_c;      // calibration temperatures, degC (any order)
  Eigen::MatrixXd rates;                   // bands x temperatures; NaN (or <= 0) = no usable points
  std::vector<ReferenceRates> references;  // optional; scale-free constraints on the ratios
};

enum class QeSolver { kPaper, kRegularised };

// Whether the regularised fit has its leak terms (RegularisedOptions::leak_sigma's bumps and the
// shape changes' additive leaks): kSelect fits with and without them and keeps them only when
// the data call for them (RegularisedOptions::leak_test_level).
enum class LeakTerms { kSelect, kKeep, kDrop };
const char* to_string(QeSolver solver);

// The paper's search. Defaults are the paper's; fewer sweeps are fine for quick checks.
struct PaperSearchOptions {
  int sweeps = 400;
  int sweeps_per_decade = 100;     // the step shrinks tenfold after this many sweeps
  double step_in_band = 0.01;      // step inside profile.filter_pass_band_nm
  double step_out_of_band = 1e-4;  // step far outside it
  double taper_nm = 100;           // log-linear taper from one to the other outside the band
};

// The regularised solve. Q_b = shift(S_b, h_b) * optics(d_lo, d_hi) * (1 + t_b x + u_b x^2) *
// (1 + tau x) + S_b * leak, with x = (l - pass band centre) / 100 nm, S_b the band's sensor QE,
// optics(d_lo, d_hi) the lens and filters with the filter's pass-band edges moved by d_lo and
// d_hi nm, tau a slope common to all bands (a neutral-density glass or window), leak >= 0 a
// smooth sum of bumps in the optical filter's blocking region shared by all bands (one filter),
// and a free gain per band. The furnace plate's true temperature at each step and each
// reference's are parameters too, near their nominal values; each reference has a free scale.
// Each sigma is a prior standard deviation (a Gaussian penalty); 0 fixes the parameter at the
// datasheet's.
struct RegularisedOptions {
  double relative_noise = 0.005;     // expected relative rms error of a measured rate (the start)
  int noise_passes = 4;              // fits weighting the data by the misfit reached, at most
  double min_relative_noise = 2e-4;  // floor of that estimate
  double tilt_sigma = 0.02;          // per 100 nm
  double curvature_sigma = 0.0;      // per (100 nm)^2; off: trades against the leak, worse highs
  double shift_sigma_nm = 3.0;       // only for bands narrower than narrow_band_fwhm_nm:
  double narrow_band_fwhm_nm = 60;   // for broad bands a shift is a tilt the data cannot tell
  double common_tilt_sigma = 0.05;   // per 100 nm: ND glass, windows (up to +-30 % / 300 nm)
  double edge_shift_sigma_nm = 5.0;  // each pass-band edge of the optical filter
  double furnace_temperature_sigma_c = 1.5;  // true plate temperature against the nominal
  double leak_spacing_nm = 25;               // bump spacing (and half width) of the test
  // The bumps' spacing (and half width) in the fit that keeps the leak terms; leak_spacing_nm
  // where 0 or not finer. Leaks next to a filter edge are narrow, and the furnace cannot tell
  // their width (the data's chi2 changes by 0 to 4 from 25 nm bumps to 10 nm ones on simulated
  // units) while their width sets how much of the hot range they light: broad bumps spread a
  // leak away from the edge, where its share of the signal grows faster with temperature. So
  // kSelect tests for leaks with the broad bumps (fewer amplitudes: a test with more power) and
  // fits those it keeps with these; kKeep fits with these.
  double fine_leak_spacing_nm = 10;
  double leak_sigma = 0.05;            // absolute filter transmission added by a leak
  double leak_curvature_sigma = 0.01;  // second difference between neighbouring bumps
  // Extrapolation control. A leak bump whose share of a band's signal grows by a factor L from
  // the hottest calibration temperature to the hottest of use_temperatures_c has its prior
  // sigma divided by L: the furnace barely sees it, the high range would depend on it.
  std::vector<double> use_temperatures_c{1500, 2000, 2500, 3000};
  int max_iterations = 100;
  // Draws from the Laplace approximation of the posterior at the solution (QeFitResult::
  // posterior): QE solutions that fit the data and the priors about equally well. Where the
  // furnace and references leave the QE unconstrained they spread, which is how the model's
  // uncertainty knows that it extrapolates.
  int posterior_samples = 0;
  std::uint64_t posterior_seed = 5;
  // Shape changes beyond the model's parameters: each band's QE times raised-cosine bumps of
  // this spacing and half width, each bump's relative amplitude N(0, discrepancy_sigma^2) (a
  // datasheet curve is typical: a unit's broad shape differs by a few %), and leaks outside the
  // pass band, bumps of discrepancy_leak_spacing_nm, absolute transmission added, at least 0,
  // with a prior N(0, discrepancy_leak^2). Chosen from that physics, not fitted to a family.
  // With fit_discrepancy they are fitted jointly with the parameters (one Levenberg-Marquardt
  // fit of both, in every reweighting pass), and they vary in the posterior. bench_extrapolation
  // prints what they give (--set discrepancy_sigma=0 for none, fit_discrepancy=0 for the
  // posterior only).
  double discrepancy_sigma = 0.05;
  double discrepancy_spacing_nm = 50;
  double discrepancy_leak = 0.003;
  double discrepancy_leak_spacing_nm = 10;
  bool fit_discrepancy = true;
  // Leaks, bounded at 0, take up the rates' noise as leaks where there are none, and a leak
  // below a short filter edge brightens the hottest readings: a bias above the furnace that more
  // units do not average away. So with kSelect the leak terms stay only where they improve the
  // fit beyond chance: where the data's chi2 (at the noise the fit with them reaches) falls by
  // more than the leak_test_level quantile of chi2 with one degree of freedom per free leak
  // amplitude. Bounded, penalised amplitudes gain less than that from noise alone (on simulated
  // units without leaks the gain stays under 4 where the 95 % quantile is 63 for the 5x5
  // camera's 46 amplitudes), so the test rarely keeps leaks that are not there; the level sets
  // how clearly a real leak must show in the furnace data to be kept.
  LeakTerms leak_terms = LeakTerms::kSelect;
  double leak_test_level = 0.95;
  // The widths above are what a camera of the datasheet's kind is expected to deviate by; a
  // camera may deviate more or less. Every prior on the QE's shape (the list
  // prior_sensitivity_fits scales) is multiplied by each of these factors in turn, and the fit
  // kept is the one whose priors the furnace data make likeliest: the largest evidence (Laplace
  // approximation: the data's fit and noise against the Occam factor of the priors' volume).
  // One factor: no choice.
  std::vector<double> prior_scales{0.5, 1, 2};
};

struct QeFitOptions {
  QeSolver solver = QeSolver::kRegularised;
  PaperSearchOptions paper;
  RegularisedOptions regularised;
};

// The regularised fit's choices of model (RegularisedOptions::leak_terms, prior_scales): made
// by the data, or given; a fit's own (held_fit_choices) for the fits that vary it.
struct QeFitChoices {
  LeakTerms leak_terms = LeakTerms::kSelect;
  std::vector<double> prior_scales = RegularisedOptions{}.prior_scales;
};

struct QeFitDiagnostics {
  // Per band: rms over the calibration temperatures of (simulated / measured - 1), both
  // normalised by their value at the band's hottest usable temperature.
  Eigen::VectorXd residual_before;  // datasheet QE
  Eigen::VectorXd residual_after;   // fitted QE
  Eigen::VectorXd qe_change_rms;    // per band rms(Q - Q_datasheet) over the grid
  // Per reference (CalibrationRates::references): its reading by the scale-free fit of its
  // rates (reference_reading_c) minus its temperature, with the datasheet QE (least-squares
  // gains on the furnace) and with the fitted QE.
  std::vector<double> reference_error_before_c, reference_error_after_c;
  int iterations = 0;  // sweeps (paper) or Gauss-Newton iterations (regularised)
  // Regularised: whether the fit has its leak terms and, where it chose (LeakTerms::kSelect),
  // the data's chi2 gain with them (at their noise), the test's threshold and the free leak
  // amplitudes it counted.
  bool leak_terms = false;
  double leak_chi2_gain = NAN, leak_chi2_threshold = NAN;
  int leak_amplitudes = 0;
  double leak_spacing_nm = NAN;  // the kept leak bumps' spacing; NaN without leak terms
  // Regularised: the factor on the priors' widths the fit kept (RegularisedOptions::
  // prior_scales) and the log of the data's evidence for each factor tried, in their order
  // (Laplace approximation, up to a constant the same for every factor; NaN where the fit's
  // curvature could not be factored).
  double prior_scale = 1;
  std::vector<double> prior_scales_tried, log_evidence;
  double wall_time_s = 0;
};

// One plausible camera: a system QE and its band gains. A first-order sample around the fit:
// the QE may dip slightly below 0 where the fit's is 0 (it is only read, never shown).
struct QeSample {
  Eigen::MatrixXd system_qe;
  Eigen::VectorXd gains;
};

// A regularised fit at other prior widths than a fit kept (RegularisedOptions::prior_scales).
struct PriorWidthFit {
  double prior_scale = 1;     // the factor on the nominal widths
  double log_evidence = NAN;  // as QeFitDiagnostics::log_evidence
  bool leak_terms = false;    // whether it has the leak terms (QeFitDiagnostics::leak_terms)
  QeSample fit;
};

struct QeFitResult {
  QeSolver solver = QeSolver::kRegularised;
  Eigen::MatrixXd system_qe;  // bands x wavelengths on profile.grid, within [0, 1]
  // k_b: measured rate / signal_rates(profile, system_qe, T) (which already holds etendue and
  // band gains). Paper: at the band's hottest usable temperature; regularised: least squares
  // over all temperatures.
  Eigen::VectorXd gains;
  QeFitDiagnostics diagnostics;
  std::vector<QeSample> posterior;  // regularised only, RegularisedOptions::posterior_samples
  // Regularised, where it chose its prior widths: the fits at the factors it did not keep, for
  // prior_sensitivity_fits.
  std::vector<PriorWidthFit> other_widths;
};

// Fits the QE. Throws InputError when shapes disagree, or naming the band when a band has fewer
// than two usable rates.
QeFitResult fit_qe(const CameraProfile& profile, const CalibrationRates& data,
                   const QeFitOptions& options = {});
QeFitResult fit_qe_paper(const CameraProfile& profile, const CalibrationRates& data,
                         const PaperSearchOptions& options = {});
QeFitResult fit_qe_regularised(const CameraProfile& profile, const CalibrationRates& data,
                               const RegularisedOptions& options = {});

// `options` with the choices the regularised `fit` made: its leak terms (kKeep or kDrop) and
// its priors' widths (prior_scales: the one kept); unchanged for the paper's solver. For the
// fits that vary that fit (prior sensitivity, cross-validation folds, Monte-Carlo refits): they
// then spread the chosen model instead of also choosing again.
QeFitOptions holding_fit_choices(QeFitOptions options, const QeFitResult& fit);
// The same as choices: those `fit` made (the defaults for the paper's solver).
QeFitChoices held_fit_choices(const QeFitResult& fit);
// `options` with `choices` in its regularised options.
QeFitOptions with_fit_choices(QeFitOptions options, const QeFitChoices& choices);

// The regularised fit's prior widths in words: the factor kept and, where it chose, the
// evidence of each factor tried; empty for the paper's solver.
std::string prior_widths_summary(const QeFitResult& fit);

// The regularised fit's leak terms in words: "kept" or "dropped", with the test's chi2 gain,
// threshold and amplitudes where it chose; empty for the paper's solver.
std::string leak_terms_summary(const QeFitResult& fit);

// The calibrated model's signal rates, DN/s: gains .* signal_rates(profile, system_qe, T).
Eigen::VectorXd fitted_signal_rates(const CameraProfile& profile, const QeFitResult& fit,
                                    double temperature_k, double emissivity = 1.0);

// The temperature whose modelled rates gains .* signal_rates(profile, system_qe, T) best match
// `rates` up to one common scale (least squares in log rate over the usable bands), degC over
// 300-4000; NaN with fewer than two usable bands.
double reference_reading_c(const CameraProfile& profile, const Eigen::MatrixXd& system_qe,
                           const Eigen::VectorXd& gains, const Eigen::VectorXd& rates);

// Per band rms of the normalised-rate residual (see QeFitDiagnostics) for any system QE.
Eigen::VectorXd normalised_rate_residuals(const CameraProfile& profile,
                                          const Eigen::MatrixXd& system_qe,
                                          const CalibrationRates& data);

// Per band rms of (fitted_signal_rates / measured - 1) over the usable rates of `data`: the error
// of predicting absolute rates at temperatures the fit may not have seen.
Eigen::VectorXd prediction_residuals(const CameraProfile& profile, const QeFitResult& fit,
                                     const CalibrationRates& data);

// How much the regularised `fit` depends on its priors, which the furnace cannot decide above
// its range: the same fit with every prior on the QE's shape (tilts, shifts, the common slope,
// the filter's edges, leaks and the shape changes beyond the model) `factor` times wider, then
// `factor` times narrower, than the widths `fit` kept, with the leak terms it chose
// (holding_fit_choices; `options`: those `fit` was made with); the furnace temperatures' prior
// is kept. Each fits the data about as well as the fit itself and may extrapolate otherwise:
// qe_model_uncertainty takes the largest reading change they make as a term of its own. Only
// the fits the data do not reject count (Occam's window, Madigan and Raftery 1994): those whose
// evidence is at least 1 / occam_odds of the largest among `fit` and them (a fit whose evidence
// could not be computed counts); infinity counts both. A fit `fit` made while choosing its
// widths (QeFitResult::other_widths) is reused where it is the same fit: the same factor and
// the same leak terms. No fits for the paper's solver.
struct PriorSensitivity {
  std::vector<PriorWidthFit> fits;  // factor times the kept widths, then 1 / factor times
  std::vector<bool> counted;        // per fit: within the window
  double best_log_evidence = NAN;   // the largest among `fit` and them
  double occam_odds = 20;
  std::vector<QeSample> counted_fits() const;
};
PriorSensitivity prior_sensitivity(const CameraProfile& profile, const CalibrationRates& data,
                                   const QeFitOptions& options, const QeFitResult& fit,
                                   double factor = 2, double occam_odds = 20);
// The fits that count (prior_sensitivity's counted_fits).
std::vector<QeSample> prior_sensitivity_fits(const CameraProfile& profile,
                                             const CalibrationRates& data,
                                             const QeFitOptions& options, const QeFitResult& fit,
                                             double factor = 2, double occam_odds = 20);
// In words, e.g. "2 x nominal counted; 0.5 x nominal left out (log evidence 24.2 below the
// best, window 3.0)"; empty without fits.
std::string prior_sensitivity_summary(const PriorSensitivity& sensitivity);

// Paper section 3.1: refit leaving out one of `groups` interleaved temperature groups (sorted
// temperatures, i-th goes to group i % groups).
struct CrossValidation {
  Eigen::MatrixXd qe_spread;         // bands x wavelengths: std of the fitted QE over folds
  Eigen::VectorXd heldout_residual;  // per band rms prediction error on held-out temperatures
  std::vector<QeFitResult> folds;
};
CrossValidation cross_validate(const CameraProfile& profile, const CalibrationRates& data,
                               const QeFitOptions& options = {}, int groups = 5);

// Fit on all but the `hottest_held_out` hottest temperatures, test on those.
struct ExtrapolationCheck {
  double fitted_up_to_c = 0;
  Eigen::VectorXd heldout_residual;  // per band rms prediction error on the hottest temperatures
  QeFitResult fit;
};
ExtrapolationCheck extrapolation_check(const CameraProfile& profile, const CalibrationRates& data,
                                       const QeFitOptions& options = {}, int hottest_held_out = 5);

}  // namespace pyrocam
