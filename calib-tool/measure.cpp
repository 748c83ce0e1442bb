// `pyrocam-calib measure`: raw frames and dark frames to temperature images offline, through the
// same library code as the ratiotemp element.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/region_stats.h"

namespace pyrocam::cli {
namespace {

struct MeasureArgs {
  std::string model, dataset, frame, dark, roi, out, pattern;
  std::string method = "mlp", demosaic = "bilinear", format = "png";
  double saturation = -1;
  double misfit_probability = 0;
  bool allow_partial = false;
  bool uncertainty = false;
};

// Truth comparison at the output resolution: only output pixels whose whole input footprint
// has one true temperature count (edges mix temperatures by design).
struct TruthScore {
  std::size_t pixels = 0, valid = 0;
  double rms_c = NAN, median_error_c = NAN;
};

TruthScore compare_truth(const cv::Mat& t, const cv::Mat& truth_dk, const MosaicLayout& layout,
                         DemosaicMethod method) {
  const bool binned =
      method == DemosaicMethod::kBinCells || layout.kind == MosaicLayout::Kind::kSnapshot;
  const int cw = binned ? layout.period_width : 3, ch = binned ? layout.period_height : 3;
  TruthScore s;
  std::vector<double> errors;
  double sum2 = 0;
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) {
      const int x0 = binned ? x * cw : x - 1, y0 = binned ? y * ch : y - 1;
      if (x0 < 0 || y0 < 0 || x0 + cw > truth_dk.cols || y0 + ch > truth_dk.rows) continue;
      const std::uint16_t v = truth_dk.at<std::uint16_t>(y0, x0);
      bool uniform = v != 0;
      for (int j = 0; j < ch && uniform; ++j)
        for (int i = 0; i < cw && uniform; ++i)
          uniform = truth_dk.at<std::uint16_t>(y0 + j, x0 + i) == v;
      if (!uniform) continue;
      ++s.pixels;
      const float est = t.at<float>(y, x);
      if (!std::isfinite(est)) continue;
      const double e = est - code_to_celsius(v);
      errors.push_back(e);
      sum2 += e * e;
    }
  s.valid = errors.size();
  if (!errors.empty()) {
    s.rms_c = std::sqrt(sum2 / static_cast<double>(errors.size()));
    auto mid = errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2);
    std::nth_element(errors.begin(), mid, errors.end());
    s.median_error_c = *mid;
  }
  return s;
}

