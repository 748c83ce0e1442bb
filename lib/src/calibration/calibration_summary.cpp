#include "pyrocam/calibration/calibration_summary.h"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <sstream>

#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/runtime/extrapolation_pair.h"

namespace pyrocam {
namespace {

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

// Manifest text and ROI size: enough to tell datasets apart in a model's provenance.
std::string dataset_fingerprint(const Dataset& d) {
  std::ifstream in(d.folder() / "manifest.csv");
  std::string text(std::istreambuf_iterator<char>(in), {});
  return fnv1a_hex(text + std::to_string(d.width()) + "x" + std::to_string(d.height()));
}

}  // namespace

double rms_finite(const Eigen::MatrixXd& m) {
  double s = 0;
  int n = 0;
  for (Eigen::Index i = 0; i < m.size(); ++i)
    if (std::isfinite(m.data()[i])) s += m.data()[i] * m.data()[i], ++n;
  return n ? std::sqrt(s / n) : NAN;
}

nlohmann::json model_provenance(const Dataset& dataset, const CameraProfile& profile,
                                std::uint64_t seed) {
  return {{"tool", "pyrocam-calib"},
          {"tool_version", PYROCAM_VERSION},
          {"created_utc", utc_now()},
          {"profile_source", profile.source.string()},
          {"profile_name", profile.name},
          {"dataset_path", std::filesystem::absolute(dataset.folder()).string()},
          {"dataset_manifest_fnv1a64", dataset_fingerprint(dataset)},
          {"seed", seed}};
}

std::vector<std::string> calibration_quality_warnings(const CalibrationOutcome& out) {
  if (out.table4.empty() || out.table4[0].true_c.empty())
    throw InputError(
        "the calibrated model reads none of the furnace settings back (each has a band "
        "saturated or dim at every exposure, or values the profile's camera cannot give): it "
        "cannot be validated, and no model is written. Check the exposures, the profile's bit "
        "depth and thresholds, and that the images hold what the manifest says");
  std::vector<std::string> w;
  std::ostringstream m;
  m.precision(1);
  m << std::fixed;
  const double residual = rms_finite(out.rate_residual_optimised);
  if (residual > kResidualWarn) {
    m << "the fitted QE leaves " << 100 * residual
      << " % rms of the furnace signal rates unexplained (a sound campaign: about 1 %): are the "
         "temperatures in degC (not K), the exposures in microseconds, and every file at its "
         "setting?";
    w.push_back(m.str());
    m.str("");
  }
  const EstimatorScore& network = out.table4[0];
  if (network.rms > kSettingsWarnC) {
    m << "the model reads its own furnace settings " << network.rms << " degC rms off ("
      << network.name << ", " << network.true_c.size()
      << " settings; a sound campaign: about 1 degC): its temperatures cannot be trusted";
    w.push_back(m.str());
  }
  return w;
}

std::string calibration_verdict(const CalibrationOutcome& out) {
  // Verdict in plain words.
  std::ostringstream v;
  v.precision(2);
  v << std::fixed << "rate residual " << 100 * rms_finite(out.rate_residual_optimised)
    << " % rms (datasheet QE: " << 100 * rms_finite(out.rate_residual_datasheet) << " %)";
  if (!out.table4.empty() && std::isfinite(out.table4[0].rms))
    v << "; MLP " << out.table4[0].rms << " degC rms on " << out.table4[0].true_c.size()
      << " calibration settings";
  int skipped_sat = 0, skipped_dim = 0;
  for (const auto& st : out.rates.status)
    for (PointStatus s : st)
      skipped_sat += s == PointStatus::kSaturated, skipped_dim += s == PointStatus::kDim;
  v << "; " << skipped_sat << " band means of the sweeps skipped as saturated, " << skipped_dim
    << " as dim";
  if (!out.warnings.empty())
    v << "; " << out.warnings.size() << (out.warnings.size() == 1 ? " warning" : " warnings");
  return v.str();
}

std::string above_calibration_summary(const ThermalModel& m) {
  const Locus locus = make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1);
  const ExtrapolationPair pair =
      extrapolation_pair(m.camera, locus, m.calibrated_up_to_c, m.max_temperature_c);
  if (!pair.active()) return "";
  const std::vector<std::string>& names = m.profile().band_names;
  int other = 0;
  while (other == pair.numerator || other == pair.denominator) ++other;
  double whole = NAN, last = NAN;  // where the pair reads alone
  for (Eigen::Index k = 0; k < locus.size(); ++k)
    if (pair.weight[static_cast<std::size_t>(k)] >= 1) {
      if (std::isnan(whole)) whole = locus.temperature_c[k];
      last = locus.temperature_c[k];
    }
  char text[400];
  std::snprintf(text, sizeof text,
                "above %.0f degC (the hottest temperature calibrated) the model reads from the "
                "ratio of %s and %s (their light at %.0f degC overlaps %.2f and %.2f with that at "
                "%.0f degC, %s's %.2f)",
                pair.from_c, names[pair.numerator].c_str(), names[pair.denominator].c_str(),
                kExtrapolationOverlapC, pair.overlap[pair.numerator],
                pair.overlap[pair.denominator], pair.from_c, names[other].c_str(),
                pair.overlap[other]);
  std::string s = text;
  if (std::isfinite(whole)) {
    std::snprintf(text, sizeof text, ", alone from %.0f to %.0f degC", whole, last);
    s += text;
  } else {
    s += ", never alone (too noisy)";
  }
  return s;
}

