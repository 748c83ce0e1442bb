#include "pyrocam/core/dataset.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <tuple>
#include <utility>

#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"

namespace pyrocam {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

double parse_number(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(v))
    throw InputError(where + ": '" + text + "' is not a number");
  return v;
}

// A manifest file name must stay inside the dataset folder, lexically: relative, no ".." that
// climbs out, and nothing the operating system would cut or reinterpret (a NUL ends a C string).
void check_relative_file_name(const std::string& name, const std::string& where) {
  if (name.empty()) throw InputError(where + ": empty file name");
  for (const char c : name)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) {
      char code[8];
      std::snprintf(code, sizeof code, "0x%02x",
                    static_cast<unsigned>(static_cast<unsigned char>(c)));
      throw InputError(where + ": file name holds a control character (byte " + code +
                       "); file names must be printable text");
    }
  const std::filesystem::path p(name);
  if (p.is_absolute() || p.has_root_name() || p.has_root_directory())
    throw InputError(where + ": file '" + name +
                     "' is an absolute path; files must be relative to the dataset folder");
  const std::filesystem::path normal = p.lexically_normal();
  if (normal.empty() || *normal.begin() == ".." || normal == ".")
    throw InputError(where + ": file '" + name + "' leaves the dataset folder");
}

const char* kind_name(FrameKind kind) {
  switch (kind) {
    case FrameKind::kDark:
      return "dark";
    case FrameKind::kReference:
      return "reference";
    case FrameKind::kFrame:
      break;
  }
  return "frame";
}

FrameKind parse_kind(const std::string& text, const std::string& where) {
  for (const FrameKind k : {FrameKind::kFrame, FrameKind::kDark, FrameKind::kReference})
    if (text == kind_name(k)) return k;
  throw InputError(where + ": kind '" + text + "' must be 'frame', 'dark' or 'reference'");
}

// Comma-separated fields, trimmed. An empty last field is kept only when `keep_empty_last`: a
// 4-column manifest has always accepted a trailing comma.
std::vector<std::string> split_fields(const std::string& line, bool keep_empty_last) {
  std::vector<std::string> f;
  std::size_t start = 0;
  bool last_empty = false;
  for (;;) {
    const std::size_t comma = line.find(',', start);
    const std::string raw = line.substr(start, comma == std::string::npos ? comma : comma - start);
    last_empty = raw.empty();
    f.push_back(trim(raw));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (!keep_empty_last && f.size() > 1 && last_empty) f.pop_back();
  return f;
}

// An image is taken at one setting: listed again it must be at the same one (a dark may serve
// several furnace temperatures, not several exposures). A copy-paste slip would otherwise
// average one image into two settings. `seen`: each file's first row, by normalised name.
void check_one_setting_per_file(const ManifestRow& row, const std::vector<ManifestRow>& rows,
                                std::map<std::string, std::size_t>& seen,
                                const std::string& where) {
  const std::string name = std::filesystem::path(row.file).lexically_normal().string();
  const auto [it, first] = seen.emplace(name, rows.size());
  if (first) return;
  const ManifestRow& e = rows[it->second];
  const bool same = e.kind == row.kind && e.exposure_us == row.exposure_us &&
                    (row.kind == FrameKind::kDark || e.temperature_c == row.temperature_c);
  if (same) return;
  std::ostringstream m;
  m << where << ": " << row.file << " is also listed at line " << e.line << " as "
    << kind_name(e.kind) << " at " << e.temperature_c << " degC, " << e.exposure_us
    << " us: one image is one setting";
  throw InputError(m.str());
}

}  // namespace

bool same_exposure(double a_us, double b_us) {
  return std::abs(a_us - b_us) <= 1e-6 * std::max(std::abs(a_us), std::abs(b_us));
}

std::vector<ManifestRow> read_manifest(const std::filesystem::path& path) {
  require_regular_file(path, "manifest");  // before opening: a FIFO would block
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": manifest unreadable");
  std::string line;
  if (!std::getline(in, line)) line.clear();
  // A byte-order mark, as spreadsheet programs write UTF-8: not part of the header.
  if (line.rfind("\xEF\xBB\xBF", 0) == 0) line.erase(0, 3);
  const std::string header = trim(line);
  const bool with_uncertainty = header == kManifestHeaderWithUncertainty;
  if (header != kManifestHeader && !with_uncertainty)
    throw InputError(path.string() + ": first line must be '" + kManifestHeader + "' or '" +
                     kManifestHeaderWithUncertainty + "'");
  std::vector<ManifestRow> rows;
  std::map<std::string, std::size_t> seen;
  int line_no = 1;
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const std::string where = path.string() + ":" + std::to_string(line_no);
    const std::vector<std::string> f = split_fields(line, with_uncertainty);
    if (with_uncertainty ? f.size() != 4 && f.size() != 5 : f.size() != 4)
      throw InputError(where + ": " + std::to_string(f.size()) + " fields, expected " +
                       (with_uncertainty ? "5" : "4") + " (" + header + ")");
    ManifestRow row;
    row.file = f[0];
    row.line = line_no;
    check_relative_file_name(row.file, where);
    row.kind = parse_kind(f[1], where);
    row.temperature_c = parse_number(f[2], where + " temperature_c");
    row.exposure_us = parse_number(f[3], where + " exposure_us");
    if (!(row.exposure_us > 0)) throw InputError(where + ": exposure_us must be > 0");
    if (f.size() == 5 && !f[4].empty()) {
      row.temperature_uncertainty_c = parse_number(f[4], where + " temperature_uncertainty_c");
      if (!(row.temperature_uncertainty_c > 0))
        throw InputError(where +
                         ": temperature_uncertainty_c must be > 0 (a standard "
                         "uncertainty in degC), not " +
                         f[4]);
    }
    check_one_setting_per_file(row, rows, seen, where);
    rows.push_back(std::move(row));
  }
  if (rows.empty()) throw InputError(path.string() + ": no rows");
  return rows;
}

