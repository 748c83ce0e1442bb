// `pyrocam-calib export`: a temperature recording (pipelines/record.sh) to a 16-bit multi-page
// TIFF, a NumPy .npy array and a CSV of per-frame statistics, for tools outside GStreamer.
#include "export.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <optional>

#include "commands.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/region_stats.h"
#include "recording.h"

namespace pyrocam::cli {
namespace {

namespace fs = std::filesystem;

struct ExportArgs {
  std::string recording, tiff, npy, csv;
  int peak_window = kDefaultPeakWindow;
};

// The .npy header (format 1.0) padded to kNpyHeaderBytes, so that it can be written first with
// the frame count unknown and rewritten in place at the end.
constexpr std::size_t kNpyHeaderBytes = 128;
std::string npy_header(std::size_t frames, int height, int width) {
  std::string dict = "{'descr': '<u2', 'fortran_order': False, 'shape': (" +
                     std::to_string(frames) + ", " + std::to_string(height) + ", " +
                     std::to_string(width) + "), }";
  const std::size_t room = kNpyHeaderBytes - 10;  // magic, version and length take 10 bytes
  if (dict.size() + 1 > room) throw InputError("frame count or size too large for .npy");
  dict.append(room - dict.size() - 1, ' ');
  dict += '\n';
  std::string h = "\x93NUMPY";
  h += '\x01';
  h += '\x00';
  h += static_cast<char>(room & 0xff);
  h += static_cast<char>(room >> 8);
  return h + dict;
}

std::string csv_number(double v, int decimals) {
  if (!std::isfinite(v)) return "";
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

}  // namespace

// An output written beside its final name and renamed when complete: a failed export leaves
// no partial file under the name asked for.
struct ExportWriter::Output {
  Output(const std::string& p, const std::string& suffix) : path(p), partial(p + suffix) {}
  ~Output() {
    std::error_code ec;
    if (!done) fs::remove(partial, ec);
  }
  void commit() {
    std::error_code ec;
    fs::rename(partial, path, ec);
    if (ec) throw InputError(path.string() + ": cannot write there (" + ec.message() + ")");
    done = true;
  }
  fs::path path, partial;
  bool done = false;
};

ExportWriter::ExportWriter(const ExportPaths& paths) : paths_(paths) {
  if (!paths.npy.empty()) {
    npy_out_ = std::make_unique<Output>(paths.npy, ".partial");
    npy_.open(npy_out_->partial, std::ios::binary);
    if (!npy_) throw InputError(paths.npy + ": cannot write");
    npy_ << npy_header(0, 0, 0);
  }
  if (!paths.csv.empty()) {
    csv_out_ = std::make_unique<Output>(paths.csv, ".partial");
    csv_.open(csv_out_->partial);
    if (!csv_) throw InputError(paths.csv + ": cannot write");
    csv_ << "index,timestamp_s,valid_fraction,min_c,median_c,mean_c,max_c,peak_c\n";
  }
  // The extension tells OpenCV the format: the partial name keeps it.
  if (!paths.tiff.empty()) tiff_out_ = std::make_unique<Output>(paths.tiff, ".partial.tif");
}

ExportWriter::~ExportWriter() {
  npy_.close();  // before the partial files go
  csv_.close();
}

void ExportWriter::add(std::size_t index, double timestamp_s, const cv::Mat& codes) {
  width_ = codes.cols;
  height_ = codes.rows;
  ++frames_;
  if (npy_out_) {
    const cv::Mat c = codes.isContinuous() ? codes : codes.clone();
    npy_.write(reinterpret_cast<const char*>(c.data),
               static_cast<std::streamsize>(c.total() * 2));  // x86-64: little-endian
    if (!npy_) throw InputError(paths_.npy + ": write failed");
  }
  if (tiff_out_) {
    constexpr std::size_t kMaxTiffBytes = std::size_t{2} << 30;  // held in memory until written
    tiff_bytes_ += codes.total() * 2;
    if (tiff_bytes_ > kMaxTiffBytes)
      throw InputError(paths_.tiff +
                       ": more than 2 GiB of frames for one TIFF; write .npy, or a part");
    pages_.push_back(codes.clone());
  }
  if (csv_out_) {
    const cv::Mat t = decode_decikelvin(codes);
    const RegionStats s = region_stats(t);
    const RegionPeak p = region_peak(t, paths_.peak_window);
    csv_ << index << ',' << csv_number(timestamp_s, 6) << ',' << csv_number(s.valid_fraction, 6)
         << ',' << csv_number(s.min_c, 2) << ',' << csv_number(s.median_c, 2) << ','
         << csv_number(s.mean_c, 3) << ',' << csv_number(s.max_c, 2) << ',' << csv_number(p.c, 2)
         << '\n';
    if (!csv_) throw InputError(paths_.csv + ": write failed");
  }
}

void ExportWriter::finish() {
  if (npy_out_) {
    npy_.seekp(0);
    npy_ << npy_header(frames_, height_, width_);
    npy_.close();
    if (!npy_) throw InputError(paths_.npy + ": write failed");
    npy_out_->commit();
  }
  if (csv_out_) {
    csv_.close();
    if (!csv_) throw InputError(paths_.csv + ": write failed");
    csv_out_->commit();
  }
  if (tiff_out_) {
    if (!cv::imwritemulti(tiff_out_->partial.string(), pages_))
      throw InputError(paths_.tiff + ": cannot write the TIFF");
    pages_.clear();
    tiff_out_->commit();
  }
}

namespace {

int run_export(const ExportArgs& a, const GlobalOptions& global) {
  const auto segments = recording_segments(a.recording);
  ExportWriter writer({a.tiff, a.npy, a.csv, a.peak_window});
  // Readings below 0 degC: no model reads them, an uncertainty's codes (0.1 K of difference)
  // are mostly there.
  const std::uint16_t freezing = temperature_code(0);
  std::uint64_t readings = 0, below_freezing = 0;
  const RecordingDescription d = read_recording(segments, [&](const RecordingFrame& f) {
    if (f.codes.type() != CV_16U)
      throw InputError(a.recording +
                       ": 8-bit frames, not temperatures (a raw recording? "
                       "re-measure it with pyrocam-calib measure --recording)");
    readings += static_cast<std::uint64_t>(cv::countNonZero(f.codes));
    below_freezing += static_cast<std::uint64_t>(
        cv::countNonZero((f.codes < freezing) & (f.codes != kNoReadingCode)));
    writer.add(f.index, f.timestamp_s, f.codes);
  });
  const auto quantity = d.fields.find("quantity");
  if (quantity != d.fields.end() && quantity->second != "temperature")
    throw InputError(a.recording + ": the recording holds " + quantity->second +
                     ", not temperatures");
  if (d.fields.empty()) {
    // matroskamux writes the tags at a segment's end: a segment cut short has none.
    if (2 * below_freezing > readings)
      throw InputError(a.recording + ": no pyrocam tags, and " + std::to_string(below_freezing) +
                       " of its " + std::to_string(readings) +
                       " readings would be below 0 degC: not temperatures (an uncertainty "
                       "recording cut short before its tags were written?)");
    if (!global.quiet)
      std::cerr << "warning: " << a.recording
                << " has no pyrocam tags (recorded before they existed, not by ratiotemp, or "
                   "cut short before matroskamux wrote them at its end): read as temperatures "
                   "in 0.1 K, 0 = no reading\n";
  }
  writer.finish();
  if (!global.quiet)
    std::cerr << "exported " << writer.frames() << " frames of " << d.width << "x" << d.height
              << " from " << segments.size() << " segment(s)"
              << (d.fields.count("model") ? " (model " + d.fields.at("model") + ")" : "") << "\n";
  return kExitOk;
}

}  // namespace

void add_export_command(CLI::App& app, const GlobalOptions& global, Command& selected) {
  static ExportArgs a;
  CLI::App* c = app.add_subcommand(
      "export", "Export a temperature recording to a TIFF stack, a NumPy array and a CSV");
  c->footer(
      "Outputs (any of them):\n"
      "  --tiff: a multi-page 16-bit TIFF, one page per frame, codes as recorded (0.1 K, 0 = no "
      "reading)\n"
      "  --npy:  a NumPy array, uint16, shape (frames, height, width), the same codes\n"
      "  --csv:  per frame: index, timestamp_s, valid_fraction, min_c, median_c, mean_c, max_c,\n"
      "          peak_c (degC = code / 10 - 273.15 over the pixels with a reading; peak: the\n"
      "          largest median of --peak-window square windows at least half read; empty when\n"
      "          there is none)\n"
      "Example:\n"
      "  pyrocam-calib export --recording out/run1 --npy run1.npy --csv run1.csv");
  c->add_option("--recording", a.recording,
                "Recording folder (temperature-NNNNN.mkv segments, from pipelines/record.sh) or "
                "one segment")
      ->required();
  c->add_option("--tiff", a.tiff, "Multi-page 16-bit TIFF to write (.tif or .tiff)");
  c->add_option("--npy", a.npy, "NumPy .npy file to write");
  c->add_option("--csv", a.csv, "CSV of per-frame statistics to write");
  c->add_option("--peak-window", a.peak_window, "Peak window, pixels (odd, 1 to 255)")
      ->check(CLI::Range(1, 255))
      ->capture_default_str();
  c->callback([&global, &selected] {
    if (a.tiff.empty() && a.npy.empty() && a.csv.empty())
      throw CLI::ValidationError("export", "give at least one of --tiff, --npy, --csv");
    if (a.peak_window % 2 == 0) throw CLI::ValidationError("--peak-window", "must be odd");
    if (!a.tiff.empty()) {
      const std::string ext = fs::path(a.tiff).extension().string();
      if (ext != ".tif" && ext != ".tiff")
        throw CLI::ValidationError("--tiff", "the file name must end in .tif or .tiff");
    }
    selected = [&global] { return run_export(a, global); };
  });
}

}  // namespace pyrocam::cli
