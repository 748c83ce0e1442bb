// `pyrocam-calib export`: a temperature recording (pipelines/record.sh) to a 16-bit multi-page
// TIFF, a NumPy .npy array and a CSV of per-frame statistics, for tools outside GStreamer.
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

// An output written beside its final name and renamed when complete: a failed export leaves
// no partial file under the name asked for.
struct Output {
  explicit Output(const std::string& p) : path(p), partial(p + ".partial") {}
  ~Output() {
    std::error_code ec;
    if (!done) fs::remove(partial, ec);
  }
  void commit() {
    fs::rename(partial, path);
    done = true;
  }
  fs::path path, partial;
  bool done = false;
};

int run_export(const ExportArgs& a, const GlobalOptions& global) {
  const auto segments = recording_segments(a.recording);
  std::optional<Output> npy_out, csv_out, tiff_out;
  std::ofstream npy, csv;
  if (!a.npy.empty()) {
    npy_out.emplace(a.npy);
    npy.open(npy_out->partial, std::ios::binary);
    if (!npy) throw InputError(a.npy + ": cannot write");
    npy << npy_header(0, 0, 0);
  }
  if (!a.csv.empty()) {
    csv_out.emplace(a.csv);
    csv.open(csv_out->partial);
    if (!csv) throw InputError(a.csv + ": cannot write");
    csv << "index,timestamp_s,valid_fraction,min_c,median_c,mean_c,max_c,peak_c\n";
  }
  if (!a.tiff.empty()) tiff_out.emplace(a.tiff);
  std::vector<cv::Mat> pages;
  constexpr std::size_t kMaxTiffBytes = std::size_t{2} << 30;  // held in memory until written
  std::size_t tiff_bytes = 0, frames = 0;
  int width = 0, height = 0;
  const RecordingDescription d = read_recording(segments, [&](const RecordingFrame& f) {
    width = f.codes.cols;
    height = f.codes.rows;
    ++frames;
    if (npy.is_open()) {
      npy.write(reinterpret_cast<const char*>(f.codes.data),
                static_cast<std::streamsize>(f.codes.total() * 2));  // x86-64: little-endian
      if (!npy) throw InputError(a.npy + ": write failed");
    }
    if (tiff_out) {
      tiff_bytes += f.codes.total() * 2;
      if (tiff_bytes > kMaxTiffBytes)
        throw InputError(a.recording +
                         ": more than 2 GiB of frames for one TIFF; export it to "
                         ".npy, or a part of it");
      pages.push_back(f.codes);
    }
    if (csv.is_open()) {
      const cv::Mat t = decode_decikelvin(f.codes);
      const RegionStats s = region_stats(t);
      const RegionPeak p = region_peak(t, a.peak_window);
      csv << f.index << ',' << csv_number(f.timestamp_s, 6) << ','
          << csv_number(s.valid_fraction, 6) << ',' << csv_number(s.min_c, 2) << ','
          << csv_number(s.median_c, 2) << ',' << csv_number(s.mean_c, 3) << ','
          << csv_number(s.max_c, 2) << ',' << csv_number(p.c, 2) << '\n';
      if (!csv) throw InputError(a.csv + ": write failed");
    }
  });
  const auto quantity = d.fields.find("quantity");
  if (quantity != d.fields.end() && quantity->second != "temperature")
    throw InputError(a.recording + ": the recording holds " + quantity->second +
                     ", not temperatures");
  if (d.fields.empty() && !global.quiet)
    std::cerr << "warning: " << a.recording
              << " has no pyrocam tags (recorded before they existed, or not by ratiotemp): "
                 "read as temperatures in 0.1 K, 0 = no reading\n";
  if (npy.is_open()) {
    npy.seekp(0);
    npy << npy_header(frames, height, width);
    npy.close();
    if (!npy) throw InputError(a.npy + ": write failed");
    npy_out->commit();
  }
  if (csv.is_open()) {
    csv.close();
    if (!csv) throw InputError(a.csv + ": write failed");
    csv_out->commit();
  }
  if (tiff_out) {
    // The extension tells OpenCV the format; the partial name has to keep it.
    tiff_out->partial = tiff_out->path.string() + ".partial.tif";
    if (!cv::imwritemulti(tiff_out->partial.string(), pages))
      throw InputError(a.tiff + ": cannot write the TIFF");
    tiff_out->commit();
  }
  if (!global.quiet)
    std::cerr << "exported " << frames << " frames of " << width << "x" << height << " from "
              << segments.size() << " segment(s)"
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