void write_manifest(const std::filesystem::path& path, const std::vector<ManifestRow>& rows) {
  std::ofstream out(path);
  if (!out) throw InputError(path.string() + ": cannot write manifest");
  const bool with_uncertainty = std::any_of(rows.begin(), rows.end(), [](const ManifestRow& r) {
    return std::isfinite(r.temperature_uncertainty_c);
  });
  out << (with_uncertainty ? kManifestHeaderWithUncertainty : kManifestHeader) << "\n"
      << std::setprecision(10);
  for (const auto& r : rows) {
    out << r.file << "," << kind_name(r.kind) << "," << r.temperature_c << "," << r.exposure_us;
    if (with_uncertainty) {
      out << ",";
      if (std::isfinite(r.temperature_uncertainty_c)) out << r.temperature_uncertainty_c;
    }
    out << "\n";
  }
  if (!out) throw InputError(path.string() + ": write failed");
}

std::string parse_mosaic_pattern(const std::string& text, const std::string& where) {
  std::string p = trim(text);
  std::transform(p.begin(), p.end(), p.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* bayer : {"rggb", "bggr", "grbg", "gbrg"})
    if (p == bayer) return p;
  const auto x = p.find('x');
  auto period = [](const std::string& n) {
    return !n.empty() && n.size() <= 2 && n[0] != '0' &&
           std::all_of(n.begin(), n.end(), [](unsigned char c) { return std::isdigit(c); });
  };
  if (x != std::string::npos && period(p.substr(0, x)) && period(p.substr(x + 1))) return p;
  throw InputError(where + ": mosaic layout '" + text +
                   "' is not rggb, bggr, grbg, gbrg or a snapshot period such as 5x5");
}

void write_mosaic_pattern(const std::filesystem::path& folder, const std::string& pattern) {
  const auto path = folder / kMosaicFile;
  std::ofstream out(path);
  out << parse_mosaic_pattern(pattern, path.string()) << "\n";
  if (!out) throw InputError(path.string() + ": cannot write");
}