std::string fmt(double v) {
  if (!std::isfinite(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

}  // namespace

void add_measure_command(CLI::App& app, const GlobalOptions& global, Command& selected) {
  static MeasureArgs a;
  CLI::App* c = app.add_subcommand(
      "measure", "Turn raw frames plus dark frames into temperature images (offline ratiotemp)");
  c->footer(
      "Output: <stem>_temperature.png (16-bit, 0.1 K units, 0 = no reading), optionally\n"
      "<stem>_uncertainty.png (expanded, k=2, 0.1 K units), and stats.csv with ROI statistics\n"
      "per frame (and errors against truth/<stem>.png when the dataset has true temperatures).\n"
      "A raw frame does not say which mosaic it was taken through: --pattern names it, or\n"
      "the dataset's mosaic.txt (written by `pyrocam-calib simulate`); it must match the\n"
      "model's, else nothing is measured.\n"
      "Examples:\n"
      "  pyrocam-calib measure --model rgb-model.json --dataset pool --out pool-t\n"
      "  pyrocam-calib measure --model rgb-model.json --frame raw.pgm --dark dark.pgm "
      "--pattern rggb --out t --uncertainty");
  c->add_option("--model", a.model, "Model file from `pyrocam-calib calibrate`")->required();
  auto* ds = c->add_option("--dataset", a.dataset, "Dataset folder: every frame row is measured");
  auto* fr = c->add_option("--frame", a.frame, "One raw frame (PGM/PNG/TIFF)");
  c->add_option("--dark", a.dark, "Dark frame for --frame")->needs(fr);
  ds->excludes(fr);
  c->add_option("--pattern", a.pattern,
                "Mosaic layout of the raw frames: rggb, bggr, grbg, gbrg (Bayer, by the top-left "
                "cell) or the snapshot period, e.g. 5x5; must be the model's. Needed with --frame "
                "and with a dataset that has no mosaic.txt; must agree with mosaic.txt otherwise")
      ->check([](const std::string& v) {
        try {
          parse_mosaic_pattern(v, "--pattern");
          return std::string();
        } catch (const InputError& e) {
          return std::string(e.what());
        }
      });
  c->add_option(
      "--roi", a.roi,
      "ROI mask for the statistics, of the frames' size (default: the dataset's roi.png)");
  c->add_option("--out", a.out, "Output folder (created)")->required();
  c->add_option("--method", a.method, "Estimator: mlp, lut or likelihood")
      ->check(CLI::IsMember({"mlp", "lut", "likelihood"}))
      ->capture_default_str();
  c->add_option("--demosaic", a.demosaic, "Bayer demosaicking: bilinear or bin2x2")
      ->check(CLI::IsMember({"bilinear", "bin2x2"}))
      ->capture_default_str();
  c->add_option("--saturation", a.saturation, "Raw saturation level, DN (-1: the model's)")
      ->capture_default_str();
  c->add_option("--misfit-probability", a.misfit_probability,
                "Band-consistency check: no reading where the bands fit no graybody near the "
                "estimate; the chance that a true graybody pixel is dropped (0 = no check, "
                "e.g. 1e-6)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  c->add_option("--format", a.format, "Image type: png or tiff")
      ->check(CLI::IsMember({"png", "tiff"}))
      ->capture_default_str();
  c->add_flag("--uncertainty", a.uncertainty, "Also write the expanded uncertainty (k=2)");
  c->add_flag("--allow-partial", a.allow_partial,
              "likelihood only: read pixels with some bands saturated or dim from the rest (at "
              "least two; ratiotemp's allow-partial); without it such pixels have no reading");
  c->callback([&global, &selected, c] {
    if (a.dataset.empty() && a.frame.empty())
      throw CLI::ValidationError("measure", "give --dataset or --frame");
    if (!a.frame.empty() && a.dark.empty())
      throw CLI::ValidationError("--dark", "--frame needs --dark");
    if (!a.frame.empty() && a.pattern.empty())
      throw CLI::ValidationError("--pattern",
                                 "--frame needs --pattern: a raw frame does not say its mosaic "
                                 "layout (rggb, bggr, grbg, gbrg or e.g. 5x5)");
    (void)c;
    selected = [&global] {
      const auto shared_model = std::make_shared<const ThermalModel>(load_model(a.model));
      const ThermalModel& model = *shared_model;
      MeasureOptions options;
      options.method = parse_method(a.method);
      options.demosaic = parse_demosaic_method(a.demosaic);
      options.saturation_level_dn = a.saturation;
      options.uncertainty = a.uncertainty;
      options.misfit_probability = a.misfit_probability;
      options.allow_partial = a.allow_partial;
      FrameMeasurer measurer(shared_model, options);

      struct Job {
        std::filesystem::path frame, dark, truth;
        double exposure_us = NAN, nominal_c = NAN;
      };
      std::vector<Job> jobs;
      cv::Mat roi;
      // The frames' layout, and where it came from, for messages.
      std::string pattern, pattern_source = "--pattern";
      if (!a.pattern.empty()) pattern = parse_mosaic_pattern(a.pattern, "--pattern");
      if (!a.dataset.empty()) {
        const Dataset d = Dataset::open(a.dataset);
        const std::string declared = d.mosaic_pattern();
        const std::string mosaic_file = (d.folder() / kMosaicFile).string();
        if (!declared.empty() && !pattern.empty() && declared != pattern)
          throw InputError("--pattern " + pattern + " contradicts " + mosaic_file + " (" +
                           declared + ")");
        if (pattern.empty()) {
          if (declared.empty())
            throw InputError(
                a.dataset + ": the dataset does not say its frames' mosaic layout (no " +
                kMosaicFile + "); give --pattern (rggb, bggr, grbg, gbrg or e.g. 5x5)");
          pattern = declared;
          pattern_source = mosaic_file;
        }
        roi = d.roi();
        for (const auto& row : d.rows()) {
          if (row.kind != FrameKind::kFrame) continue;
          Job j;
          j.frame = d.path_of(row);
          const auto& dark = d.dark_for(row.exposure_us);
          j.dark = dark.files.front();
          const auto truth = d.folder() / "truth" / (j.frame.stem().string() + ".png");
          if (std::filesystem::exists(truth)) j.truth = truth;
          j.exposure_us = row.exposure_us;
          j.nominal_c = row.temperature_c;
          jobs.push_back(j);
        }
      } else {
        jobs.push_back({a.frame, a.dark, {}, NAN, NAN});
      }
      std::string model_pattern = model.profile().mosaic.pattern;
      std::transform(model_pattern.begin(), model_pattern.end(), model_pattern.begin(),
                     [](unsigned char ch) { return static_cast<char>(std::tolower(ch)); });
      if (model_pattern != pattern)
        throw InputError(a.model + ": the model was calibrated for a " + model_pattern +
                         " mosaic (profile " + model.profile().name + "), the frames are " +
                         pattern + " (" + pattern_source + ")");
      const cv::Size frame_size = read_image_size(jobs.front().frame);
      if (!a.roi.empty()) roi = read_raw_image(a.roi, frame_size, "the frame") != 0;
      std::filesystem::create_directories(a.out);
      std::ofstream csv(std::filesystem::path(a.out) / "stats.csv");
      csv << "file,exposure_us,nominal_c,pixels,valid_fraction,min_c,max_c,mean_c,median_c,"
             "truth_pixels,truth_valid,truth_rms_c,truth_median_error_c\n";
      ProgressPrinter progress(global, "measuring");
      const std::string ext = a.format == "png" ? ".png" : ".tif";
      for (std::size_t i = 0; i < jobs.size(); ++i) {
        const Job& j = jobs[i];
        const cv::Mat raw = read_raw_image(j.frame);
        const cv::Mat dark = read_raw_image(j.dark, raw.size(), "the frame " + j.frame.string());
        cv::Mat t, u;
        measurer.measure(raw, dark, t, a.uncertainty ? &u : nullptr);
        const std::string stem = j.frame.stem().string();
        write_raw_image(std::filesystem::path(a.out) / (stem + "_temperature" + ext),
                        encode_decikelvin(t));
        if (a.uncertainty) {
          // Uncertainty as a temperature difference in 0.1 K, 0 = no reading.
          write_raw_image(std::filesystem::path(a.out) / (stem + "_uncertainty" + ext),
                          encode_decikelvin_difference(u));
        }
        cv::Mat mask;
        if (!roi.empty()) cv::resize(roi, mask, t.size(), 0, 0, cv::INTER_NEAREST);
        const RegionStats s = region_stats(t, mask);
        TruthScore ts;
        if (!j.truth.empty()) {
          const cv::Mat truth = read_raw_image(j.truth, raw.size(), "the frame");
          if (truth.depth() != CV_16U)
            throw InputError(j.truth.string() +
                             ": true temperatures must be 16-bit (0.1 K units), this is 8-bit");
          ts = compare_truth(t, truth, model.profile().mosaic, options.demosaic);
        }
        csv << j.frame.filename().string() << "," << fmt(j.exposure_us) << "," << fmt(j.nominal_c)
            << "," << s.pixels << "," << fmt(s.valid_fraction) << "," << fmt(s.min_c) << ","
            << fmt(s.max_c) << "," << fmt(s.mean_c) << "," << fmt(s.median_c) << "," << ts.pixels
            << "," << ts.valid << "," << fmt(ts.rms_c) << "," << fmt(ts.median_error_c) << "\n";
        progress(i + 1, jobs.size());
      }
      if (!csv) throw InputError(a.out + "/stats.csv: write failed");
      if (!global.quiet)
        std::cout << jobs.size() << " frame(s) measured; images and stats.csv in " << a.out << "\n";
      return kExitOk;
    };
  });
}

}  // namespace pyrocam::cli
