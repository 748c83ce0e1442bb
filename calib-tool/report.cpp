#include "report.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "pyrocam/calibration/calibration_summary.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/spectrum.h"
#include "svg_plot.h"

namespace pyrocam::cli {
namespace {

const char* kColours[] = {"#d62728", "#2ca02c", "#1f77b4", "#ff7f0e", "#9467bd",
                          "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

std::string colour(std::size_t i) { return kColours[i % 10]; }

std::vector<double> to_vec(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

std::string num(double v, int digits = 2) {
  if (!std::isfinite(v)) return "–";
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

// The furnace's lowest and hottest temperatures (NaN, NaN without any).
std::pair<double, double> furnace_span(const CalibrationOutcome& o) {
  const auto& t = o.rates.temperatures_c;
  if (t.empty()) return {NAN, NAN};
  const auto [lo, hi] = std::minmax_element(t.begin(), t.end());
  return {*lo, *hi};
}

// The library's texts say degC (they go to terminals too); the page says °C.
std::string with_degree_signs(std::string text) {
  for (std::size_t at = text.find("degC"); at != std::string::npos; at = text.find("degC", at))
    text.replace(at, 4, "°C");
  return text;
}

// Bands to plot: all for colour cameras, a handful spread over the range for 25 bands.
std::vector<int> plotted_bands(int bands) {
  std::vector<int> out;
  const int step = bands > 6 ? bands / 5 : 1;
  for (int b = 0; b < bands; b += step) out.push_back(b);
  return out;
}

// A plot title's note of the bands left out ("" when all are shown).
std::string bands_shown(int bands) {
  const std::size_t shown = plotted_bands(bands).size();
  return shown == static_cast<std::size_t>(bands)
             ? ""
             : " (" + std::to_string(shown) + " of " + std::to_string(bands) + " bands)";
}

}  // namespace

void write_report_json(const CalibrationOutcome& o, const std::filesystem::path& path) {
  nlohmann::json j = outcome_summary(o);
  j["profile"] = o.model.profile().name;
  j["provenance"] = o.model.provenance;
  nlohmann::json fits = nlohmann::json::array();
  for (std::size_t t = 0; t < o.rates.temperatures_c.size(); ++t)
    for (std::size_t b = 0; b < o.rates.band_names.size(); ++b) {
      const SlopeFit& f = o.rates.fits[t][b];
      fits.push_back(
          {{"temperature_c", o.rates.temperatures_c[t]},
           {"band", o.rates.band_names[b]},
           {"rate_dn_per_s", std::isfinite(f.rate_dn_per_s) ? nlohmann::json(f.rate_dn_per_s)
                                                            : nlohmann::json(nullptr)},
           {"r_squared",
            std::isfinite(f.r_squared) ? nlohmann::json(f.r_squared) : nlohmann::json(nullptr)},
           {"points", f.points}});
    }
  j["slope_fits"] = fits;
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out) throw InputError(path.string() + ": cannot write report");
}

namespace {

// The page head, title, verdict and what was calibrated from what.
void html_head(const CalibrationOutcome& o, std::ostream& h) {
  const ThermalModel& m = o.model;
  const CameraProfile& p = o.model.profile();
  h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>pyrocam calibration: "
    << html_escape(p.name)
    << "</title><style>body{font-family:sans-serif;max-width:1100px;"
       "margin:auto;padding:1em}table{border-collapse:collapse}td,th{border:1px solid #ccc;"
       "padding:3px 8px;text-align:right}th{background:#f4f4f4}.verdict{font-size:1.15em;"
       "background:#eef6ee;padding:.6em;border-left:4px solid #2ca02c}svg{margin:.4em}</style>"
       "</head><body>";
  h << "<h1>Calibration of " << html_escape(p.name) << "</h1>";
  h << "<p class='verdict'>" << html_escape(with_degree_signs(o.verdict)) << "</p>";
  const auto [furnace_lo, furnace_hi] = furnace_span(o);
  h << "<p><b>Furnace data " << num(furnace_lo, 0) << "–" << num(furnace_hi, 0)
    << " °C</b>; the model reads " << num(m.min_temperature_c, 0) << "–"
    << num(m.max_temperature_c, 0) << " °C, and outside the furnace's range it extrapolates. ";
  if (o.references.empty())
    h << "No reference sources beyond the furnace: readings above " << num(furnace_hi, 0)
      << " °C rest on the QE model alone, and their uncertainty (u QE model, below) grows with "
         "the distance from the furnace's range. ";
  else
    h << o.references.size()
      << " reference source(s) beyond the furnace constrained the QE fit (below). ";
  if (const std::string pair = above_calibration_summary(m); !pair.empty())
    h << html_escape(with_degree_signs("Reading: " + pair)) << ". ";
  h << "</p><p>QE solver chosen: <b>" << html_escape(m.qe_solver) << "</b>. Calibration took "
    << num(o.seconds, 1) << " s. Created " << html_escape(m.provenance.value("created_utc", ""))
    << " from <code>" << html_escape(m.provenance.value("dataset_path", "")) << "</code>.</p>";
}

// Paper Table 4: every estimator on the calibration data.
void table4_section(const CalibrationOutcome& o, std::ostream& h) {
  h << "<h2>Temperature error on the calibration data (Table 4 of Sala et al., Sensors 2025, 25, "
       "3094)</h2><table><tr>"
       "<th>estimator</th><th>settings</th><th>mean °C</th><th>std °C</th><th>rms °C</th>"
       "<th>exposure spread °C</th></tr>";
  for (const auto& s : o.table4)
    h << "<tr><td style='text-align:left'>" << html_escape(s.name) << "</td><td>" << s.true_c.size()
      << (s.missing ? " (+" + std::to_string(s.missing) + " no reading)" : "") << "</td><td>"
      << num(s.mean) << "</td><td>" << num(s.std) << "</td><td>" << num(s.rms) << "</td><td>"
      << num(s.exposure_spread) << "</td></tr>";
  h << "</table><p>Each estimator reads the ROI's mean signals of every furnace setting; "
       "<i>exposure spread</i>: the spread of one temperature's readings over its exposures, "
       "averaged over temperatures. <i>Ohno</i>: the nearest point of the locus refined by "
       "triangular interpolation between its samples (the paper's baseline).";
  if (o.model.profile().band_count() == 3)
    h << " The paper's figures for its colour camera: MLP 3.7 °C rms, Ohno with optimised QE "
         "6.0 °C, two-colour 35.5 °C, Ohno with datasheet QE about 100× worse.";
  h << "</p>";
}

// The QE solvers and the datasheet vs optimised QE (and its cross-validation spread).
void qe_section(const CalibrationOutcome& o, std::ostream& h) {
  const ThermalModel& m = o.model;
  const CameraProfile& p = o.model.profile();
  const auto bands = plotted_bands(p.band_count());
  h << "<h2>QE optimisation</h2><table><tr><th>solver</th><th>fit residual</th>"
       "<th>held-out residual</th><th>rms(Q − Q<sub>datasheet</sub>)</th><th>leak terms</th>"
       "<th>prior widths</th><th>time s</th></tr>";
  for (const auto& s : o.solvers)
    h << "<tr><td style='text-align:left'>" << html_escape(s.solver) << "</td><td>"
      << num(100 * s.calibration_residual) << " %</td><td>" << num(100 * s.held_out_residual)
      << " %</td><td>" << num(s.qe_change_rms, 5) << "</td><td style='text-align:left'>"
      << html_escape(s.leak_terms.empty() ? "—" : s.leak_terms)
      << "</td><td style='text-align:left'>"
      << html_escape(s.prior_widths.empty() ? "—" : s.prior_widths)
      << (s.prior_sensitivity.empty() ? "" : "; uncertainty's prior fits: ")
      << html_escape(s.prior_sensitivity) << "</td><td>" << num(s.seconds, 1) << "</td></tr>";
  h << "</table><p>Fit residual: the rms relative error of the normalised band rates (each "
       "band's rates over its rate at the hottest usable temperature) that the solver's QE "
       "leaves at the furnace temperatures; held-out residual: the same on groups of "
       "temperatures left out of the fit in turn (for the datasheet solver, which fits nothing, "
       "the same figure). Leak terms: the regularised fit's leaks outside the pass band stay only "
       "where the furnace data call for them (a chi-squared test: the fit's chi2 with them must "
       "fall by more than its 95 % quantile with one degree of freedom per leak amplitude, the "
       "<i>chi2 gain</i>): fitted to noise they would read high above the furnace range. Prior "
       "widths: the fit's priors on the QE's shape at half, once and twice their "
       "nominal widths, the one the furnace data make likeliest kept (the largest evidence): a "
       "camera that deviates from its datasheet more than the nominal priors expect gets wider "
       "ones, and extrapolates less from the datasheet's shape (<i>log evidence</i>: the log of "
       "the "
       "probability of the furnace data under those priors, Laplace approximation; larger is "
       "likelier). The uncertainty's prior fits: the chosen fit again with its priors twice and "
       "half as wide; the change of reading they make is a term of the QE-model uncertainty, "
       "counted only for those whose evidence is at least 1/20 of the best (<i>Occam's "
       "window</i>).</p>";
  std::vector<Series> qe;
  for (std::size_t i = 0; i < bands.size(); ++i) {
    const int b = bands[i];
    qe.push_back({p.band_names[b] + " datasheet", to_vec(p.grid.nm()),
                  to_vec(m.datasheet_qe.row(b).transpose()), colour(i), false, true});
    qe.push_back({p.band_names[b] + " optimised", to_vec(p.grid.nm()),
                  to_vec(m.camera.system_qe.row(b).transpose()), colour(i)});
  }
  h << svg_plot({"System QE: datasheet (dashed) and optimised" + bands_shown(p.band_count()),
                 "wavelength (nm)", "system QE (log)", true, 1000, 420},
                qe);
  if (o.qe_spread.size() > 0) {
    std::vector<Series> spread;
    for (std::size_t i = 0; i < bands.size(); ++i)
      spread.push_back({p.band_names[bands[i]], to_vec(p.grid.nm()),
                        to_vec(o.qe_spread.row(bands[i]).transpose()), colour(i)});
    h << svg_plot({"Cross-validation spread of the optimised QE (5 temperature groups)" +
                       bands_shown(p.band_count()),
                   "wavelength (nm)", "std of system QE", false, 1000, 320},
                  spread);
  }
}

// Measured vs simulated signal rates, their residuals and the slope fits.
void rates_section(const CalibrationOutcome& o, std::ostream& h) {
  const CameraProfile& p = o.model.profile();
  const auto& t_c = o.rates.temperatures_c;
  const auto bands = plotted_bands(p.band_count());
  const Eigen::MatrixXd measured = o.rates.rates();
  // Each step's part common to all bands (its plate off the nominal temperature) taken out.
  Eigen::MatrixXd own = o.rate_residual_optimised;
  for (Eigen::Index t = 0; t < own.rows(); ++t) {
    double sum = 0;
    int n = 0;
    for (Eigen::Index b = 0; b < own.cols(); ++b)
      if (std::isfinite(own(t, b))) sum += own(t, b), ++n;
    if (n > 0) own.row(t).array() -= sum / n;
  }
  std::vector<Series> rates, resid, resid_own;
  for (std::size_t i = 0; i < bands.size(); ++i) {
    const int b = bands[i];
    std::vector<double> sheet, opt;
    for (std::size_t t = 0; t < t_c.size(); ++t) {
      sheet.push_back(measured(t, b) * (1 + o.rate_residual_datasheet(t, b)));
      opt.push_back(measured(t, b) * (1 + o.rate_residual_optimised(t, b)));
    }
    rates.push_back({p.band_names[b] + " measured", t_c, to_vec(measured.col(b)), colour(i), true});
    rates.push_back({p.band_names[b] + " optimised", t_c, opt, colour(i)});
    rates.push_back({p.band_names[b] + " datasheet", t_c, sheet, colour(i), false, true});
    resid.push_back(
        {p.band_names[b], t_c, to_vec(100 * o.rate_residual_optimised.col(b)), colour(i)});
    resid_own.push_back({p.band_names[b], t_c, to_vec(100 * own.col(b)), colour(i)});
  }
  // How much a band's rate moves for 1 °C at 1000 °C, from the model.
  const Eigen::ArrayXd r0 = o.model.camera.rates(1000).array(),
                       r1 = o.model.camera.rates(1001).array();
  const Eigen::ArrayXd per_degree = 100 * (r1 / r0 - 1);
  const std::string shown = bands_shown(p.band_count());
  h << "<h2>Signal rates</h2>"
    << svg_plot(
           {"Measured (points) vs simulated rates: optimised (line), datasheet (dashed)" + shown,
            "temperature (°C)", "signal rate (DN/s, log)", true, 1000, 420},
           rates)
    << svg_plot({"Residual of the optimised model" + shown, "temperature (°C)",
                 "modelled/measured − 1 (%)", false, 1000, 300},
                resid)
    << svg_plot({"The same less each step's part common to all bands" + shown, "temperature (°C)",
                 "residual − the step's mean over bands (%)", false, 1000, 300},
                resid_own)
    << "<p>Offsets of the lines of net signal against exposure: "
    << html_escape(rate_offsets_summary(o.rates.offsets)) << ".</p>"
    << "<p>At the nominal furnace temperatures: where the plate was off its nominal temperature "
       "every band moves together (here "
    << num(per_degree.minCoeff(), 2) << "–" << num(per_degree.maxCoeff(), 2)
    << " % per °C at 1000 °C, by band), which the fit takes as that step's temperature error; "
       "what the QE model cannot explain shows as bands moving apart (the second plot).</p>";
  // Every band's rms residual, the plots showing a few of many.
  const auto rms_of = [](const Eigen::MatrixXd& m, Eigen::Index b) {
    double sum = 0;
    int n = 0;
    for (Eigen::Index t = 0; t < m.rows(); ++t)
      if (std::isfinite(m(t, b))) sum += m(t, b) * m(t, b), ++n;
    return n > 0 ? 100 * std::sqrt(sum / n) : NAN;
  };
  h << "<table><tr><th>band</th><th>rms residual, datasheet QE (%)</th><th>optimised QE (%)</th>"
       "<th>optimised, less each step's common part (%)</th></tr>";
  for (int b = 0; b < p.band_count(); ++b)
    h << "<tr><td>" << html_escape(p.band_names[b]) << "</td><td>"
      << num(rms_of(o.rate_residual_datasheet, b)) << "</td><td>"
      << num(rms_of(o.rate_residual_optimised, b)) << "</td><td>" << num(rms_of(own, b))
      << "</td></tr>";
  h << "</table>";

  // Slope fits.
  std::vector<Series> r2;
  for (std::size_t i = 0; i < bands.size(); ++i) {
    std::vector<double> v;
    for (std::size_t t = 0; t < t_c.size(); ++t) v.push_back(o.rates.fits[t][bands[i]].r_squared);
    r2.push_back({p.band_names[bands[i]], t_c, v, colour(i), true});
  }
  h << svg_plot({"Slope fits of ROI signal vs exposure: R²" + shown, "temperature (°C)", "R²",
                 false, 1000, 280},
                r2);
}

// The Planckian locus in the model's ratio space, the furnace measurements on it. Colour: the two
// normalised ratios; more bands: the shortest- and longest-wavelength numerators' ratios.
void locus_section(const CalibrationOutcome& o, std::ostream& h) {
  const ThermalModel& m = o.model;
  const CameraProfile& p = m.profile();
  const std::vector<int>& numerators = p.normalisation.numerators;
  if (numerators.empty()) return;
  const Eigen::Index ix = 0, iy = static_cast<Eigen::Index>(numerators.size()) - 1;
  const Locus locus = make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 5);
  Series line{"locus (model)", to_vec(locus.ratios.col(ix)), to_vec(locus.ratios.col(iy)),
              colour(2)};
  Series ticks{"every 500 °C", {}, {}, colour(2), true};
  for (Eigen::Index i = 0; i < locus.size(); ++i) {
    const double t = locus.temperature_c(i);
    if (std::fmod(t, 500.0) != 0) continue;
    ticks.x.push_back(locus.ratios(i, ix));
    ticks.y.push_back(locus.ratios(i, iy));
    ticks.labels.push_back(num(t, 0) + " °C");
  }
  // The furnace's measured rates, normalised the same way; labelled every 100 degC.
  const Eigen::MatrixXd measured = o.rates.rates();
  Series furnace{"furnace (measured)", {}, {}, colour(0), true};
  for (Eigen::Index t = 0; t < measured.rows(); ++t) {
    const Eigen::VectorXd r = normalised_ratios(p.normalisation, measured.row(t).transpose());
    const double t_c = o.rates.temperatures_c[static_cast<std::size_t>(t)];
    furnace.x.push_back(r(ix));
    furnace.y.push_back(r(iy));
    // (Not where the locus's own 500 degC ticks are labelled: the two would overlap.)
    furnace.labels.push_back(std::fmod(t_c, 100.0) == 0 && std::fmod(t_c, 500.0) != 0 ? num(t_c, 0)
                                                                                      : "");
  }
  const auto ratio_name = [&](Eigen::Index i) {
    std::string ref;
    for (int b : p.normalisation.reference) ref += (ref.empty() ? "" : ",") + p.band_names[b];
    return p.band_names[numerators[static_cast<std::size_t>(i)]] + " / " +
           (p.normalisation.reference.size() > 1 ? "mean(" + ref + ")" : ref);
  };
  h << "<h2>Planckian locus</h2><p>The model's locus from " << num(m.min_temperature_c, 0) << " to "
    << num(m.max_temperature_c, 0)
    << " °C in its normalised band ratios (what the estimators read), and the furnace "
       "measurements' ratios: on a good calibration they lie on the locus at their temperatures.";
  if (numerators.size() > 2)
    h << " Shown: two of the " << numerators.size() << " ratios, the first and the last numerator.";
  h << "</p>"
    << svg_plot({"Planckian locus and furnace measurements", ratio_name(ix), ratio_name(iy), false,
                 1000, 520, "locus-plot"},
                {line, ticks, furnace});
}

// The temperature error of every furnace setting (temperature and exposure) per estimator.
void setting_errors_section(const CalibrationOutcome& o, std::ostream& h) {
  // The estimators the elements read with; the baselines' errors (the table above) are far
  // larger and would flatten these to a line. All of them if those names are not found.
  const auto runtime = [](const std::string& name) {
    return name == "MLP" || name == "likelihood fit";
  };
  bool any = false;
  for (const EstimatorScore& s : o.table4) any = any || runtime(s.name);
  std::vector<Series> series;
  for (std::size_t i = 0; i < o.table4.size(); ++i) {
    const EstimatorScore& s = o.table4[i];
    if (any && !runtime(s.name)) continue;
    Series e{s.name, s.true_c, {}, colour(i), true};
    for (std::size_t k = 0; k < s.true_c.size(); ++k) e.y.push_back(s.estimate_c[k] - s.true_c[k]);
    series.push_back(std::move(e));
  }
  h << "<h2>Error per furnace setting</h2><p>Each point is one furnace setting (a temperature and "
       "an exposure time): the estimator's reading of the ROI's mean signals minus the furnace "
       "temperature. Points of one temperature spread over its exposures. Shown: the network "
       "and the likelihood fit (the baselines' errors are in the table above).</p>"
    << svg_plot({"Temperature error per setting", "furnace temperature (°C)",
                 "reading − furnace (°C)", false, 1000, 420, "setting-error-plot"},
                series);
}

// The temperature network: locus error and training curve.
void network_section(const CalibrationOutcome& o, std::ostream& h) {
  // One pass per Adam epoch, then per L-BFGS iteration of the polish.
  const std::vector<double> passes(o.mlp_report.pass.begin(), o.mlp_report.pass.end());
  h << "<h2>Temperature network</h2><p>Max error over the noise-free locus: "
    << num(o.mlp_locus_max_error_c, 3) << " °C; held-out rmse "
    << num(o.mlp_report.final_test_rmse, 3) << " °C.";
  if (o.mlp_report.augmented_samples > 0) {
    h << " Trained besides on " << o.mlp_report.augmented_samples
      << " noisy single-pixel copies of the locus's training samples, towards the likelihood "
         "fit's reading of each, so that pixels off the locus read as that fit reads them: "
         "the network's rmse from those readings "
      << num(o.mlp_report.augmented_rmse, 3) << " °C, median |difference| "
      << num(o.mlp_report.augmented_median_abs_error, 3) << " °C.";
  }
  h << " Trained by Adam (stochastic gradient steps), then polished by L-BFGS (a quasi-Newton "
       "method) on the whole training set.</p>"
    << svg_plot({"MLP training curve: " + std::to_string(o.mlp_report.epochs) +
                     (o.mlp_report.epochs == 1 ? " Adam epoch, then " : " Adam epochs, then ") +
                     std::to_string(o.mlp_report.polish_iterations_done) + " L-BFGS iterations",
                 "pass over the training set", "rmse (°C, log)", true, 1000, 320},
                {{"train", passes, o.mlp_report.train_rmse, colour(2)},
                 {"test", passes, o.mlp_report.test_rmse, colour(0)}});
}

// The systematic GUM terms over the model range.
void uncertainty_section(const CalibrationOutcome& o, std::ostream& h) {
  const ThermalModel& m = o.model;
  const UncertaintyModel& u = m.uncertainty;
  std::vector<double> total;
  for (double t : u.temperature_c) total.push_back(u.coverage_factor * u.systematic_u_c(t));
  h << "<h2>Uncertainty model (GUM)</h2><p>Systematic terms; each pixel adds its own signal-noise "
       "term at inference. Thermocouple ±"
    << num(u.thermocouple_tolerance_c, 1) << " °C (rectangular) ";
  if (u.monte_carlo_refits > 1)
    h << "by " << u.monte_carlo_refits
      << " Monte-Carlo refits, each with one deviation of the thermocouple, linear in "
         "temperature and within the tolerance at the coldest and the hottest furnace step; ";
  else
    h << "without Monte-Carlo refits (the datasheet solver, or <code>--mc-refits</code> 0 or "
         "1): u calibration is the tolerance over √3 at every temperature; ";
  h << "emissivity slope "
       "u(α) = "
    << num(100 * u.emissivity_slope_u, 1)
    << " % per 100 nm (the relative change of the emissivity over 100 nm of wavelength; a grey "
       "body has none), either sign.</p>";
  const auto [furnace_lo, furnace_hi] = furnace_span(o);
  PlotSpec plot{"Systematic uncertainty (log scale)",
                "temperature (°C)",
                "uncertainty (°C, log)",
                true,
                1000,
                340};
  plot.shade_from = furnace_lo, plot.shade_to = furnace_hi, plot.shade_label = "furnace data";
  h << svg_plot(plot, [&] {
    std::vector<Series> series{
        {"u calibration (k=1)", u.temperature_c, u.u_calibration_c, colour(0)},
        {"u emissivity (k=1)", u.temperature_c, u.u_emissivity_c, colour(1)},
        {"expanded (k=2)", u.temperature_c, total, colour(2)}};
    if (!u.u_qe_model_c.empty())
      series.push_back({"u QE model (k=1)", u.temperature_c, u.u_qe_model_c, colour(3)});
    return series;
  }());
  if (u.u_qe_model_c.empty())
    h << "<p><b>No QE-model term</b>: the " << html_escape(m.qe_solver)
      << " solver has no posterior to draw it from, so the uncertainty of readings beyond the "
         "furnace's range leaves out how far the QE is unknown there. The regularised solver "
         "(<code>pyrocam-calib calibrate --solver regularised</code>) gives it.</p>";
  else
    h << "<p>u QE model: the spread of the readings of QE solutions that fit the furnace (and "
         "reference) data about equally well (posterior samples of the fit), with the largest "
         "change of the reading when the fit's priors are made twice as wide or half as wide "
         "(never less than nearer the furnace range). It grows where the model extrapolates "
         "beyond the data.</p>";
}

// Reference rows: each source beyond the furnace read with the datasheet QE and the fitted QE.
void references_section(const CalibrationOutcome& o, std::ostream& h) {
  if (o.references.empty()) return;
  h << "<h2>Reference sources</h2><p>Each reference row's reading (the temperature whose modelled "
       "band ratios best match its rates, scale free) minus its stated temperature. The rows "
       "were part of the QE fit (their temperatures held to their uncertainty), so the errors "
       "with the fitted QE are the fit's residuals, not an independent check: for that, keep a "
       "reference out of the dataset and measure it.</p><table>"
       "<tr><th>reference</th><th>stated temperature (°C)</th><th>u (k=1, °C)</th>"
       "<th>error with the datasheet QE (°C)</th><th>error with the fitted QE (°C)</th></tr>";
  for (const ReferenceCheck& r : o.references)
    h << "<tr><td>" << html_escape(r.name) << "</td><td>" << num(r.temperature_c, 2) << "</td><td>"
      << num(r.uncertainty_c, 2) << "</td><td>" << num(r.error_datasheet_c, 2) << "</td><td>"
      << num(r.error_fitted_c, 2) << "</td></tr>";
  h << "</table>";
}

// What the calibration warned about.
void warnings_section(const CalibrationOutcome& o, std::ostream& h) {
  if (!o.warnings.empty()) {
    h << "<h2>Warnings</h2><ul>";
    for (const auto& w : o.warnings) h << "<li>" << html_escape(w) << "</li>";
    h << "</ul>";
  }
}

}  // namespace

void write_report_html(const CalibrationOutcome& o, const std::filesystem::path& path) {
  std::ostringstream h;
  html_head(o, h);
  table4_section(o, h);
  qe_section(o, h);
  rates_section(o, h);
  locus_section(o, h);
  setting_errors_section(o, h);
  network_section(o, h);
  references_section(o, h);
  uncertainty_section(o, h);
  warnings_section(o, h);
  h << "</body></html>\n";
  std::ofstream out(path);
  out << h.str();
  if (!out) throw InputError(path.string() + ": cannot write report");
}

}  // namespace pyrocam::cli