Dataset Dataset::open(const std::filesystem::path& folder) {
  if (!std::filesystem::is_directory(folder))
    throw InputError(folder.string() + ": dataset folder not found");
  Dataset d;
  d.folder_ = folder;
  d.rows_ = read_manifest(folder / "manifest.csv");
  const auto& rows = d.rows_;
  if (const auto mosaic = folder / kMosaicFile; std::filesystem::exists(mosaic)) {
    require_regular_file(mosaic, "mosaic layout file");
    std::ifstream in(mosaic);
    std::string line;
    std::getline(in, line);
    d.mosaic_pattern_ = parse_mosaic_pattern(line, mosaic.string());
  }

  std::filesystem::path roi_path;
  for (const char* name : {"roi.png", "roi.pgm"})
    if (std::filesystem::exists(folder / name)) roi_path = folder / name;
  if (roi_path.empty()) throw InputError(folder.string() + ": no roi.png or roi.pgm");
  const cv::Mat roi = read_raw_image(roi_path);
  d.roi_ = roi != 0;
  if (cv::countNonZero(d.roi_) == 0)
    throw InputError(roi_path.string() + ": the ROI is empty (no nonzero pixel)");
  if (const auto ref_path = folder / kReferenceRoiFile; std::filesystem::exists(ref_path)) {
    d.reference_roi_ = read_raw_image(ref_path, d.roi_.size(), "the ROI's size") != 0;
    if (cv::countNonZero(d.reference_roi_) == 0)
      throw InputError(ref_path.string() + ": the reference ROI is empty (no nonzero pixel)");
  }

  std::map<std::tuple<int, double, double>, FrameGroup> groups;
  // The first stated uncertainty per (kind, temperature) and its line: the rows of one source
  // must agree (a dark's temperature is informational, so is its uncertainty).
  std::map<std::pair<int, double>, std::pair<double, int>> stated;
  std::error_code ec;
  const auto canonical_folder = std::filesystem::weakly_canonical(folder, ec);
  if (ec)
    throw InputError(folder.string() + ": cannot resolve the dataset folder (" + ec.message() +
                     ")");
  for (const auto& r : rows) {
    const auto file = folder / r.file;
    const std::string row = file.string() + " (manifest.csv line " + std::to_string(r.line) + ")";
    const auto type = std::filesystem::status(file, ec).type();
    if (type == std::filesystem::file_type::not_found)
      throw InputError(row + ": listed but not found");
    if (type == std::filesystem::file_type::directory)
      throw InputError(row + ": is a directory, not an image");
    if (type != std::filesystem::file_type::regular)
      throw InputError(row + ": is not a regular file (a FIFO, socket or device)");
    // A symbolic link inside the folder must not lead out of it either.
    const auto resolved = std::filesystem::weakly_canonical(file, ec);
    const auto inside = resolved.lexically_relative(canonical_folder);
    if (ec || inside.empty() || *inside.begin() == "..")
      throw InputError(row + ": resolves to " + resolved.string() + ", outside the dataset folder");
    // Rounded keys merge rows whose numbers differ only by text formatting.
    const double t_key = r.kind == FrameKind::kDark ? 0.0 : std::round(r.temperature_c * 1e6);
    if (r.kind != FrameKind::kDark && std::isfinite(r.temperature_uncertainty_c)) {
      const auto [it, first] = stated.try_emplace({static_cast<int>(r.kind), t_key},
                                                  r.temperature_uncertainty_c, r.line);
      const double u = it->second.first;
      if (!first && std::abs(u - r.temperature_uncertainty_c) > 1e-9 * u) {
        std::ostringstream m;
        m << row << ": temperature_uncertainty_c " << r.temperature_uncertainty_c
          << " differs from the " << u << " that line " << it->second.second
          << " states for the same " << kind_name(r.kind) << " temperature";
        throw InputError(m.str());
      }
    }
    const auto key =
        std::make_tuple(static_cast<int>(r.kind), t_key, std::round(r.exposure_us * 1e3));
    FrameGroup& g = groups[key];
    if (g.files.empty()) g.line = r.line;
    g.kind = r.kind;
    g.temperature_c = r.temperature_c;
    g.exposure_us = r.exposure_us;
    g.files.push_back(file);
  }
  for (auto& [key, g] : groups) {
    const auto u = stated.find({std::get<0>(key), std::get<1>(key)});
    if (u != stated.end())
      g.temperature_uncertainty_c = u->second.first;
    else if (g.kind == FrameKind::kReference)
      g.temperature_uncertainty_c = kDefaultReferenceUncertaintyC;
    (g.kind == FrameKind::kDark        ? d.darks_
     : g.kind == FrameKind::kReference ? d.references_
                                       : d.frames_)
        .push_back(g);
  }
  if (d.frames_.empty()) throw InputError(folder.string() + ": manifest lists no frames");
  // Every exposure of the frames and references has a dark; else the first group without one,
  // by its file and manifest line.
  const auto require_dark = [&](const FrameGroup& g, const char* what, const char* verb) {
    if (std::any_of(d.darks_.begin(), d.darks_.end(), [&](const FrameGroup& k) {
          return same_exposure(k.exposure_us, g.exposure_us);
        }))
      return;
    std::ostringstream m;
    m << std::setprecision(15) << g.files.front().string() << " (manifest.csv line " << g.line
      << "): " << what << " at " << g.temperature_c << " degC, exposure " << g.exposure_us << " us "
      << verb << " no dark row of that exposure";
    throw InputError(m.str());
  };
  for (const auto& f : d.frames_) require_dark(f, "frames", "have");
  for (const auto& g : d.references_) require_dark(g, "reference", "has");
  return d;
}

const FrameGroup& Dataset::dark_for(double exposure_us) const {
  for (const auto& g : darks_)
    if (same_exposure(g.exposure_us, exposure_us)) return g;
  std::ostringstream msg;
  msg << std::setprecision(15) << folder_.string() << ": no dark frame for exposure " << exposure_us
      << " us";
  throw InputError(msg.str());
}

std::vector<double> Dataset::temperatures_c() const {
  std::vector<double> t;
  for (const auto& g : frames_)
    if (t.empty() || std::abs(t.back() - g.temperature_c) > 1e-9) t.push_back(g.temperature_c);
  return t;
}

cv::Mat Dataset::load(const std::filesystem::path& file) const {
  // The header is checked against the ROI's size before anything is decoded.
  cv::Mat img = read_raw_image(file, roi_.size(), "the dataset's (ROI) size");
  const int depth = img.depth() == CV_8U ? 8 : 16;
  if (bit_depth_ == 0) bit_depth_ = depth;
  if (depth != bit_depth_)
    throw InputError(file.string() + ": " + std::to_string(depth) + "-bit image in a " +
                     std::to_string(bit_depth_) + "-bit dataset");
  return img;
}

cv::Mat Dataset::average(const FrameGroup& group) const {
  cv::Mat sum = cv::Mat::zeros(height(), width(), CV_64F);
  for (const auto& f : group.files) cv::add(sum, load(f), sum, cv::noArray(), CV_64F);
  return sum / static_cast<double>(group.files.size());
}

}  // namespace pyrocam