nlohmann::json outcome_summary(const CalibrationOutcome& o) {
  using nlohmann::json;
  json j;
  j["verdict"] = o.verdict;
  j["qe_solver"] = o.model.qe_solver;
  json solvers = json::array();
  for (const auto& s : o.solvers)
    solvers.push_back({{"solver", s.solver},
                       {"calibration_residual_rms", s.calibration_residual},
                       {"held_out_residual_rms", s.held_out_residual},
                       {"qe_change_rms", s.qe_change_rms},
                       {"leak_terms", s.leak_terms},
                       {"prior_widths", s.prior_widths},
                       {"prior_sensitivity", s.prior_sensitivity},
                       {"seconds", s.seconds}});
  j["solvers"] = solvers;
  j["rate_offsets"] = rate_offsets_summary(o.rates.offsets);
  j["rate_residual_rms"] = {{"datasheet", rms_finite(o.rate_residual_datasheet)},
                            {"optimised", rms_finite(o.rate_residual_optimised)}};
  json t4 = json::array();
  for (const auto& s : o.table4)
    t4.push_back({{"estimator", s.name},
                  {"n", s.true_c.size()},
                  {"missing", s.missing},
                  {"mean_c", s.mean},
                  {"std_c", s.std},
                  {"rms_c", s.rms},
                  {"exposure_spread_c", s.exposure_spread}});
  j["table4"] = t4;
  json refs = json::array();
  for (const ReferenceCheck& r : o.references)
    refs.push_back({{"name", r.name},
                    {"temperature_c", r.temperature_c},
                    {"uncertainty_c", r.uncertainty_c},
                    {"error_datasheet_c", r.error_datasheet_c},
                    {"error_fitted_c", r.error_fitted_c}});
  j["references"] = refs;
  j["above_calibration"] = above_calibration_summary(o.model);
  j["mlp"] = {{"final_train_rmse_c", o.mlp_report.final_train_rmse},
              {"final_test_rmse_c", o.mlp_report.final_test_rmse},
              {"locus_max_error_c", o.mlp_locus_max_error_c},
              {"locus_rms_error_c", o.mlp_locus_rms_error_c},
              {"polish_iterations", o.mlp_report.polish_iterations_done},
              {"noisy_copies", o.mlp_report.augmented_samples},
              {"noisy_copies_rmse_c", o.mlp_report.augmented_rmse},
              {"noisy_copies_median_abs_error_c", o.mlp_report.augmented_median_abs_error},
              {"seconds", o.mlp_report.seconds}};
  j["warnings"] = o.warnings;
  j["seconds"] = o.seconds;
  return j;
}

}  // namespace pyrocam
