// `pyrocam-calib measure --recording`: a raw recording (record.sh with RAW=1: the camera's
// mosaic as FFV1/Matroska segments raw-NNNNN.mkv) measured again, frame by frame, with a model
// (the one it was recorded with, or another), into the export formats.
#include "measure_recording.h"

#include <cctype>
#include <iostream>
#include <optional>

#include "commands.h"
#include "export.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/prebuilt_tables.h"
#include "recording.h"

namespace pyrocam::cli {
namespace {

std::string lower(std::string s) {
  for (char& ch : s) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
  return s;
}

// The dark record.sh recorded with: its DARK setting, "dark-level=N" or "location=FILE".
void dark_from_tags(const std::map<std::string, std::string>& fields, const std::string& where,
                    double* level, std::string* file) {
  const auto it = fields.find("dark");
  if (it == fields.end())
    throw InputError(where + ": the recording does not say its dark; give --dark or --dark-level");
  const std::string& v = it->second;
  try {
    if (v.rfind("dark-level=", 0) == 0) {
      *level = std::stod(v.substr(11));
      if (*level >= 0) return;
    } else if (v.rfind("location=", 0) == 0 && v.size() > 9) {
      *file = v.substr(9);
      return;
    }
  } catch (const std::exception&) {
  }
  throw InputError(where + ": the recording's dark '" + v +
                   "' is neither dark-level=N nor location=FILE; give --dark or --dark-level");
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
      if (fields.empty() || f.tags->comment.rfind("pyrocam-raw", 0) != 0)
        std::cerr << "warning: " << m.recording
                  << " has no pyrocam-raw tags (not recorded by record.sh RAW=1?)\n";
      std::string pattern = lower(m.pattern);
      const auto tagged = fields.find("pattern");
      if (pattern.empty() && tagged != fields.end()) pattern = lower(tagged->second);
      MeasureOptions options = m.options;
      options.bayer_pattern =
          frames_bayer_pattern(*m.model, m.model_path, pattern,
                               m.pattern.empty() ? "the recording's tags" : "--pattern", m.quiet);
      measurer.emplace(m.model, options);
      load_prebuilt_table(*measurer, options, m.model_path, m.quiet);
      double level = m.dark_level;
      std::string file = m.dark;
      if (file.empty() && level < 0) dark_from_tags(fields, m.recording, &level, &file);
      dark = file.empty() ? cv::Mat(f.codes.size(), CV_32F, cv::Scalar(level))
                          : read_raw_image(file, f.codes.size(), "the recording's frames");
    }
    cv::Mat t;
    measurer->measure(f.codes, dark, t);
    writer.add(f.index, f.timestamp_s, encode_decikelvin(t));
  });
  writer.finish();
  if (!m.quiet)
    std::cerr << "measured " << writer.frames() << " raw frames of " << m.recording << " into "
              << (out / "temperature.npy").string() << " and " << (out / "temperature.csv").string()
              << "\n";
  return kExitOk;
}

}  // namespace pyrocam::cli
