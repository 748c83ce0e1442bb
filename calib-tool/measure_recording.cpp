// `pyrocam-calib measure --recording`: a raw recording (record.sh with RAW=1: the camera's
// mosaic as FFV1/Matroska segments raw-NNNNN.mkv) measured again, frame by frame, with a model
// (the one it was recorded with, or another), into the export formats.
#include "measure_recording.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "commands.h"
#include "export.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/core/recording_comment.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/prebuilt_tables.h"
#include "recording.h"

namespace pyrocam::cli {
namespace {

std::string lower(std::string s) {
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

// What record.sh's DARK setting (darksub's properties, as the raw tags' dark field) says
// measure needs: the dark (a level or a file), darksub's saturation level and mosaic pattern.
struct RecordedDarksub {
  double level = -1;  // DN; negative: none
  std::string file;
  double saturation = -1;  // DN; negative: darksub's default
  std::string pattern;     // lower case; empty: none
};

RecordedDarksub recorded_darksub(const std::map<std::string, std::string>& fields,
                                 const std::string& where, bool quiet) {
  RecordedDarksub d;
  const auto it = fields.find("dark");
  if (it == fields.end()) return d;
  std::istringstream words(it->second);
  std::string word;
  const auto number = [&](const std::string& text, double low, double high) {
    try {
      std::size_t used = 0;
      const double v = std::stod(text, &used);
      if (used == text.size() && v >= low && v <= high) return v;
    } catch (const std::exception&) {
    }
    throw InputError(where + ": the recording's dark setting '" + word +
                     "' is not a number of DN; give --dark or --dark-level (and --saturation)");
  };
  while (words >> word) {
    const auto eq = word.find('=');
    const std::string key = word.substr(0, eq),
                      value = eq == std::string::npos ? "" : word.substr(eq + 1);
    if (key == "dark-level") {
      d.level = number(value, 0, 65535);
    } else if (key == "location" && !value.empty()) {
      d.file = value;
    } else if (key == "saturation-level") {
      d.saturation = number(value, -1, 65535);
    } else if (key == "pattern" && value != "auto") {
      d.pattern = lower(value);
    } else if (key != "pattern" && !quiet) {
      // bit-depth, capture-frames, ...: what they change is not measure's to know.
      std::cerr << "warning: " << where << ": the recording's dark settings '" << it->second
                << "' name " << word
                << ", which measure --recording does not take: its codes may differ from the "
                   "recorded ones (give --saturation as darksub had it)\n";
    }
  }
  return d;
}

// The recorded dark (level or file) where the command line gave none.
void dark_from_tags(const RecordedDarksub& recorded,
                    const std::map<std::string, std::string>& fields, const std::string& where,
                    double* level, std::string* file) {
  if (fields.find("dark") == fields.end())
    throw InputError(where + ": the recording does not say its dark; give --dark or --dark-level");
  if (!recorded.file.empty()) {
    *file = recorded.file;
  } else if (recorded.level >= 0) {
    *level = recorded.level;
  } else {
    throw InputError(where + ": the recording's dark '" + fields.at("dark") +
                     "' has neither dark-level=N nor location=FILE; give --dark or --dark-level");
  }
}

// The settings ratiotemp's tags name (what adopt_recorded_settings takes).
constexpr const char* kRecordedSettings[] = {
    "method",          "e-slope",           "partial-bands", "misfit-probability",
    "blur-correction", "brightness-radius", "demosaic"};

// What ratiotemp's tags on the recording's temperature segments say it read them with (the
// comment's fields), or nothing where there are none: the first segment's first frame. A later
// segment read with other settings is said: measure reads every frame with the first's.
std::map<std::string, std::string> recorded_settings(const std::string& recording, bool quiet) {
  struct FirstFrame {};
  std::map<std::string, std::string> first;
  try {
    const auto segments = recording_segments(recording, "temperature-");
    for (std::size_t i = 0; i < segments.size(); ++i) {
      std::map<std::string, std::string> fields;
      try {
        read_recording({segments[i]}, [&](const RecordingFrame& f) {
          if (f.tags->comment.rfind(kTemperatureRecordingMark, 0) == 0) fields = f.tags->fields;
          throw FirstFrame{};
        });
      } catch (const FirstFrame&) {
      }
      if (i == 0) {
        first = fields;
        continue;
      }
      // Matroska writes its tags as a segment is closed: one cut short by SIGKILL has none, and
      // says nothing of its settings.
      if (fields.empty()) continue;
      for (const char* key : kRecordedSettings) {
        const auto a = first.find(key), b = fields.find(key);
        const bool same = (a == first.end()) == (b == fields.end()) &&
                          (a == first.end() || a->second == b->second);
        if (same) continue;
        std::cerr << "warning: " << segments[i].filename().string() << " was read with " << key
                  << " " << (b == fields.end() ? "(not said)" : b->second) << ", "
                  << segments[0].filename().string() << " with "
                  << (a == first.end() ? "(not said)" : a->second)
                  << ": measure reads the whole recording with the first segment's settings, "
                     "so the codes from there on may differ from the recorded ones\n";
        return first;
      }
    }
  } catch (const InputError& e) {
    if (!quiet)
      std::cerr << "note: the recording's temperatures cannot say what they were read with ("
                << e.what() << "): measure's settings read it\n";
  }
  return first;
}

// The settings ratiotemp read the recording's temperatures with, for those the command line
// does not give, so that the same model gives the recorded codes; one that it gives otherwise
// is said (the codes then differ from the recorded ones, as asked).
void adopt_recorded_settings(const std::map<std::string, std::string>& fields,
                             const std::set<std::string>& given, MeasureOptions& options,
                             bool quiet) {
  // `ours`: the setting's value as the tags write it.
  const auto take = [&](const char* field, const std::string& option, const std::string& ours,
                        const std::function<void(const std::string&)>& set) {
    const auto it = fields.find(field);
    if (it == fields.end() || it->second == ours) return;
    if (given.count(option) == 0) {
      set(it->second);
      if (!quiet)
        std::cerr << "note: " << field << " " << it->second << ", as the recording's "
                  << "temperatures were read (their tags)\n";
    } else {
      std::cerr << "warning: the recording's temperatures were read with " << field << " "
                << it->second << ", " << option << " gives " << ours
                << ": the codes will differ from the recorded ones\n";
    }
  };
  take("method", "--method", method_name(options.method),
       [&](const std::string& v) { options.method = parse_method(v); });
  const auto slope = fields.find("e-slope");
  if (slope != fields.end() &&
      recording_comment_field_number(slope->second) != options.emissivity_slope * 100)
    take("e-slope", "--e-slope",
         recording_comment_number(options.emissivity_slope * 100) + " %/100 nm",
         [&](const std::string& v) {
           options.emissivity_slope = recording_comment_field_number(v) / 100;
         });
  const std::string partial = options.allow_partial ? "any" : options.safe_partial ? "safe" : "off";
  take("partial-bands", given.count("--allow-partial") ? "--allow-partial" : "--partial-bands",
       partial, [&](const std::string& v) {
         if (v != "off" && v != "safe" && v != "any")
           throw InputError("the recording's tags: partial-bands '" + v + "'");
         options.allow_partial = v == "any";
         options.safe_partial = v == "safe";
       });
  const auto misfit = fields.find("misfit-probability");
  if (misfit != fields.end() &&
      recording_comment_field_number(misfit->second) != options.misfit_probability)
    take("misfit-probability", "--misfit-probability",
         recording_comment_number(options.misfit_probability), [&](const std::string& v) {
           options.misfit_probability = recording_comment_field_number(v);
         });
  take("blur-correction", "--blur-correction", options.blur_correction ? "on" : "off",
       [&](const std::string& v) { options.blur_correction = v == "on"; });
  take("brightness-radius", "--brightness-radius", std::to_string(options.brightness_radius),
       [&](const std::string& v) {
         options.brightness_radius = static_cast<int>(recording_comment_field_number(v));
       });
  // demosaic25's method (matched on the fused path); 5x5 mosaics bin with bilinear and bin2x2
  // alike.
  take("demosaic", "--demosaic",
       demosaic_method_name(resolve_demosaic_method(options.demosaic, MosaicLayout{})),
       [&](const std::string& v) {
         try {
           options.demosaic = parse_demosaic_method(v);
         } catch (const InputError& e) {
           throw InputError(std::string("the recording's tags: ") + e.what());
         }
       });
}

std::string mosaic_words(const MosaicLayout& layout) {
  return layout.kind == MosaicLayout::Kind::kBayer ? lower(layout.pattern) + " Bayer mosaic"
                                                   : layout.pattern + " mosaic";
}

// The camera profile the recording's temperatures were read with (their tags) against the
// model's. The raw tags name the Bayer pattern only where the recording's caps did, so without
// this a model of another mosaic would read the raw frames as nonsense, with no error.
void check_recorded_profile(const std::map<std::string, std::string>& recorded,
                            const ThermalModel& model, const std::string& model_path,
                            const std::string& recording, bool quiet) {
  const auto it = recorded.find("profile");
  const CameraProfile& ours = model.profile();
  if (it == recorded.end() || it->second == ours.name) return;
  std::optional<CameraProfile> theirs;
  try {
    theirs = load_profile_by_name(it->second);
  } catch (const InputError&) {
  }
  if (!theirs) {
    if (!quiet)
      std::cerr << "warning: " << recording << "'s temperatures were read with camera profile "
                << it->second << " (not found here), the model " << model_path << " is for "
                << ours.name << ": the raw frames must be of a " << mosaic_words(ours.mosaic)
                << "\n";
    return;
  }
  const MosaicLayout& a = ours.mosaic;
  const MosaicLayout& b = theirs->mosaic;
  const bool same_kind =
      a.kind == b.kind && (a.kind == MosaicLayout::Kind::kBayer || a.pattern == b.pattern);
  if (!same_kind)
    throw InputError(model_path + ": the model was calibrated for a " + mosaic_words(a) +
                     " (profile " + ours.name + "), the recording " + recording + " for a " +
                     mosaic_words(b) + " (profile " + it->second + ", its temperatures' tags)");
}

}  // namespace

void load_prebuilt_table(const FrameMeasurer& measurer, const MeasureOptions& options,
                         const std::string& model_path, bool quiet) {
  if (options.method != Method::kLut) return;
  const std::string file = prebuilt_tables_file(model_path);
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return;
  try {
    measurer.load_tables(file);
  } catch (const InputError& e) {
    if (!quiet)
      std::cerr << "warning: prebuilt lookup table " << file << " not used (" << e.what()
                << "); the table is filled from the network as frames need it\n";
  }
}

void warn_when_network_folds(const FrameMeasurer& measurer, const MeasureOptions& options,
                             const ThermalModel& model, const std::string& model_path) {
  if (options.method == Method::kLikelihood) return;  // it gives no reading there
  const AboveRangeFold fold = measurer.above_range_fold();
  if (fold.read_inside == 0) return;
  std::cerr << "warning: with method " << method_name(options.method) << ", model " << model_path
            << " reads graybodies hotter than its range inside it (" << fold.worst_true_c
            << " degC as " << std::lround(fold.worst_read_c) << " degC): a surface hotter than "
            << model.max_temperature_c
            << " degC reads wrong, not as no reading; use --method likelihood, or a model "
               "calibrated to a higher --max-temperature\n";
}

std::string frames_bayer_pattern(const ThermalModel& model, const std::string& model_path,
                                 const std::string& frames, const std::string& source, bool quiet) {
  const std::string model_pattern = lower(model.profile().mosaic.pattern);
  if (frames.empty() || frames == model_pattern) return {};
  const bool both_bayer =
      model.profile().mosaic.kind == MosaicLayout::Kind::kBayer &&
      (frames == "rggb" || frames == "bggr" || frames == "grbg" || frames == "gbrg");
  if (!both_bayer)
    throw InputError(model_path + ": the model was calibrated for a " + model_pattern +
                     " mosaic (profile " + model.profile().name + "), the frames are " + frames +
                     " (" + source + ")");
  if (!quiet)
    std::cerr << "note: the frames are " << frames << " (" << source << "), the model's camera "
              << model_pattern << ": read as " << frames
              << " (the same filters, a readout window that starts on another cell)\n";
  return frames;
}

bool frames_read_as_the_camera(const FrameMeasurer& measurer, const std::string& out) {
  for (const std::string& problem : measurer.dark_level_problems())
    std::cerr << "warning: " << problem
              << "; measure the dark (a dark frame of the exposure, lens capped)\n";
  const std::vector<std::string> problems = measurer.layout_problems();
  for (const std::string& problem : problems) std::cerr << "error: " << problem << "\n";
  if (problems.empty()) return true;
  std::cerr << "pyrocam-calib: error: the frames do not read as the model's camera; what was "
               "written in "
            << out << " is kept to be looked at, not as results\n";
  return false;
}

int measure_recording(const RecordingMeasure& m) {
  const auto segments = recording_segments(m.recording, "raw-");
  const std::filesystem::path out(m.out);
  std::filesystem::create_directories(out);
  std::optional<FrameMeasurer> measurer;  // once the tags have said the frames' layout
  ExportWriter writer(
      {"", (out / "temperature.npy").string(), (out / "temperature.csv").string(), m.peak_window});
  cv::Mat dark;  // CV_32F or a raw image of the frames' size, from the first frame on
  read_recording(segments, [&](const RecordingFrame& f) {
    if (dark.empty()) {
      // The tags have come with the first frame: the layout and the dark.
      const auto& fields = f.tags->fields;
      if (f.tags->comment.rfind(kTemperatureRecordingMark, 0) == 0)
        throw InputError(m.recording + " holds temperatures (ratiotemp's codes), not raw " +
                         "frames: measure --recording reads the raw-NNNNN.mkv segments of a " +
                         "recording made with RAW=1");
      if (fields.empty() || f.tags->comment.rfind(kRawRecordingMark, 0) != 0)
        std::cerr << "warning: " << m.recording
                  << " has no pyrocam-raw tags (not recorded by record.sh RAW=1?)\n";
      const RecordedDarksub darksub = recorded_darksub(fields, m.recording, m.quiet);
      std::string pattern = lower(m.pattern);
      const auto tagged = fields.find("pattern");
      if (pattern.empty() && tagged != fields.end()) pattern = lower(tagged->second);
      if (pattern.empty()) pattern = darksub.pattern;
      // Read as the model's layout, a Bayer camera of another one reads about half its
      // temperature, and no check of the frames tells red from blue.
      if (pattern.empty() && m.model->profile().mosaic.kind == MosaicLayout::Kind::kBayer)
        throw InputError(m.recording +
                         ": the recording does not say its Bayer layout (its raw tags name no "
                         "pattern: recorded with a CAPS that has no format=?); give --pattern "
                         "rggb, bggr, grbg or gbrg as the camera sent it");
      MeasureOptions options = m.options;
      if (!m.given.count("--saturation") && darksub.saturation >= 0)
        options.saturation_level_dn = darksub.saturation;
      options.check_layout = true;
      const auto recorded = recorded_settings(m.recording, m.quiet);
      check_recorded_profile(recorded, *m.model, m.model_path, m.recording, m.quiet);
      adopt_recorded_settings(recorded, m.given, options, m.quiet);
      options.bayer_pattern =
          frames_bayer_pattern(*m.model, m.model_path, pattern,
                               m.pattern.empty() ? "the recording's tags" : "--pattern", m.quiet);
      measurer.emplace(m.model, options);
      load_prebuilt_table(*measurer, options, m.model_path, m.quiet);
      warn_when_network_folds(*measurer, options, *m.model, m.model_path);
      double level = m.dark_level;
      std::string file = m.dark;
      if (file.empty() && level < 0) dark_from_tags(darksub, fields, m.recording, &level, &file);
      dark = file.empty() ? cv::Mat(f.codes.size(), CV_32F, cv::Scalar(level))
                          : read_raw_image(file, f.codes.size(), "the recording's frames");
      char level_text[48];
      std::snprintf(level_text, sizeof level_text, "dark level %g DN", level);
      measurer->set_dark_name(file.empty() ? level_text : file);
    }
    cv::Mat t;
    measurer->measure(f.codes, dark, t);
    writer.add(f.index, f.timestamp_s, encode_decikelvin(t));
  });
  writer.finish();
  if (measurer && !frames_read_as_the_camera(*measurer, m.out)) return kExitFailed;
  if (!m.quiet)
    std::cerr << "measured " << writer.frames() << " raw frames of " << m.recording << " into "
              << (out / "temperature.npy").string() << " and " << (out / "temperature.csv").string()
              << "\n";
  return kExitOk;
}

}  // namespace pyrocam::cli
