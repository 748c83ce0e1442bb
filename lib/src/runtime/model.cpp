#include "pyrocam/runtime/model.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "detail/json_input.h"
#include "detail/json_text.h"
#include "mlp_layers_text.h"
#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

using nlohmann::json;

// A number in messages: "-5", "1e+300", "0.25".
std::string to_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

json matrix_to_json(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    const Eigen::VectorXd row = m.row(r).transpose();
    rows.push_back(std::vector<double>(row.data(), row.data() + row.size()));
  }
  return rows;
}

Eigen::MatrixXd matrix_from_json(const json& j, Eigen::Index rows, Eigen::Index cols,
                                 const std::string& what) {
  if (!j.is_array() || static_cast<Eigen::Index>(j.size()) != rows)
    throw InputError(what + " must have " + std::to_string(rows) + " rows");
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index r = 0; r < rows; ++r) {
    const auto& row = j[static_cast<std::size_t>(r)];
    if (!row.is_array() || static_cast<Eigen::Index>(row.size()) != cols)
      throw InputError(what + " rows must have " + std::to_string(cols) + " values");
    for (Eigen::Index c = 0; c < cols; ++c) {
      const json& v = row[static_cast<std::size_t>(c)];
      if (!v.is_number()) throw InputError(what + " holds a value that is not a number");
      m(r, c) = v.get<double>();
      if (!std::isfinite(m(r, c)) || m(r, c) < 0)
        throw InputError(what + "[" + std::to_string(r) + "][" + std::to_string(c) + "] is " +
                         to_text(m(r, c)) + "; QE values must be finite and >= 0");
    }
  }
  return m;
}

double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
  if (x.empty()) return 0;
  if (at <= x.front()) return y.front();
  if (at >= x.back()) return y.back();
  const auto it = std::upper_bound(x.begin(), x.end(), at);
  const std::size_t i = static_cast<std::size_t>(it - x.begin());
  const double f = (at - x[i - 1]) / (x[i] - x[i - 1]);
  return y[i - 1] + f * (y[i] - y[i - 1]);
}

// A list of finite numbers, each within [lo, hi]; the message names the field and the value.
std::vector<double> numbers_within(const json& j, const std::string& what, double lo, double hi) {
  if (!j.is_array()) throw InputError(what + " must be a list of numbers");
  std::vector<double> out;
  out.reserve(j.size());
  for (std::size_t i = 0; i < j.size(); ++i) {
    if (!j[i].is_number()) throw InputError(what + "[" + std::to_string(i) + "] is not a number");
    const double v = j[i].get<double>();
    if (!(v >= lo && v <= hi))
      throw InputError(what + "[" + std::to_string(i) + "] is " + to_text(v) + ", outside " +
                       to_text(lo) + ".." + to_text(hi));
    out.push_back(v);
  }
  return out;
}

double number_within(const json& j, const std::string& what, double lo, double hi) {
  if (!j.is_number()) throw InputError(what + " is not a number");
  const double v = j.get<double>();
  if (!(v >= lo && v <= hi))
    throw InputError(what + " is " + to_text(v) + ", outside " + to_text(lo) + ".." + to_text(hi));
  return v;
}

// FNV-1a 64's offset basis, and the one models were written with before 2026-12 (a digit
// short), still read.
constexpr std::uint64_t kFnv1aOffsetBasis = 14695981039346656037ull;
constexpr std::uint64_t kEarlierOffsetBasis = 1469598103934665603ull;
constexpr std::uint64_t kFnv1aPrime = 1099511628211ull;

