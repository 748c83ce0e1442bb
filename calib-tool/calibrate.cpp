// `pyrocam-calib calibrate`: furnace dataset + camera profile -> model file and report.
#include "pyrocam/calibration/calibrate.h"

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include "commands.h"
#include "pyrocam/core/error.h"
#include "pyrocam/runtime/prebuilt_tables.h"
#include "report.h"

namespace pyrocam::cli {
namespace {

struct CalibrateArgs {
  std::string dataset, profile = "rgb-reference", out = "model.json", report;
  std::string leak_terms = "select";
  std::string prior_widths = "select";
  std::string rate_offsets = "select";
  CalibrationOptions options;
  bool no_table = false;
};

// The prebuilt lookup table beside a colour model (none for a 5x5 model, which has no table):
// a line for the summary, or a warning. A table that cannot be made leaves the model usable
// (ratiotemp then fills its table as pixels need it).
void prebuild_beside(const std::string& model_path, std::vector<std::string>& lines,
                     std::vector<std::string>& warnings) {
  const std::string file = prebuilt_tables_file(model_path);
  try {
    const auto model = std::make_shared<const ThermalModel>(load_model(model_path));
    const bool colour = model->profile().normalisation.numerators.size() == 2;
    const PrebuiltTables t = prebuild_tables(model, file);
    if (t.problem.empty())
      lines.push_back("table:  " + file + " (" + std::to_string(t.blocks) + " blocks)");
    else if (colour)
      warnings.push_back("no prebuilt lookup table: " + t.problem);
  } catch (const std::exception& e) {
    warnings.push_back("prebuilt lookup table not written: " + std::string(e.what()));
  }
}

}  // namespace

void add_calibrate_command(CLI::App& app, const GlobalOptions& global, Command& selected) {
  static CalibrateArgs a;
  CLI::App* c = app.add_subcommand(
      "calibrate", "Calibrate a camera from a furnace dataset: write a model file and a report");
  c->footer(
      "Examples:\n"
      "  pyrocam-calib calibrate --dataset furnace --profile rgb-reference --out rgb-model.json\n"
      "  pyrocam-calib calibrate --dataset furnace-nir --profile nir5x5-reference --solver "
      "regularised --out nir-model.json\n"
      "The report is written beside the model (<out>-report.html and .json) unless --report "
      "names another prefix, and for a colour camera the prebuilt lookup table (<out>.lut, "
      "ratiotemp's fast start) unless --no-prebuilt-table. Nothing is written when calibration "
      "fails.");
  c->add_option("--dataset", a.dataset, "Dataset folder (manifest.csv, images, roi.png)")
      ->required();
  CLI::Option* profile_option =
      c->add_option("--profile", a.profile,
                    "Camera profile: shipped name or .json path (default: rgb-reference, or "
                    "nir5x5-reference for a dataset whose mosaic.txt says 5x5)")
          ->capture_default_str();
  c->add_option("--out", a.out, "Model file to write")->capture_default_str();
  c->add_option("--report", a.report, "Report path prefix (default: the model's, minus .json)");
  c->add_option("--solver", a.options.qe_solver,
                "QE solver: auto (the lower held-out error; paper only when more than 10 % "
                "lower, as in range the two often tie and beyond it paper's fit can be far off), "
                "paper, regularised, datasheet")
      ->check(CLI::IsMember({"auto", "paper", "regularised", "datasheet"}))
      ->capture_default_str();
  c->add_option("--leak-terms", a.leak_terms,
                "The regularised QE fit's leaks outside the filter's pass band: select (kept "
                "only where the furnace data call for them, a chi2 test; fitted to noise they "
                "read high above the furnace), keep, drop; kept leaks are fitted with bumps "
                "every 10 nm (a leak next to a filter edge is narrow)")
      ->check(CLI::IsMember({"select", "keep", "drop"}))
      ->capture_default_str();
  c->add_option("--prior-widths", a.prior_widths,
                "The regularised QE fit's priors on the QE's shape (tilts, shifts, the filter's "
                "edges, the common slope, leaks, shape changes): select (fitted at 0.5, 1 and 2 "
                "times their nominal widths, the one the furnace data make likeliest kept), "
                "nominal, or a factor on the nominal widths (0.1 to 10)")
      ->capture_default_str();
  c->add_option(
       "--rate-offsets", a.rate_offsets,
       "Where each furnace temperature's line of net signal against exposure meets zero "
       "exposure: select (one offset per band, what the darks left, unless the "
       "temperatures' own offsets differ beyond the noise, a chi2 test), common (one per "
       "band), per-step (one per temperature: the paper's lines, two to three times as noisy)")
      ->check(CLI::IsMember({"select", "common", "per-step"}))
      ->capture_default_str();
  c->add_option("--min-temperature", a.options.min_temperature_c, "Locus start, degC")
      ->check(finite_range(kModelMinTemperatureC, kModelMaxTemperatureC))
      ->capture_default_str();
  c->add_option("--max-temperature", a.options.max_temperature_c, "Locus end, degC")
      ->check(finite_range(kModelMinTemperatureC, kModelMaxTemperatureC))
      ->capture_default_str();
  c->add_option("--locus-step", a.options.locus_step_c,
                "Locus step, degC (0.01 to 100, whole steps over the range)")
      ->check(finite_range(0.01, 100.0))
      ->capture_default_str();
  c->add_option("--epochs", a.options.mlp.epochs, "MLP training: Adam epochs")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  c->add_option("--polish-iterations", a.options.mlp.polish_iterations,
                "MLP training: L-BFGS iterations after Adam (0: Adam only, as in the paper)")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  c->add_option("--noisy-copies", a.options.noisy_locus.copies,
                "MLP training: noisy single-pixel copies of each locus sample trained on besides "
                "it, read as the likelihood fit reads them (0: the locus alone)")
      ->check(CLI::Range(0, 100))
      ->capture_default_str();
  c->add_option("--mc-refits", a.options.monte_carlo_refits,
                "Monte-Carlo QE refits for the thermocouple uncertainty")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  c->add_option("--thermocouple-tolerance", a.options.thermocouple_tolerance_c,
                "Tolerance of the furnace's thermocouple, +-degC (0 to 50; read as a rectangular "
                "distribution, as IEC 60584-2 states tolerances; the default is class 1 at "
                "1100 degC): the calibration term's refits move the furnace temperatures by a "
                "deviation linear in temperature, within it at the coldest and the hottest step "
                "(without refits its standard uncertainty, tolerance / sqrt(3), is the term)")
      ->check(finite_range(0.0, 50.0))
      ->capture_default_str();
  c->add_option("--seed", a.options.seed, "Seed (MLP training, Monte-Carlo)")
      ->capture_default_str();
  c->add_option("--threads", a.options.threads, "Threads for reading frames")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  c->add_flag("--no-prebuilt-table", a.no_table,
              "Write no prebuilt lookup table beside a colour model (<out>.lut): ratiotemp then "
              "fills its table as the first frames need it (seconds on a first run)");
  c->callback([&global, &selected, profile_option] {
    if (!(a.options.min_temperature_c < a.options.max_temperature_c))
      throw CLI::ValidationError("--min-temperature", "must be below --max-temperature");
    // The locus the network learns ends on a whole step: at 690..1100 degC with steps of 100 it
    // ended at 1090 while the model said 1100.
    const double steps =
        (a.options.max_temperature_c - a.options.min_temperature_c) / a.options.locus_step_c;
    if (std::abs(steps - std::round(steps)) > 1e-6 * std::max(1.0, steps))
      throw CLI::ValidationError("--locus-step",
                                 "must divide the range from --min-temperature to "
                                 "--max-temperature into whole steps");
    a.options.fit_choices.leak_terms = a.leak_terms == "keep"   ? LeakTerms::kKeep
                                       : a.leak_terms == "drop" ? LeakTerms::kDrop
                                                                : LeakTerms::kSelect;
    if (a.prior_widths == "nominal") {
      a.options.fit_choices.prior_scales = {1};
    } else if (a.prior_widths != "select") {
      char* end = nullptr;
      const double factor = std::strtod(a.prior_widths.c_str(), &end);
      if (a.prior_widths.empty() || *end != '\0' || !(factor >= 0.1 && factor <= 10))
        throw CLI::ValidationError(
            "--prior-widths",
            "must be select, nominal or a factor from 0.1 to 10, not '" + a.prior_widths + "'");
      a.options.fit_choices.prior_scales = {factor};
    }
    a.options.rate_offsets = a.rate_offsets == "common"     ? RateOffsets::kCommon
                             : a.rate_offsets == "per-step" ? RateOffsets::kPerStep
                                                            : RateOffsets::kSelect;
    selected = [&global, profile_option] {
      // Before minutes of calibration: the folders the model and the report go to must be there.
      for (const std::string& file : {a.out, a.report}) {
        const std::filesystem::path folder = std::filesystem::path(file).parent_path();
        std::error_code ec;
        if (!file.empty() && !folder.empty() && !std::filesystem::is_directory(folder, ec))
          throw InputError(file + ": the folder " + folder.string() + " does not exist");
      }
      std::error_code ec;
      if (std::filesystem::is_directory(a.out, ec))
        throw InputError(a.out + ": is a folder; --out names the model file to write (e.g. " +
                         (std::filesystem::path(a.out) / "model.json").string() + ")");
      std::string prefix = a.report;
      if (prefix.empty()) {
        std::filesystem::path p(a.out);
        prefix = (p.parent_path() / p.stem()).string() + "-report";
      }
      // --out cam.json --report cam wrote the report's JSON over the model, and said the model
      // was written.
      const auto same_file = [](const std::string& x, const std::string& y) {
        std::error_code e1, e2;
        return std::filesystem::weakly_canonical(std::filesystem::absolute(x), e1) ==
                   std::filesystem::weakly_canonical(std::filesystem::absolute(y), e2) &&
               !e1 && !e2;
      };
      for (const std::string& report : {prefix + ".html", prefix + ".json"})
        for (const std::string& model : {a.out, prebuilt_tables_file(a.out)})
          if (same_file(report, model))
            throw InputError("--report " + prefix + " would write " + report +
                             " over the model's " + model + ": give the report another name");
      const Dataset dataset = Dataset::open(a.dataset);
      // Without --profile, a 5x5 dataset is the shipped 5x5 camera's, not the colour default.
      std::string profile_name = a.profile;
      if (profile_option->count() == 0 && dataset.mosaic_pattern() == "5x5") {
        profile_name = "nir5x5-reference";
        if (!global.quiet)
          std::fprintf(stderr,
                       "calibrate: the dataset's mosaic is 5x5 and no --profile was given: "
                       "using the shipped %s\n",
                       profile_name.c_str());
      }
      const CameraProfile profile = load_profile_by_name(profile_name);
      std::string current;
      const auto t0 = std::chrono::steady_clock::now();
      double last = -1;
      // One line per stage, refreshed at most 4 times a second.
      auto progress = [&](const std::string& stage, std::size_t done, std::size_t total) {
        if (global.quiet) return;
        const double s =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const bool new_stage = stage != current;
        if (!new_stage && done < total && s - last < 0.25) return;
        if (new_stage && !current.empty()) std::fprintf(stderr, "\n");
        current = stage;
        last = s;
        std::fprintf(stderr, "\r%-28s %zu/%zu  (%.1f s)", stage.c_str(), done, total, s);
      };
      const CalibrationOutcome o = calibrate(dataset, profile, a.options, progress);
      if (!global.quiet) std::fprintf(stderr, "\n");
      // The model replaces an earlier one only once the reports are written: a report that
      // could not be written left a new model beside the old model's table.
      const std::string staged = a.out + ".partial";
      save_model(o.model, staged);
      try {
        write_report_html(o, prefix + ".html");
        write_report_json(o, prefix + ".json");
      } catch (...) {
        std::filesystem::remove(staged, ec);
        throw;
      }
      std::filesystem::rename(staged, a.out, ec);
      if (ec) {
        const std::string why = ec.message();
        std::filesystem::remove(staged, ec);
        throw InputError(a.out + ": cannot write the model: " + why);
      }
      std::vector<std::string> table_lines, warnings = o.warnings;
      if (!a.no_table) {
        prebuild_beside(a.out, table_lines, warnings);
      } else {
        std::error_code ec;  // a table of an earlier model of that name: never read again
        std::filesystem::remove(prebuilt_tables_file(a.out), ec);
      }
      if (!global.quiet) {
        for (const auto& w : warnings) std::cerr << "warning: " << w << "\n";
        std::cout << o.verdict << "\n";
        for (const auto& s : o.table4) {
          if (s.true_c.empty())
            std::printf("  %-22s no reading on any calibration setting\n", s.name.c_str());
          else
            std::printf("  %-22s rms %7.2f degC  mean %7.2f  std %7.2f  (%zu settings)\n",
                        s.name.c_str(), s.rms, s.mean, s.std, s.true_c.size());
        }
        std::cout << "model:  " << a.out << "\nreport: " << prefix << ".html, " << prefix
                  << ".json\n";
        for (const auto& line : table_lines) std::cout << line << "\n";
      }
      return kExitOk;
    };
  });
}

}  // namespace pyrocam::cli
