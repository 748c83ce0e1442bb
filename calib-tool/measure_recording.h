// `pyrocam-calib measure --recording`: a raw recording measured again with a model.
#pragma once

#include <memory>
#include <set>
#include <string>

#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam::cli {

struct RecordingMeasure {
  std::string recording;  // folder of raw-NNNNN.mkv segments (or one)
  std::string out;        // folder for temperature.npy and temperature.csv
  std::shared_ptr<const ThermalModel> model;
  std::string model_path;
  MeasureOptions options;
  std::string dark;        // dark frame file; empty: --dark-level or the recording's tags
  double dark_level = -1;  // DN; negative: the dark frame or the recording's tags
  std::string pattern;     // --pattern; empty: the recording's tags, else the model's
  int peak_window = 5;
  bool quiet = false;
  // The options given on the command line ("--e-slope", ...): the others that ratiotemp's tags
  // on the recording's temperature segments name are taken from them.
  std::set<std::string> given;
};

int measure_recording(const RecordingMeasure& m);

// The model's prebuilt lookup table (model path + ".lut") into the measurer when its method reads
// a table and the file is there: the same readings, a faster first frame. A file that cannot be
// used is said on stderr (unless quiet) and the table is filled as frames need it.
void load_prebuilt_table(const FrameMeasurer& measurer, const MeasureOptions& options,
                         const std::string& model_path, bool quiet);

// Says on stderr, even when quiet, where the method reads graybodies hotter than the model's
// range as temperatures inside it (a network trained only up to a narrow range's end), as
// ratiotemp says it when it starts: a surface that hot would read wrong, not as no reading.
void warn_when_network_folds(const FrameMeasurer& measurer, const MeasureOptions& options,
                             const ThermalModel& model, const std::string& model_path);

// What the checks of the frames measured (MeasureOptions::check_layout) said, on stderr even when
// quiet: a dark that looks off (a warning: the dark is the user's to measure) and frames that do
// not read as the model's camera (errors: temperatures that would look right and be wrong).
// Returns false after the errors: what was written in `out` is kept to be looked at, and the
// exit status keeps a script from taking it.
bool frames_read_as_the_camera(const FrameMeasurer& measurer, const std::string& out);

// The frames' layout against the model's (both lower case; `frames` from `source`, for messages):
// empty where they are the same; the frames' pattern where both are Bayer patterns (the same
// filters, a readout window that starts on another cell: MeasureOptions::bayer_pattern), said
// on stderr unless quiet; throws InputError for another kind of mosaic.
std::string frames_bayer_pattern(const ThermalModel& model, const std::string& model_path,
                                 const std::string& frames, const std::string& source, bool quiet);

}  // namespace pyrocam::cli