std::string hex16(std::uint64_t h) {
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string fnv1a_hex_from(std::uint64_t basis, const std::string& text) {
  std::uint64_t h = basis;
  for (unsigned char c : text) h = (h ^ c) * kFnv1aPrime;
  return hex16(h);
}

// Whether `checksum` is the payload text's, with either offset basis.
bool checksum_of(const std::string& checksum, const std::string& payload_text) {
  return !checksum.empty() && (fnv1a_hex_from(kFnv1aOffsetBasis, payload_text) == checksum ||
                               fnv1a_hex_from(kEarlierOffsetBasis, payload_text) == checksum);
}

// The checksums (both offset bases) of payload.dump() without the dump, from the file's own
// text, when the file is as save_model writes it: dump() is the payload's text with the white
// space outside strings left out. Empty when the payload is not found (then the caller dumps the
// parsed payload).
std::vector<std::string> payload_text_checksums(const std::string& text) {
  auto skip_space = [&](std::size_t i) { return detail::json_skip_space(text, i); };
  std::vector<std::string> found;  // the payload's checksums
  std::size_t i = skip_space(0);
  if (i >= text.size() || text[i] != '{') return {};
  for (i = skip_space(i + 1); i < text.size() && text[i] == '"';) {
    const std::size_t key_end = detail::json_value_end(text, i);
    if (key_end == std::string::npos) return {};
    const bool payload = text.compare(i, key_end - i, "\"payload\"") == 0;
    i = skip_space(key_end);
    if (i >= text.size() || text[i] != ':') return {};
    const std::size_t start = skip_space(i + 1), end = detail::json_value_end(text, start);
    if (end == std::string::npos) return {};
    if (payload) {
      // The parser keeps the last of two payloads: with two, the dump decides.
      if (!found.empty()) return {};
      std::uint64_t h = kFnv1aOffsetBasis, earlier = kEarlierOffsetBasis;
      bool in_string = false, escaped = false;
      for (std::size_t k = start; k < end; ++k) {
        const unsigned char c = static_cast<unsigned char>(text[k]);
        if (in_string) {
          if (escaped)
            escaped = false;
          else if (c == '\\')
            escaped = true;
          else if (c == '"')
            in_string = false;
        } else if (c == '"') {
          in_string = true;
        } else if (c == ' ' || c == '\n' || c == '\t' || c == '\r') {
          continue;
        }
        h = (h ^ c) * kFnv1aPrime;
        earlier = (earlier ^ c) * kFnv1aPrime;
      }
      found = {hex16(h), hex16(earlier)};
    }
    i = skip_space(end);
    if (i < text.size() && text[i] == ',') i = skip_space(i + 1);
  }
  return found;
}

}  // namespace

double UncertaintyModel::systematic_u_c(double t) const {
  const double a = interpolate(temperature_c, u_calibration_c, t);
  const double b = interpolate(temperature_c, u_emissivity_c, t);
  const double c = u_qe_model_c.empty() ? 0.0 : interpolate(temperature_c, u_qe_model_c, t);
  return std::sqrt(a * a + b * b + c * c);
}

std::string fnv1a_hex(const std::string& text) { return fnv1a_hex_from(kFnv1aOffsetBasis, text); }

