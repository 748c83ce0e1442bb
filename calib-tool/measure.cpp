// `pyrocam-calib measure`: raw frames and dark frames to temperature images offline, through the
// same library code as the ratiotemp element.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <set>

#include "commands.h"
#include "measure_recording.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/region_stats.h"

namespace pyrocam::cli {
namespace {

struct MeasureArgs {
  std::string model, dataset, frame, dark, roi, out, pattern, recording;
  double dark_level = -1;  // --recording: DN
  std::string method = "auto", demosaic = "auto", format = "png";
  std::string partial_bands = "safe";
  double saturation = -1;
  double misfit_probability = 0;
  double mixed_pixels = 0;                       // MeasureOptions::footprint_spread
  double e_slope = 0, e_slope_uncertainty = -1;  // %/100 nm
  double gain_db = 0;
  bool allow_partial = false;
  bool uncertainty = false;
  bool blur_correction = false;  // MeasureOptions::blur_correction
  bool overwrite = false;        // --overwrite: replace a measurement in --out
  int brightness_radius = 0;     // MeasureOptions::brightness_radius
  int peak_window = kDefaultPeakWindow;
  std::set<std::string> given;  // the options on the command line, by name
};

// Truth comparison at the output resolution: only output pixels whose whole input footprint
// has one true temperature count (edges mix temperatures by design).
struct TruthScore {
  std::size_t pixels = 0, valid = 0;
  double rms_c = NAN, median_error_c = NAN;
};

TruthScore compare_truth(const cv::Mat& t, const cv::Mat& truth_dk, const MosaicLayout& layout,
                         DemosaicMethod method) {
  method = resolve_demosaic_method(method, layout);
  const bool binned =
      method == DemosaicMethod::kBinCells || layout.kind == MosaicLayout::Kind::kSnapshot;
  // The footprint of an output pixel, in output pixels (cells when binned) around it: bilinear
  // draws on 3x3 pixels, matched on 5x5 pixels or 3x3 cells, binning on one cell.
  const bool matched = method == DemosaicMethod::kMatched;
  const int reach = binned ? (matched ? 1 : 0) : (matched ? 2 : 1);
  const int unit_w = binned ? layout.period_width : 1, unit_h = binned ? layout.period_height : 1;
  const int cw = (2 * reach + 1) * unit_w, ch = (2 * reach + 1) * unit_h;
  TruthScore s;
  std::vector<double> errors;
  double sum2 = 0;
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) {
      const int x0 = (x - reach) * unit_w, y0 = (y - reach) * unit_h;
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

// A frame to measure: its dark frame, its true temperatures (when the dataset has them) and
// the setting it was taken at (NaN for a single --frame).
struct Job {
  std::filesystem::path frame, dark, truth;
  double exposure_us = NAN, nominal_c = NAN;
};

struct MeasureInputs {
  std::vector<Job> jobs;
  cv::Mat roi;
  cv::Size frame_size;  // the first frame's: every frame, dark and the ROI have it

  // The frames' layout, and where it came from, for messages.
  std::string pattern, pattern_source = "--pattern";
};

// What CLI11 cannot check by itself: which inputs go together.
void check_measure_args(const MeasureArgs& a) {
  if (a.dataset.empty() && a.frame.empty() && a.recording.empty())
    throw CLI::ValidationError("measure", "give --dataset, --frame or --recording");
  if (!a.dark.empty() && a.frame.empty() && a.recording.empty())
    throw CLI::ValidationError("--dark", "--dark goes with --frame or --recording");
  if (!a.frame.empty() && a.dark.empty())
    throw CLI::ValidationError("--dark", "--frame needs --dark");
  if (!a.frame.empty() && a.pattern.empty())
    throw CLI::ValidationError("--pattern",
                               "--frame needs --pattern: a raw frame does not say its mosaic "
                               "layout (rggb, bggr, grbg, gbrg or e.g. 5x5)");
}

// auto chooses as ratiotemp does, and says on stderr (unless -q) why it did not take the table.
MeasureOptions measure_options(const MeasureArgs& a,
                               const std::shared_ptr<const ThermalModel>& model,
                               const GlobalOptions& global) {
  MeasureOptions options;
  std::string not_lut;
  options.method = a.method == "auto" ? choose_method(model, MethodRequest::kAuto, &not_lut)
                                      : parse_method(a.method);
  if (!not_lut.empty() && !global.quiet)
    std::cerr << "warning: method auto uses likelihood, not lut: " << not_lut << "\n";
  options.demosaic = parse_demosaic_method(a.demosaic);
  options.saturation_level_dn = a.saturation;
  options.uncertainty = a.uncertainty;
  options.misfit_probability = a.misfit_probability;
  options.footprint_spread = a.mixed_pixels;
  options.blur_correction = a.blur_correction;
  options.brightness_radius = a.brightness_radius;
  options.allow_partial = a.allow_partial || a.partial_bands == "any";
  options.safe_partial = a.partial_bands == "safe";
  options.emissivity_slope = a.e_slope / 100;
  options.emissivity_slope_u = a.e_slope_uncertainty / 100;
  options.gain_db = a.gain_db;
  return options;
}

// Every frame row of the dataset, with the dark frame of its exposure and its truth image if
// there is one; the layout from mosaic.txt unless --pattern gave it (they must agree).
void add_dataset_jobs(const MeasureArgs& a, MeasureInputs& in) {
  const Dataset d = Dataset::open(a.dataset);
  const std::string declared = d.mosaic_pattern();
  const std::string mosaic_file = (d.folder() / kMosaicFile).string();
  if (!declared.empty() && !in.pattern.empty() && declared != in.pattern)
    throw InputError("--pattern " + in.pattern + " contradicts " + mosaic_file + " (" + declared +
                     ")");
  if (in.pattern.empty()) {
    if (declared.empty())
      throw InputError(a.dataset + ": the dataset does not say its frames' mosaic layout (no " +
                       kMosaicFile + "); give --pattern (rggb, bggr, grbg, gbrg or e.g. 5x5)");
    in.pattern = declared;
    in.pattern_source = mosaic_file;
  }
  in.roi = d.roi();
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
    in.jobs.push_back(j);
  }
}

// The frames to measure (the dataset's or the one --frame), their layout, and the ROI the
// statistics are taken over.
MeasureInputs measure_inputs(const MeasureArgs& a) {
  MeasureInputs in;
  if (!a.pattern.empty()) in.pattern = parse_mosaic_pattern(a.pattern, "--pattern");
  if (!a.dataset.empty()) {
    add_dataset_jobs(a, in);
  } else {
    in.jobs.push_back({a.frame, a.dark, {}, NAN, NAN});
  }
  in.frame_size = read_image_size(in.jobs.front().frame);
  if (!a.roi.empty()) in.roi = read_raw_image(a.roi, in.frame_size, "the frame") != 0;
  // A dataset's ROI of another size would be stretched onto the frames: statistics of the
  // wrong pixels.
  if (!in.roi.empty() && in.roi.size() != in.frame_size)
    throw InputError((a.roi.empty() ? a.dataset + "/roi.png" : a.roi) + ": the ROI is " +
                     std::to_string(in.roi.cols) + "x" + std::to_string(in.roi.rows) +
                     ", the frames " + std::to_string(in.frame_size.width) + "x" +
                     std::to_string(in.frame_size.height));
  // An empty ROI measured every frame into rows of empty statistics, exit 0.
  if (!in.roi.empty() && cv::countNonZero(in.roi) == 0)
    throw InputError((a.roi.empty() ? a.dataset + "/roi.png" : a.roi) +
                     ": the ROI is empty (no nonzero pixel)");
  return in;
}

// The output folder, and stats.csv in it with its header line.
std::ofstream open_stats_csv(const std::string& out) {
  std::filesystem::create_directories(out);
  std::ofstream csv(std::filesystem::path(out) / "stats.csv");
  csv << "file,exposure_us,nominal_c,pixels,valid_fraction,min_c,max_c,mean_c,median_c,"
         "truth_pixels,truth_valid,truth_rms_c,truth_median_error_c,median_u_c,peak_c,peak_x,"
         "peak_y,peak_lower_bound,truth_peak_c,truth_max_c,peak_error_c,above_range,"
         "peak_u_sys_c\n";
  return csv;
}

// <stem>_temperature and, when asked for, <stem>_uncertainty, in 0.1 K (0 = no reading); their
// paths added to `written`.
void write_frame_images(const MeasureArgs& a, const std::string& stem, const cv::Mat& t,
                        const cv::Mat& u, std::vector<std::filesystem::path>& written) {
  const std::string ext = a.format == "png" ? ".png" : ".tif";
  written.push_back(std::filesystem::path(a.out) / (stem + "_temperature" + ext));
  write_raw_image(written.back(), encode_decikelvin(t));
  if (a.uncertainty) {
    // Uncertainty as a temperature difference in 0.1 K, 0 = no reading.
    written.push_back(std::filesystem::path(a.out) / (stem + "_uncertainty" + ext));
    write_raw_image(written.back(), encode_decikelvin_difference(u));
  }
}

// The largest median of the window x window windows at least half read (region_peak) over the
// whole frame; none where the window does not fit.
RegionPeak frame_peak(const cv::Mat& temperature_c, int window) {
  if (window > temperature_c.cols || window > temperature_c.rows) return {};
  return region_peak(temperature_c, window);
}

// One frame measured: its images written and its row of stats.csv.
void measure_frame(const Job& j, const MeasureArgs& a, const MeasureInputs& in,
                   const ThermalModel& model, const MeasureOptions& options,
                   FrameMeasurer& measurer, std::ostream& csv, bool quiet,
                   std::vector<std::filesystem::path>& written) {
  const cv::Mat raw = read_raw_image(j.frame, in.frame_size, "the first frame");
  const cv::Mat dark = read_raw_image(j.dark, raw.size(), "the frame " + j.frame.string());
  const auto bits = [](const cv::Mat& m) { return std::to_string(8 * m.elemSize1()) + "-bit"; };
  if (dark.depth() != raw.depth())
    throw InputError(j.dark.string() + ": the dark has " + bits(dark) + " samples, the frame " +
                     j.frame.string() + " " + bits(raw) + " ones");
  cv::Mat t, u;
  measurer.set_dark_name(j.dark.string());
  measurer.set_exposure_us(j.exposure_us);  // NaN for a single --frame: unknown
  try {
    measurer.measure(raw, dark, t, a.uncertainty ? &u : nullptr);
  } catch (const InputError& e) {
    throw InputError(j.frame.string() + " (dark " + j.dark.string() + "): " + e.what());
  }
  write_frame_images(a, j.frame.stem().string(), t, u, written);
  cv::Mat mask;
  if (!in.roi.empty()) cv::resize(in.roi, mask, t.size(), 0, 0, cv::INTER_NEAREST);
  const RegionStats s = region_stats(t, mask);
  if (!quiet && s.pixels > 0 && s.valid_fraction < 0.5) {
    // A frame that reads little says why, so that the exposure can be put right.
    const FrameMeasurer::Unread why = measurer.unread(t, mask);
    std::cerr << "warning: " << j.frame.filename().string() << ": " << s.valid << " of " << s.pixels
              << " pixels of the ROI read; " << why.saturated
              << " have a band saturated or at the saturation level (shorten the exposure), "
              << why.dim << " a band below or near the dim threshold ("
              << model.profile().thresholds.inference_dim_dn << " DN; lengthen it)";
    if (measurer.above_range() > 0)
      std::cerr << ", " << measurer.above_range()
                << " of the frame hotter than the model's range (up to " << model.max_temperature_c
                << " degC: a model calibrated higher reads them)";
    if (why.both > 0)
      std::cerr << ", " << why.both
                << " one band saturated and another dim at once (no one exposure reads them: "
                   "their bands span more than the sensor's range; bracket exposures and fuse "
                   "them, as pyrocamsrc bracket and thermalfuse do)";
    std::cerr << "\n";
  }
  TruthScore ts;
  RegionPeak truth_peak;
  const RegionPeak peak = frame_peak(t, a.peak_window);
  double truth_max_c = NAN;
  if (!j.truth.empty()) {
    const cv::Mat truth = read_raw_image(j.truth, raw.size(), "the frame");
    if (truth.depth() != CV_16U)
      throw InputError(j.truth.string() +
                       ": true temperatures must be 16-bit (0.1 K units), this is 8-bit");
    ts = compare_truth(t, truth, model.profile().mosaic, options.demosaic);
    // The truth's own peak at the output's resolution (a 5x5 cell's mean temperature).
    cv::Mat truth_c = decode_decikelvin(truth);
    if (truth_c.size() != t.size()) cv::resize(truth_c, truth_c, t.size(), 0, 0, cv::INTER_AREA);
    truth_peak = frame_peak(truth_c, a.peak_window);
    cv::patchNaNs(truth_c, -1);  // code 0, no true temperature: below any
    cv::minMaxLoc(truth_c, nullptr, &truth_max_c);
    if (truth_max_c < 0) truth_max_c = NAN;
  }
  // Pixels without a reading where light saturated a band may be the hottest, and those hotter
  // than the model's range are: the peak read around them is then only a lower bound.
  const FrameMeasurer::Unread unread = measurer.unread(t, cv::Mat());
  const bool lower_bound = unread.saturated + unread.both > 0 || measurer.above_range() > 0;
  csv << j.frame.filename().string() << "," << fmt(j.exposure_us) << "," << fmt(j.nominal_c) << ","
      << s.pixels << "," << fmt(s.valid_fraction) << "," << fmt(s.min_c) << "," << fmt(s.max_c)
      << "," << fmt(s.mean_c) << "," << fmt(s.median_c) << "," << ts.pixels << "," << ts.valid
      << "," << fmt(ts.rms_c) << "," << fmt(ts.median_error_c) << ","
      << fmt(a.uncertainty ? measurer.median_uncertainty_c(t, u, mask) : NAN) << "," << fmt(peak.c)
      << "," << (peak.found() ? std::to_string(peak.x) : "") << ","
      << (peak.found() ? std::to_string(peak.y) : "") << "," << (lower_bound ? "true" : "false")
      << "," << fmt(truth_peak.c) << "," << fmt(truth_max_c) << "," << fmt(peak.c - truth_peak.c)
      << "," << measurer.above_range() << ","
      << fmt(lower_bound ? NAN : measurer.systematic_expanded_u_c(peak.c)) << "\n";
}

// A folder that holds a measurement (frames: stats.csv and an image per frame; a recording:
// temperature.npy and .csv) is not written into: the new images would sit among the earlier
// run's, and stats.csv would describe some of them. Refused before any work unless --overwrite;
// returns the earlier measurement's files (only names this command writes), removed by
// remove_earlier once the inputs have been read.
std::vector<std::filesystem::path> earlier_measurement(const MeasureArgs& a) {
  namespace fs = std::filesystem;
  const fs::path out(a.out);
  std::error_code ec;
  std::vector<fs::path> earlier;
  if (!fs::is_directory(out, ec)) return earlier;
  const auto ours = [](const fs::path& p) {
    const std::string name = p.filename().string(), ext = p.extension().string();
    const std::string stem = p.stem().string();
    const auto ends = [&](const std::string& s) {
      return stem.size() > s.size() && stem.compare(stem.size() - s.size(), s.size(), s) == 0;
    };
    return name == "stats.csv" || name == "temperature.npy" || name == "temperature.csv" ||
           ((ext == ".png" || ext == ".tif") && (ends("_temperature") || ends("_uncertainty")));
  };
  for (const auto& entry : fs::directory_iterator(out, ec))
    if (entry.is_regular_file(ec) && ours(entry.path())) earlier.push_back(entry.path());
  const bool measured =
      fs::exists(out / "stats.csv", ec) || fs::exists(out / "temperature.npy", ec);
  if (!measured) return {};
  if (!a.overwrite)
    throw InputError(a.out + " already holds a measurement (" +
                     (fs::exists(out / "stats.csv", ec) ? "stats.csv" : "temperature.npy") +
                     "): choose another --out, or --overwrite to replace it");
  return earlier;
}

void remove_earlier(const std::vector<std::filesystem::path>& earlier) {
  std::error_code ec;
  for (const auto& p : earlier)
    if (!std::filesystem::remove(p, ec) && ec)
      throw InputError(p.string() + ": could not remove the earlier measurement's file (" +
                       ec.message() + ")");
}

// The whole subcommand once the arguments are checked.
int run_measure(const MeasureArgs& a, const GlobalOptions& global) {
  const std::vector<std::filesystem::path> earlier = earlier_measurement(a);
  const auto shared_model = std::make_shared<const ThermalModel>(load_model(a.model));
  const ThermalModel& model = *shared_model;
  const MeasureOptions options = measure_options(a, shared_model, global);
  if (!a.recording.empty()) {
    RecordingMeasure m;
    m.recording = a.recording;
    m.out = a.out;
    m.model = shared_model;
    m.model_path = a.model;
    m.options = options;
    m.dark = a.dark;
    m.dark_level = a.dark_level;
    m.pattern = a.pattern;
    m.quiet = global.quiet;
    m.peak_window = a.peak_window;
    m.given = a.given;
    remove_earlier(earlier);
    return measure_recording(m);
  }
  const MeasureInputs in = measure_inputs(a);
  MeasureOptions frame_options = options;
  frame_options.bayer_pattern =
      frames_bayer_pattern(model, a.model, in.pattern, in.pattern_source, global.quiet);
  frame_options.check_layout = true;
  FrameMeasurer measurer(shared_model, frame_options);
  load_prebuilt_table(measurer, frame_options, a.model, global.quiet);
  warn_when_network_folds(measurer, frame_options, model, a.model);
  remove_earlier(earlier);
  std::ofstream csv = open_stats_csv(a.out);
  // A run that fails part-way leaves no results that look complete: what it wrote goes.
  std::vector<std::filesystem::path> written{std::filesystem::path(a.out) / "stats.csv"};
  try {
    ProgressPrinter progress(global, "measuring");
    for (std::size_t i = 0; i < in.jobs.size(); ++i) {
      measure_frame(in.jobs[i], a, in, model, frame_options, measurer, csv, global.quiet, written);
      progress(i + 1, in.jobs.size());
    }
    csv.flush();
    if (!csv) throw InputError(a.out + "/stats.csv: write failed");
  } catch (...) {
    csv.close();
    std::error_code ec;
    for (const auto& path : written) std::filesystem::remove(path, ec);
    throw;
  }
  if (!frames_read_as_the_camera(measurer, a.out)) return kExitFailed;
  if (!global.quiet)
    std::cout << in.jobs.size() << " frame(s) measured; images and stats.csv in " << a.out << "\n";
  return kExitOk;
}

// What is measured: the model, the frames (a dataset or one frame and its dark), their layout
// and the ROI.
void add_input_options(CLI::App* c, MeasureArgs& a) {
  c->add_option("--model", a.model, "Model file from `pyrocam-calib calibrate`")->required();
  auto* ds = c->add_option("--dataset", a.dataset, "Dataset folder: every frame row is measured");
  auto* fr = c->add_option("--frame", a.frame, "One raw frame (PGM/PNG/TIFF)");
  auto* rec = c->add_option("--recording", a.recording,
                            "Raw recording (record.sh RAW=1: raw-NNNNN.mkv segments) to measure "
                            "again into OUT/temperature.npy and OUT/temperature.csv (the export "
                            "formats); its dark and layout come from its tags");
  c->add_option("--dark", a.dark, "Dark frame for --frame (or for --recording)");
  c->add_option("--dark-level", a.dark_level,
                "--recording: dark level in DN instead of the recording's (darksub dark-level)")
      ->check(finite_range(0.0, 65535.0))
      ->needs(rec);
  ds->excludes(fr);
  rec->excludes(ds);
  rec->excludes(fr);
  c->add_option(
       "--pattern", a.pattern,
       "Mosaic layout of the raw frames: rggb, bggr, grbg, gbrg (Bayer, by the top-left "
       "cell) or the snapshot period, e.g. 5x5: the model's, or for a Bayer model any of the "
       "four (a readout window that starts on another cell). Needed with --frame "
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
}

// Where the results go and how they are read: output folder, estimator and image options.
void add_output_options(CLI::App* c, MeasureArgs& a) {
  c->add_option("--out", a.out,
                "Output folder (created); one that holds a measurement is refused unless "
                "--overwrite")
      ->required();
  c->add_flag("--overwrite", a.overwrite,
              "Replace the measurement in --out: its stats.csv and images (or a recording's "
              "temperature.npy and .csv) are removed first");
  c->add_option("--method", a.method,
                "Estimator: mlp (the paper's network), lut, likelihood or auto (ratiotemp's "
                "default: lut where the model has two ratios and its table passes the check "
                "against the network, else likelihood)")
      ->check(CLI::IsMember({"mlp", "lut", "likelihood", "auto"}))
      ->capture_default_str();
  c->add_option("--demosaic", a.demosaic,
                "Demosaicking: bilinear, bin2x2, matched (every band through a kernel of the "
                "same spread: no colour shift on hot spots, no wild ratios at edges to a cold "
                "background; 5x5 mosaics: each band read at the cell's centre) or auto "
                "(matched, as demosaic25's default); 5x5 mosaics are binned by bilinear and "
                "bin2x2")
      ->check(CLI::IsMember({"bilinear", "bin2x2", "matched", "auto"}))
      ->capture_default_str();
  c->add_option("--mixed-pixels", a.mixed_pixels,
                "Bayer: no reading where a band's samples under the pixel's footprint differ "
                "by more than this share of the largest plus 5 noise standard deviations (a "
                "sharp edge; demosaic25 mixed-pixels; 0 = no check, e.g. 0.5)")
      ->check(finite_range(0.0, kMaxRelativeSpread))
      ->capture_default_str();
  c->add_flag("--blur-correction", a.blur_correction,
              "Matched demosaicking only: subtract the kernel's bias on steep gradients (a "
              "footprint's mean signal is that of a hotter surface than its mean temperature: "
              "+180 degC at 150 degC a pixel near 1400 degC), the gradient taken from the "
              "readings; off by default");
  c->add_option("--brightness-radius", a.brightness_radius,
                "Read each pixel from its own brightness, its bands' scales the mean of what "
                "the ratio readings imply over a window: Bayer (full-resolution demosaicking), "
                "each pixel from its own sample, the window (4 r + 1) x (4 r + 1) pixels; "
                "snapshot (5x5), each cell from all its bands, the window (2 r + 1) x (2 r + 1) "
                "cells. r from 1 to 8, e.g. 2; 0 = the ratio readings as they are. As "
                "ratiotemp's brightness-radius. Assumes one emissivity over the window: near an "
                "emissivity step it reads wrong where the ratio reads right")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  c->add_option("--peak-window", a.peak_window,
                "stats.csv's peak_c: the largest median of these square windows (odd, 1 to 255 "
                "output pixels) at least half read, over the whole frame, as ratiotemp's "
                "peak-window")
      ->check(CLI::Range(1, 255))
      ->capture_default_str();
  c->add_option("--saturation", a.saturation,
                "Raw saturation level, DN (0 to 65535; -1: the model's)")
      ->check(finite_range(-1.0, 65535.0))
      ->capture_default_str();
  c->add_option("--misfit-probability", a.misfit_probability,
                "Band-consistency check: no reading where the bands fit no graybody near the "
                "estimate; the chance that a true graybody pixel is dropped (0 = no check, "
                "e.g. 1e-6)")
      ->check(finite_range(0.0, 0.5))
      ->capture_default_str();
  c->add_option("--e-slope", a.e_slope,
                "Emissivity slope of the surface, %/100 nm (-50 to 50; ratiotemp's e-slope): "
                "emissivity 1 + slope (wavelength - middle of the filter pass band), positive "
                "rising with wavelength; readings are corrected for it (0 = grey)")
      ->check(finite_range(-50.0, 50.0))
      ->capture_default_str();
  c->add_option("--e-slope-uncertainty", a.e_slope_uncertainty,
                "Standard uncertainty of --e-slope, %/100 nm (0 to 100), for the emissivity "
                "term of --uncertainty; negative: the model's (1 %/100 nm from calibrate)")
      ->check(finite_range(-1.0, 100.0))
      ->capture_default_str();
  c->add_option("--gain-db", a.gain_db,
                "Analogue gain the frames were taken with, dB (0 to 48; pyrocamsrc's gain): the "
                "shot noise per DN grows with it, which the likelihood weights, the "
                "band-consistency check and --uncertainty follow; readings by ratio do not")
      ->check(finite_range(0.0, 48.0))
      ->capture_default_str();
  c->add_option("--format", a.format, "Image type: png or tiff")
      ->check(CLI::IsMember({"png", "tiff"}))
      ->capture_default_str();
  c->add_flag("--uncertainty", a.uncertainty, "Also write the expanded uncertainty (k=2)");
  c->add_option("--partial-bands", a.partial_bands,
                "Pixels where some bands are saturated or below the dim threshold (ratiotemp's "
                "partial-bands): off: no reading; safe: read by the likelihood fit from the rest "
                "when they include two bands whose ratio is monotonic over the model's range "
                "(decided from its locus; none for the shipped colour camera, most pairs for "
                "the 5x5 one) and the noise alone leaves the reading within 50 degC at 1500 "
                "degC, growing as the square of the absolute temperature (one standard "
                "deviation); any: from any two")
      ->check(CLI::IsMember({"off", "safe", "any"}))
      ->capture_default_str();
  c->add_flag("--allow-partial", a.allow_partial,
              "The same as --partial-bands any (ratiotemp's allow-partial), which it overrides");
}

}  // namespace

void add_measure_command(CLI::App& app, const GlobalOptions& global, Command& selected) {
  static MeasureArgs a;
  CLI::App* c = app.add_subcommand(
      "measure", "Turn raw frames plus dark frames into temperature images (offline ratiotemp)");
  c->footer(
      "Output: <stem>_temperature.png (16-bit, 0.1 K units, 0 = no reading), optionally\n"
      "<stem>_uncertainty.png (expanded, k=2, 0.1 K units), and stats.csv with ROI statistics\n"
      "per frame (and errors against truth/<stem>.png when the dataset has true temperatures;\n"
      "with --uncertainty, median_u_c: the expanded uncertainty (k=2) of the ROI's median;\n"
      "over the whole frame, peak_c, peak_x, peak_y as ratiotemp's peak-c, peak_lower_bound\n"
      "where a pixel without a reading has a saturated band or is hotter than the model's\n"
      "range, with true temperatures truth_peak_c, truth_max_c and peak_error_c = peak_c -\n"
      "truth_peak_c, above_range: pixels hotter than the model's range, as ratiotemp's, and\n"
      "peak_u_sys_c: k=2 times the systematic uncertainty of a reading at peak_c, without noise,\n"
      "as ratiotemp's peak-u-sys-c; none on a lower bound).\n"
      "stats.csv always has the same columns: those that do not apply are empty (without\n"
      "true temperatures truth_pixels and truth_valid are 0).\n"
      "A raw frame does not say which mosaic it was taken through: --pattern names it, or\n"
      "the dataset's mosaic.txt (written by `pyrocam-calib simulate`): the model's kind of\n"
      "mosaic (a colour model reads any of the four Bayer patterns), else nothing is\n"
      "measured. Frames that read as another phase than they have, or whose readings\n"
      "mostly misfit the model's band spectra, fail (exit 1; what was written is kept).\n"
      "Examples:\n"
      "  pyrocam-calib measure --model rgb-model.json --dataset pool --out pool-t\n"
      "  pyrocam-calib measure --model rgb-model.json --frame raw.pgm --dark dark.pgm "
      "--pattern rggb --out t --uncertainty\n"
      "  pyrocam-calib measure --model other.json --recording out/run1 --method lut --out t2\n"
      "With --recording (a raw recording, record.sh RAW=1) the output is OUT/temperature.npy\n"
      "and OUT/temperature.csv as `pyrocam-calib export` writes them. The ratiotemp settings\n"
      "that change readings (method, e-slope, partial-bands, misfit-probability,\n"
      "blur-correction, brightness-radius) and demosaic25's method (--demosaic) come from\n"
      "the recording's temperature tags unless given here; with the recording's model the\n"
      "codes are then the recorded ones.");
  add_input_options(c, a);
  add_output_options(c, a);
  c->callback([&global, &selected, c] {
    if (a.peak_window % 2 == 0) throw CLI::ValidationError("--peak-window", "must be odd");
    check_measure_args(a);
    for (const CLI::Option* o : c->get_options())
      if (o->count() > 0) a.given.insert(o->get_name());
    selected = [&global] { return run_measure(a, global); };
  });
}

}  // namespace pyrocam::cli
