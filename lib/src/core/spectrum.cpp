#include "pyrocam/core/spectrum.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <pugixml.hpp>
#include <sstream>

namespace pyrocam {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, sep)) out.push_back(trim(field));
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
}

bool parse_double(const std::string& text, double& value) {
  if (text.empty()) return false;
  char* end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end == text.c_str() + text.size();
}

void check_increasing(const std::vector<double>& wl, const std::string& origin) {
  for (std::size_t i = 1; i < wl.size(); ++i)
    if (!(wl[i] > wl[i - 1]))
      throw InputError(origin + ": wavelengths not increasing (" + std::to_string(wl[i - 1]) +
                       " nm then " + std::to_string(wl[i]) + " nm)");
}

}  // namespace

std::size_t CsvTable::column_index(const std::string& name) const {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return i;
  std::string names;
  for (const auto& h : header) names += (names.empty() ? "" : ", ") + h;
  throw InputError(path.string() + ": no column '" + name + "' (columns: " + names + ")");
}

CsvTable read_csv_table(const std::filesystem::path& path) {
  require_regular_file(path, "CSV file");
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open file");
  CsvTable table;
  table.path = path;
  std::string line;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    const auto fields = split(t, ',');
    if (table.header.empty()) {
      table.header = fields;
      table.columns.assign(fields.size(), {});
      continue;
    }
    if (fields.size() != table.header.size())
      throw InputError(path.string() + ":" + std::to_string(line_no) + ": " +
                       std::to_string(fields.size()) + " columns, the header has " +
                       std::to_string(table.header.size()));
    for (std::size_t c = 0; c < fields.size(); ++c) {
      double v;
      if (!parse_double(fields[c], v) || !std::isfinite(v))
        throw InputError(path.string() + ":" + std::to_string(line_no) + ": '" + fields[c] +
                         "' in column '" + table.header[c] + "' is not a number");
      table.columns[c].push_back(v);
    }
  }
  if (table.header.empty() || table.columns.empty() || table.columns[0].empty())
    throw InputError(path.string() + ": no data rows");
  return table;
}

Spectrum read_spectrum_csv(const std::filesystem::path& path, const std::string& column,
                           double max_value) {
  const CsvTable table = read_csv_table(path);
  if (table.header.size() < 2)
    throw InputError(path.string() + ": needs a wavelength column and at least one value column");
  const std::size_t wl_col = table.column_index("wavelength_nm");
  std::size_t value_col;
  if (column.empty()) {
    if (table.header.size() != 2)
      throw InputError(path.string() + ": " + std::to_string(table.header.size()) +
                       " columns; name the one to use");
    value_col = wl_col == 0 ? 1 : 0;
  } else {
    value_col = table.column_index(column);
  }
  Spectrum s;
  s.origin = path.string() + (column.empty() ? "" : " [" + column + "]");
  s.wavelength_nm = table.columns[wl_col];
  s.value = table.columns[value_col];
  check_increasing(s.wavelength_nm, s.origin);
  for (std::size_t i = 0; i < s.value.size(); ++i) {
    if (s.value[i] < 0)
      throw InputError(s.origin + ": negative value " + std::to_string(s.value[i]) + " at " +
                       std::to_string(s.wavelength_nm[i]) + " nm");
    if (s.value[i] > max_value)
      throw InputError(s.origin + ": value " + std::to_string(s.value[i]) + " at " +
                       std::to_string(s.wavelength_nm[i]) + " nm is above " +
                       std::to_string(max_value));
  }
  return s;
}

Eigen::VectorXd Spectrum::resample(const WavelengthGrid& grid) const {
  const double tol = 1e-9;
  if (wavelength_nm.empty() || grid.nm()[0] < wavelength_nm.front() - tol ||
      grid.nm()[grid.size() - 1] > wavelength_nm.back() + tol)
    throw InputError(origin + ": covers " + std::to_string(wavelength_nm.front()) + "-" +
                     std::to_string(wavelength_nm.back()) + " nm, the profile's grid needs " +
                     std::to_string(grid.start_nm()) + "-" + std::to_string(grid.stop_nm()) +
                     " nm");
  Eigen::VectorXd out(grid.size());
  std::size_t j = 0;
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    const double x = grid.nm()[i];
    while (j + 2 < wavelength_nm.size() && wavelength_nm[j + 1] < x) ++j;
    if (wavelength_nm.size() == 1) {
      out[i] = value[0];
      continue;
    }
    const double x0 = wavelength_nm[j], x1 = wavelength_nm[j + 1];
    const double f = std::clamp((x - x0) / (x1 - x0), 0.0, 1.0);
    out[i] = value[j] + f * (value[j + 1] - value[j]);
  }
  return out;
}

std::vector<Spectrum> read_imec_band_responses(const std::filesystem::path& path) {
  require_regular_file(path, "IMEC calibration file");
  pugi::xml_document doc;
  const pugi::xml_parse_result ok = doc.load_file(path.c_str());
  if (!ok) throw InputError(path.string() + ": not readable XML (" + ok.description() + ")");
  const pugi::xml_node info =
      doc.select_node("/sensor_calibration/filter_info/calibration_info").node();
  const pugi::xml_node bands =
      doc.select_node("/sensor_calibration/filter_info/filter_zones/filter_zone/bands").node();
  if (!info || !bands)
    throw InputError(path.string() +
                     ": not an IMEC sensor calibration (no calibration_info or bands)");
  const double start = info.child("wavelength_range_start_nm").text().as_double(NAN);
  const double res = info.child("wavelength_resolution_nm").text().as_double(NAN);
  if (!std::isfinite(start) || !(res > 0))
    throw InputError(path.string() + ": wavelength range or resolution missing");
  std::vector<Spectrum> out;
  for (pugi::xml_node band : bands.children("band")) {
    const int index = band.attribute("index").as_int(-1);
    const pugi::xml_node response = band.child("response");
    const std::string origin = path.string() + " [band " + std::to_string(index) + "]";
    if (index != static_cast<int>(out.size()) || !response)
      throw InputError(origin + ": bands must be listed in index order, each with a response");
    Spectrum s;
    s.origin = origin;
    for (const auto& field : split(response.text().as_string(), ',')) {
      double v;
      if (!parse_double(field, v) || !std::isfinite(v))
        throw InputError(origin + ": response value '" + field + "' is not a number");
      if (v < 0) throw InputError(origin + ": negative QE " + field);
      s.value.push_back(v);
    }
    const int declared = response.attribute("nr_elements").as_int(-1);
    if (declared != static_cast<int>(s.value.size()))
      throw InputError(origin + ": response has " + std::to_string(s.value.size()) +
                       " values, nr_elements says " + std::to_string(declared));
    for (std::size_t i = 0; i < s.value.size(); ++i) s.wavelength_nm.push_back(start + i * res);
    out.push_back(std::move(s));
  }
  if (out.empty()) throw InputError(path.string() + ": no bands");
  return out;
}

}  // namespace pyrocam