void save_model(const ThermalModel& m, const std::filesystem::path& path) {
  json payload;
  payload["profile"] = profile_to_json(m.camera.profile);
  payload["system_qe"] = matrix_to_json(m.camera.system_qe);
  payload["datasheet_qe"] = matrix_to_json(m.datasheet_qe);
  const Eigen::VectorXd& k = m.camera.band_scale;
  payload["band_scale"] = std::vector<double>(k.data(), k.data() + k.size());
  payload["qe_solver"] = m.qe_solver;
  payload["temperature_range_c"] = {m.min_temperature_c, m.max_temperature_c};
  if (std::isfinite(m.calibrated_up_to_c)) payload["calibrated_up_to_c"] = m.calibrated_up_to_c;
  payload["mlp"] = m.mlp.to_json();
  const UncertaintyModel& u = m.uncertainty;
  // JSON has no NaN: it would be written as null and the model refused when loaded.
  for (const auto& [name, values] : {std::pair{"u_calibration_c", &u.u_calibration_c},
                                     {"u_emissivity_c", &u.u_emissivity_c},
                                     {"u_qe_model_c", &u.u_qe_model_c},
                                     {"temperature_c", &u.temperature_c}})
    for (std::size_t i = 0; i < values->size(); ++i)
      if (!std::isfinite((*values)[i]))
        throw InputError(path.string() + ": not written: uncertainty." + name + "[" +
                         std::to_string(i) + "] is not a number");
  payload["uncertainty"] = {{"temperature_c", u.temperature_c},
                            {"u_calibration_c", u.u_calibration_c},
                            {"u_emissivity_c", u.u_emissivity_c},
                            {"u_qe_model_c", u.u_qe_model_c},
                            {"thermocouple_tolerance_c", u.thermocouple_tolerance_c},
                            {"emissivity_slope_u", u.emissivity_slope_u},
                            {"monte_carlo_refits", u.monte_carlo_refits},
                            {"coverage_factor", u.coverage_factor}};
  payload["provenance"] = m.provenance;
  payload["summary"] = m.summary;
  const std::string text = payload.dump();
  json file = {{"format", kModelFormat},
               {"version", kModelFormatVersion},
               {"checksum_fnv1a64", fnv1a_hex(text)},
               {"payload", payload}};
  const auto tmp = path.string() + ".partial";
  {
    std::ofstream out(tmp);
    if (!out) throw InputError(path.string() + ": cannot write model file");
    out << file.dump(1) << "\n";
    if (!out) throw InputError(path.string() + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    const std::string why = ec.message();
    std::filesystem::remove(tmp, ec);
    throw InputError(path.string() + ": cannot write the model file there (" + why + ")");
  }
}

ThermalModel load_model(const std::filesystem::path& path) {
  const std::string where = path.string();
  require_regular_file(path, "model file");
  std::error_code size_error;
  const std::uintmax_t bytes = std::filesystem::file_size(path, size_error);
  if (!size_error && bytes > kModelMaxFileBytes)
    throw InputError(where + ": model file is " + std::to_string(bytes >> 20) +
                     " MB, more than any model (at most " +
                     std::to_string(kModelMaxFileBytes >> 20) + " MB)");
  // Read whole, then parsed from memory: a stream fed the parser a character at a time.
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where + ": model file unreadable");
  // In blocks: a string built from stream iterators grows a byte at a time.
  std::string text;
  if (!size_error) text.reserve(static_cast<std::size_t>(bytes));
  std::vector<char> block(std::size_t{1} << 16);
  while (in.read(block.data(), static_cast<std::streamsize>(block.size())) || in.gcount() > 0)
    text.append(block.data(), static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw InputError(where + ": model file unreadable");
  // The network's layers, most of the text, are read by a faster scanner than the parser
  // (mlp_layers_text.h), and the parser reads the rest with the layers left as []. Anything the
  // scanner does not read, and any error in the rest, goes through the parser whole: it names
  // what is wrong, where it is in the file.
  std::optional<std::pair<std::size_t, std::size_t>> span;
  if (const auto payload_span = detail::json_member_span(text, 0, "payload"))
    if (const auto mlp_span = detail::json_member_span(text, payload_span->first, "mlp"))
      span = detail::json_member_span(text, mlp_span->first, "layers");
  // The checksum of the payload's text on another core while the parser reads the rest. The
  // layers' scan goes with whichever takes less: the parser takes about six times as long per
  // byte as the checksum (measured on both test models), so with a rest of more than a sixth of
  // the file (a 5x5 model's profile and QE) the scan goes with the checksum. Neither throws but
  // on allocation failure.
  const std::size_t layer_bytes = span ? span->second - span->first : 0;
  const bool layers_beside_checksum = span && 6 * (text.size() - layer_bytes) > text.size();
  std::vector<std::string> from_text;
  std::optional<std::vector<MlpLayer>> layers;
  const auto read_layers = [&] {
    if (span)
      layers = detail::read_layers_text(std::string_view(text).substr(span->first, layer_bytes));
  };
  const auto checksum_and_layers = [&] {
    try {
      from_text = payload_text_checksums(text);
      if (layers_beside_checksum) read_layers();
    } catch (...) {
      from_text.clear();  // the dump decides
      layers.reset();     // the parser reads them
    }
  };
  std::thread checksum_thread;
  try {
    checksum_thread = std::thread(checksum_and_layers);
  } catch (const std::system_error&) {
    checksum_and_layers();
  }
  struct Join {
    std::thread& t;
    ~Join() {
      if (t.joinable()) t.join();
    }
  } join{checksum_thread};
  auto parse = [&](const std::string& json_text) {
    try {
      return parse_bounded_json(json_text, where);
    } catch (const json::exception& e) {
      throw InputError(where +
                       ": not a complete JSON model file (truncated or corrupt): " + e.what());
    }
  };
  if (!layers_beside_checksum) read_layers();
  json file;
  bool rest_parsed = false;
  if (span) {
    std::string rest;
    rest.reserve(text.size() - (span->second - span->first) + 2);
    rest.append(text, 0, span->first).append("[]").append(text, span->second);
    try {
      file = parse_bounded_json(rest, where);
      rest_parsed = true;
    } catch (const std::exception&) {  // the parser reads the whole text below and names it
    }
  }
  if (checksum_thread.joinable()) checksum_thread.join();
  if (!rest_parsed) layers.reset();
  if (!layers) file = parse(text);
  try {
    if (!file.is_object() || file.value("format", std::string()) != kModelFormat)
      throw InputError(where + ": not a pyrocam thermal model (format is not \"" +
                       std::string(kModelFormat) + "\")");
    const int version = file.value("version", -1);
    if (version != kModelFormatVersion)
      throw InputError(where + ": model format version " + std::to_string(version) +
                       ", this build reads version " + std::to_string(kModelFormatVersion) +
                       "; recalibrate with this pyrocam-calib");
    // The file's own text first (no dump of megabytes); a payload written in another layout
    // (another program's white space or number format) is checked as before, by its dump, for
    // which the layers must be parsed too.
    const std::string checksum = file.value("checksum_fnv1a64", std::string());
    const bool text_checked = !checksum.empty() && std::find(from_text.begin(), from_text.end(),
                                                             checksum) != from_text.end();
    if (layers && !text_checked) {
      layers.reset();
      file = parse(text);
    }
    const json& payload = file.at("payload");
    if (!text_checked && !checksum_of(checksum, payload.dump()))
      throw InputError(where + ": checksum mismatch: the model file was edited or corrupted");

    ThermalModel m;
    m.fingerprint = file.value("checksum_fnv1a64", std::string());
    m.camera.profile = profile_from_json(payload.at("profile"), path);
    const CameraProfile& p = m.camera.profile;
    const Eigen::Index bands = p.band_count(), wl = p.grid.size();
    m.camera.system_qe =
        matrix_from_json(payload.at("system_qe"), bands, wl, where + ": system_qe");
    m.datasheet_qe =
        matrix_from_json(payload.at("datasheet_qe"), bands, wl, where + ": datasheet_qe");
    const auto k = numbers_within(payload.at("band_scale"), where + ": band_scale",
                                  std::numeric_limits<double>::min(), kModelMaxBandScale);
    if (static_cast<Eigen::Index>(k.size()) != bands)
      throw InputError(where + ": band_scale must have one value per band");
    m.camera.band_scale = Eigen::Map<const Eigen::VectorXd>(k.data(), bands);
    m.qe_solver = payload.at("qe_solver").get<std::string>();
    const auto range =
        numbers_within(payload.at("temperature_range_c"), where + ": temperature_range_c",
                       kModelMinTemperatureC, kModelMaxTemperatureC);
    if (range.size() != 2 || !(range[0] < range[1]))
      throw InputError(where + ": temperature_range_c must be [min, max] with min < max");
    m.min_temperature_c = range[0];
    m.max_temperature_c = range[1];
    if (payload.contains("calibrated_up_to_c")) {
      const json& top = payload.at("calibrated_up_to_c");
      if (!top.is_number() ||
          !(top.get<double>() >= m.min_temperature_c && top.get<double>() <= m.max_temperature_c))
        throw InputError(where +
                         ": calibrated_up_to_c must be a temperature within "
                         "temperature_range_c");
      m.calibrated_up_to_c = top.get<double>();
    }
    try {
      m.mlp = Mlp::from_json(payload.at("mlp"), std::move(layers));
    } catch (const std::exception& e) {
      throw InputError(where + ": MLP: " + e.what());
    }
    if (m.mlp.input_size() != static_cast<int>(p.normalisation.numerators.size()))
      throw InputError(where + ": the MLP takes " + std::to_string(m.mlp.input_size()) +
                       " inputs, the normalisation gives " +
                       std::to_string(p.normalisation.numerators.size()));
    const json& u = payload.at("uncertainty");
    const std::string uw = where + ": uncertainty.";
    UncertaintyModel& um = m.uncertainty;
    um.temperature_c = numbers_within(u.at("temperature_c"), uw + "temperature_c",
                                      kModelMinTemperatureC, kModelMaxTemperatureC);
    um.u_calibration_c =
        numbers_within(u.at("u_calibration_c"), uw + "u_calibration_c", 0, kModelMaxUncertaintyC);
    um.u_emissivity_c =
        numbers_within(u.at("u_emissivity_c"), uw + "u_emissivity_c", 0, kModelMaxUncertaintyC);
    if (u.contains("u_qe_model_c")) {
      um.u_qe_model_c =
          numbers_within(u.at("u_qe_model_c"), uw + "u_qe_model_c", 0, kModelMaxUncertaintyC);
      if (!um.u_qe_model_c.empty() && um.u_qe_model_c.size() != um.temperature_c.size())
        throw InputError(uw + "u_qe_model_c has " + std::to_string(um.u_qe_model_c.size()) +
                         " rows, temperature_c " + std::to_string(um.temperature_c.size()));
    }
    if (um.temperature_c.empty())
      throw InputError(uw + "temperature_c is empty; the uncertainty table needs at least one row");
    if (um.u_calibration_c.size() != um.temperature_c.size() ||
        um.u_emissivity_c.size() != um.temperature_c.size())
      throw InputError(uw + "temperature_c, u_calibration_c and u_emissivity_c differ in length (" +
                       std::to_string(um.temperature_c.size()) + ", " +
                       std::to_string(um.u_calibration_c.size()) + ", " +
                       std::to_string(um.u_emissivity_c.size()) + ")");
    for (std::size_t i = 1; i < um.temperature_c.size(); ++i)
      if (!(um.temperature_c[i] > um.temperature_c[i - 1]))
        throw InputError(uw + "temperature_c must increase (" + to_text(um.temperature_c[i - 1]) +
                         " then " + to_text(um.temperature_c[i]) + ")");
    um.thermocouple_tolerance_c =
        number_within(u.at("thermocouple_tolerance_c"), uw + "thermocouple_tolerance_c", 0,
                      kModelMaxUncertaintyC);
    um.emissivity_slope_u =
        number_within(u.at("emissivity_slope_u"), uw + "emissivity_slope_u", 0, 1);
    if (!u.at("monte_carlo_refits").is_number_integer())
      throw InputError(uw + "monte_carlo_refits must be a whole number");
    um.monte_carlo_refits = static_cast<int>(
        number_within(u.at("monte_carlo_refits"), uw + "monte_carlo_refits", 0, 1e6));
    um.coverage_factor = number_within(u.at("coverage_factor"), uw + "coverage_factor",
                                       kModelMinCoverageFactor, kModelMaxCoverageFactor);
    m.provenance = payload.value("provenance", json::object());
    m.summary = payload.value("summary", json::object());
    return m;
  } catch (const json::exception& e) {
    throw InputError(where + ": malformed model (" + std::string(e.what()) + ")");
  }
}

}  // namespace pyrocam
