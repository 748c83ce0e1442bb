#include "pyrocam/core/profile.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "detail/json_input.h"

namespace pyrocam {
namespace {

using nlohmann::json;

class ProfileReader {
 public:
  explicit ProfileReader(std::filesystem::path path) : path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path_.string() + ": " + what);
  }

  const json& require(const json& j, const char* key, const std::string& where) const {
    if (!j.is_object() || !j.contains(key)) fail(where + " needs '" + key + "'");
    return j.at(key);
  }

  double number(const json& j, const char* key, const std::string& where, double fallback,
                bool required = false) const {
    if (!j.contains(key)) {
      if (required) fail(where + " needs '" + key + "'");
      return fallback;
    }
    if (!j.at(key).is_number()) fail(where + "." + key + " must be a number");
    const double v = j.at(key).get<double>();
    if (!std::isfinite(v)) fail(where + "." + key + " is not finite");
    return v;
  }

  // A whole number within lo..hi; checked as a double first, since converting an out-of-range
  // double to int is undefined.
  int integer(const json& j, const char* key, const std::string& where, int fallback, int lo,
              int hi, bool required = false) const {
    const double v = number(j, key, where, fallback, required);
    if (!(v >= lo && v <= hi) || v != std::floor(v))
      fail(where + "." + key + " is " + json(v).dump() + "; expected a whole number within " +
           std::to_string(lo) + ".." + std::to_string(hi));
    return static_cast<int>(v);
  }

  std::filesystem::path resolve(const std::string& rel) const {
    std::filesystem::path p(rel);
    if (p.is_relative()) p = path_.parent_path() / p;
    if (!std::filesystem::exists(p))
      fail("file '" + rel + "' not found (looked for " + p.string() + ")");
    require_regular_file(p, "file named by " + path_.string());
    return p;
  }

  std::vector<Spectrum> imec_bands(const std::string& rel) {
    const auto p = resolve(rel);
    auto it = imec_cache_.find(p.string());
    if (it == imec_cache_.end())
      it = imec_cache_.emplace(p.string(), read_imec_band_responses(p)).first;
    return it->second;
  }

  Eigen::VectorXd curve(const json& spec, const WavelengthGrid& grid, const std::string& where,
                        double max_value) {
    if (spec.is_string())
      return read_spectrum_csv(resolve(spec.get<std::string>()), "", max_value).resample(grid);
    if (!spec.is_object()) fail(where + " must be a file name or an object");
    if (spec.contains("values")) {  // inline, one value per grid wavelength
      const auto& v = spec.at("values");
      if (!v.is_array() || static_cast<Eigen::Index>(v.size()) != grid.size())
        fail(where + ".values must hold " + std::to_string(grid.size()) +
             " numbers, one per grid wavelength");
      Eigen::VectorXd out(grid.size());
      for (Eigen::Index i = 0; i < grid.size(); ++i) {
        out[i] = v[static_cast<std::size_t>(i)].get<double>();
        if (!std::isfinite(out[i]) || out[i] < 0 || out[i] > max_value)
          fail(where + ".values[" + std::to_string(i) + "] is outside 0.." +
               std::to_string(max_value));
      }
      return out;
    }
    if (spec.contains("imec_xml")) {
      const auto bands = imec_bands(spec.at("imec_xml").get<std::string>());
      const int b = integer(spec, "band", where, 0, 0, kMaxProfileBands - 1, true);
      if (b < 0 || b >= static_cast<int>(bands.size()))
        fail(where + ": band " + std::to_string(b) + " not in the IMEC file (" +
             std::to_string(bands.size()) + " bands)");
      return bands[b].resample(grid);
    }
    const std::string file = require(spec, "file", where).get<std::string>();
    const std::string column = spec.value("column", std::string());
    return read_spectrum_csv(resolve(file), column, max_value).resample(grid);
  }

  CameraProfile read_json(const json& j) {
    try {
      return read(j);
    } catch (const json::exception& e) {
      fail(std::string("wrong value type: ") + e.what());
    }
  }

  CameraProfile read() {
    std::ifstream in(path_);
    if (!in) fail("cannot open camera profile");
    json j;
    try {
      j = parse_bounded_json(in, path_.string(), /*ignore_comments=*/true);
    } catch (const json::exception& e) {
      fail(std::string("not valid JSON: ") + e.what());
    }
    try {
      return read(j);
    } catch (const json::exception& e) {
      fail(std::string("wrong value type: ") + e.what());
    }
  }

  CameraProfile read(const json& j) {
    if (j.value("format", std::string()) != "pyrocam-camera-profile")
      fail("not a camera profile (\"format\" must be \"pyrocam-camera-profile\")");
    if (!j.is_object()) fail("not a camera profile (not a JSON object)");
    const int version = integer(j, "version", "profile", 0, 0, 1000000, true);
    if (version != kProfileFormatVersion)
      fail("profile format version " + std::to_string(version) + ", this build reads version " +
           std::to_string(kProfileFormatVersion));

    CameraProfile p;
    p.source = path_;
    p.name = require(j, "name", "profile").get<std::string>();
    p.description = j.value("description", std::string());
    read_grid(j, p);
    try {
      p.mosaic = read_mosaic(require(j, "mosaic", "profile"));
    } catch (const InputError& e) {
      if (std::string(e.what()).rfind(path_.string(), 0) == 0) throw;
      fail(e.what());
    }
    read_bands(require(j, "bands", "profile"), p);
    if (p.band_count() != p.mosaic.band_count())
      fail("mosaic uses " + std::to_string(p.mosaic.band_count()) + " bands, " +
           std::to_string(p.band_count()) + " are described");
    read_optics(j, p);
    read_sensor(j, p);
    read_noise(j, p);
    read_thresholds(j, p);
    read_normalisation(j, p);
    read_unit_variation(j, p);
    return p;
  }

 private:
  // The wavelength grid every curve is resampled onto.
  void read_grid(const json& j, CameraProfile& p) const {
    const json& g = require(j, "wavelength_grid_nm", "profile");
    try {
      const double start = number(g, "start", "wavelength_grid_nm", 0, true);
      const double stop = number(g, "stop", "wavelength_grid_nm", 0, true);
      const double step = number(g, "step", "wavelength_grid_nm", 0, true);
      // Bounded before the grid is allocated from the three numbers.
      if (step > 0 && stop > start &&
          !((stop - start) / step < static_cast<double>(kMaxProfileWavelengthSamples) - 0.5))
        fail("wavelength_grid_nm " + json(start).dump() + ".." + json(stop).dump() + " step " +
             json(step).dump() + " nm has more than " +
             std::to_string(kMaxProfileWavelengthSamples) + " samples");
      p.grid = WavelengthGrid(start, stop, step);
    } catch (const std::invalid_argument& e) {
      fail(e.what());
    }
  }

  // Lens and filter transmissions, and the filter pass band.
  void read_optics(const json& j, CameraProfile& p) {
    p.optics_transmission = Eigen::VectorXd::Ones(p.grid.size());
    if (j.contains("optics")) {
      for (const auto& o : j.at("optics"))
        p.optics_transmission.array() *= curve(o, p.grid, "optics", 1.0).array();
    }
    if (j.contains("filter_pass_band_nm")) {
      const auto& fb = j.at("filter_pass_band_nm");
      if (!fb.is_array() || fb.size() != 2 || !(fb[0].get<double>() < fb[1].get<double>()))
        fail("filter_pass_band_nm must be [start, stop] with start < stop");
      p.filter_pass_band_nm = {fb[0].get<double>(), fb[1].get<double>()};
    } else {
      p.filter_pass_band_nm = {p.grid.start_nm(), p.grid.stop_nm()};
    }
  }

  // Bit depth, dark offset and etendue.
  void read_sensor(const json& j, CameraProfile& p) const {
    p.bit_depth = integer(j, "bit_depth", "profile", 8, 8, 16);
    p.dark_offset_dn = number(j, "dark_offset_dn", "profile", 0);
    if (p.dark_offset_dn < 0 || p.dark_offset_dn >= p.max_dn())
      fail("dark_offset_dn must lie within 0.." + std::to_string(p.max_dn()));
    p.etendue_m2_sr = number(j, "etendue_m2_sr", "profile", p.etendue_m2_sr);
    if (!(p.etendue_m2_sr > 0)) fail("etendue_m2_sr must be > 0");
  }

  // EMVA 1288 noise terms (defaults where absent).
  void read_noise(const json& j, CameraProfile& p) const {
    if (j.contains("noise")) {
      const json& n = j.at("noise");
      NoiseModel& nm = p.noise;
      nm.system_gain_dn_per_e = number(n, "system_gain_dn_per_e", "noise", nm.system_gain_dn_per_e);
      nm.read_noise_e = number(n, "read_noise_e", "noise", nm.read_noise_e);
      nm.full_well_e = number(n, "full_well_e", "noise", nm.full_well_e);
      nm.dark_current_e_per_s = number(n, "dark_current_e_per_s", "noise", nm.dark_current_e_per_s);
      nm.dark_fpn_dn = number(n, "dark_fpn_dn", "noise", nm.dark_fpn_dn);
      nm.prnu = number(n, "prnu", "noise", nm.prnu);
      if (!(nm.system_gain_dn_per_e > 0) || !(nm.full_well_e > 0) || nm.read_noise_e < 0 ||
          nm.dark_current_e_per_s < 0 || nm.dark_fpn_dn < 0 || nm.prnu < 0)
        fail("noise: gain and full well must be > 0, the other terms >= 0");
    }
  }

  // Dim and saturation thresholds, checked against the bit depth.
  void read_thresholds(const json& j, CameraProfile& p) const {
    if (j.contains("thresholds")) {
      const json& t = j.at("thresholds");
      Thresholds& th = p.thresholds;
      th.calibration_dim_dn = number(t, "calibration_dim_dn", "thresholds", th.calibration_dim_dn);
      th.calibration_saturation_dn =
          number(t, "calibration_saturation_dn", "thresholds", th.calibration_saturation_dn);
      th.inference_dim_dn = number(t, "inference_dim_dn", "thresholds", th.inference_dim_dn);
      th.inference_saturation_dn =
          number(t, "inference_saturation_dn", "thresholds", th.inference_saturation_dn);
    }
    {
      // Dim thresholds apply to dark-subtracted values and must keep a zero signal out (a ratio
      // of zeros is no temperature); saturation thresholds apply to raw values.
      const Thresholds& th = p.thresholds;
      if (!(th.calibration_dim_dn > 0 && th.calibration_dim_dn < th.calibration_saturation_dn &&
            th.calibration_saturation_dn <= p.max_dn()) ||
          !(th.inference_dim_dn > 0 && th.inference_dim_dn < th.inference_saturation_dn &&
            th.inference_saturation_dn <= p.max_dn()))
        fail("thresholds: need 0 < dim < saturation <= " + std::to_string(p.max_dn()) +
             " DN (bit_depth " + std::to_string(p.bit_depth) + ") for calibration (" +
             std::to_string(th.calibration_dim_dn) + ", " +
             std::to_string(th.calibration_saturation_dn) + ") and inference (" +
             std::to_string(th.inference_dim_dn) + ", " +
             std::to_string(th.inference_saturation_dn) + ")");
    }
  }

  // Which bands are numerators and which the reference of the ratios.
  void read_normalisation(const json& j, CameraProfile& p) const {
    const json& norm = require(j, "normalisation", "profile");
    p.normalisation.numerators = band_list(require(norm, "numerators", "normalisation"), p);
    p.normalisation.reference = band_list(require(norm, "reference", "normalisation"), p);
    if (p.normalisation.numerators.empty() || p.normalisation.reference.empty())
      fail("normalisation needs at least one numerator and one reference band");
  }

  // How a simulated unit may differ from the datasheet.
  void read_unit_variation(const json& j, CameraProfile& p) const {
    if (j.contains("unit_variation")) {
      const json& u = j.at("unit_variation");
      UnitVariation& uv = p.unit_variation;
      if (u.contains("leak_range_nm")) {
        uv.leak_range_nm = {u.at("leak_range_nm").at(0).get<double>(),
                            u.at("leak_range_nm").at(1).get<double>()};
        if (!(uv.leak_range_nm[0] < uv.leak_range_nm[1]))
          fail("unit_variation.leak_range_nm must be [start, stop] with start < stop");
      }
      uv.leak_system_qe = number(u, "leak_system_qe", "unit_variation", uv.leak_system_qe);
      uv.scale_sigma = number(u, "scale_sigma", "unit_variation", uv.scale_sigma);
      uv.tilt_sigma = number(u, "tilt_sigma", "unit_variation", uv.tilt_sigma);
      uv.shift_sigma_nm = number(u, "shift_sigma_nm", "unit_variation", uv.shift_sigma_nm);
      uv.filter_shift_sigma_nm =
          number(u, "filter_shift_sigma_nm", "unit_variation", uv.filter_shift_sigma_nm);
      uv.ripple_rms = number(u, "ripple_rms", "unit_variation", uv.ripple_rms);
      if (u.contains("ripple_period_nm")) {
        uv.ripple_period_nm = {u.at("ripple_period_nm").at(0).get<double>(),
                               u.at("ripple_period_nm").at(1).get<double>()};
        if (!(uv.ripple_period_nm[0] > 0 && uv.ripple_period_nm[0] <= uv.ripple_period_nm[1]))
          fail(
              "unit_variation.ripple_period_nm must be [shortest, longest] with 0 < shortest <= "
              "longest");
      }
      for (double sigma : {uv.leak_system_qe, uv.scale_sigma, uv.tilt_sigma, uv.shift_sigma_nm,
                           uv.filter_shift_sigma_nm, uv.ripple_rms})
        if (!(sigma >= 0)) fail("unit_variation: every size must be >= 0");
    }
  }

  MosaicLayout read_mosaic(const json& m) const {
    const std::string type = require(m, "type", "mosaic").get<std::string>();
    if (type == "bayer") {
      return MosaicLayout::bayer(require(m, "pattern", "mosaic").get<std::string>());
    } else if (type == "snapshot") {
      const json& rows = require(m, "band_map", "mosaic");
      if (!rows.is_array() || rows.empty()) fail("mosaic.band_map must be a list of rows");
      const std::size_t width = rows[0].size();
      if (rows.size() > kMaxMosaicPeriod || width > kMaxMosaicPeriod)
        fail("mosaic.band_map is " + std::to_string(width) + "x" + std::to_string(rows.size()) +
             "; a mosaic period is at most " + std::to_string(kMaxMosaicPeriod) + " on a side");
      std::vector<int> map;
      for (const auto& row : rows) {
        if (!row.is_array() || row.size() != width) fail("mosaic.band_map rows differ in length");
        for (const auto& v : row) {
          if (!v.is_number_integer() || v.get<long long>() < 0 ||
              v.get<long long>() >= kMaxProfileBands)
            fail("mosaic.band_map holds " + v.dump() + "; band indices are whole numbers 0.." +
                 std::to_string(kMaxProfileBands - 1));
          map.push_back(v.get<int>());
        }
      }
      return MosaicLayout::snapshot(static_cast<int>(width), static_cast<int>(rows.size()),
                                    std::move(map));
    }
    fail("unknown mosaic type '" + type + "' (use \"bayer\" or \"snapshot\")");
  }

  void read_bands(const json& bands, CameraProfile& p) {
    std::vector<Eigen::VectorXd> qe;
    std::vector<double> gains;
    if (bands.is_object()) {
      // Shorthand for snapshot sensors: every band of an IMEC calibration file, in its order.
      const std::string file = require(bands, "imec_xml", "bands").get<std::string>();
      const double gain = number(bands, "gain", "bands", 1.0);
      const std::string prefix = bands.value("name_prefix", std::string("b"));
      const auto responses = imec_bands(file);
      if (responses.size() > static_cast<std::size_t>(kMaxProfileBands))
        fail("the IMEC file " + file + " describes " + std::to_string(responses.size()) +
             " bands; at most " + std::to_string(kMaxProfileBands) + " are supported");
      for (std::size_t b = 0; b < responses.size(); ++b) {
        p.band_names.push_back(prefix + std::to_string(b + 1));
        qe.push_back(responses[b].resample(p.grid));
        gains.push_back(gain);
      }
    } else if (bands.is_array() && !bands.empty()) {
      if (bands.size() > static_cast<std::size_t>(kMaxProfileBands))
        fail("bands lists " + std::to_string(bands.size()) + " bands; at most " +
             std::to_string(kMaxProfileBands) + " are supported");
      for (std::size_t b = 0; b < bands.size(); ++b) {
        const std::string where = "bands[" + std::to_string(b) + "]";
        p.band_names.push_back(require(bands[b], "name", where).get<std::string>());
        qe.push_back(curve(require(bands[b], "qe", where), p.grid, where + ".qe", 1.0));
        gains.push_back(number(bands[b], "gain", where, 1.0));
      }
    } else {
      fail("bands must be a non-empty list or an {\"imec_xml\": ...} object");
    }
    p.sensor_qe.resize(static_cast<Eigen::Index>(qe.size()), p.grid.size());
    p.band_gain.resize(static_cast<Eigen::Index>(gains.size()));
    for (std::size_t b = 0; b < qe.size(); ++b) {
      p.sensor_qe.row(static_cast<Eigen::Index>(b)) = qe[b].transpose();
      if (!(gains[b] > 0)) fail("band " + p.band_names[b] + " gain must be > 0");
      p.band_gain[static_cast<Eigen::Index>(b)] = gains[b];
    }
  }

  std::vector<int> band_list(const json& names, const CameraProfile& p) const {
    std::vector<int> out;
    if (!names.is_array()) fail("normalisation lists must be arrays of band names");
    for (const auto& n : names) {
      const int i = p.band_index(n.get<std::string>());
      if (i < 0) fail("normalisation names unknown band '" + n.get<std::string>() + "'");
      out.push_back(i);
    }
    return out;
  }

  std::filesystem::path path_;
  std::map<std::string, std::vector<Spectrum>> imec_cache_;
};

}  // namespace

int CameraProfile::band_index(const std::string& n) const {
  for (std::size_t i = 0; i < band_names.size(); ++i)
    if (band_names[i] == n) return static_cast<int>(i);
  return -1;
}

Eigen::MatrixXd CameraProfile::system_qe() const {
  return sensor_qe.array().rowwise() * optics_transmission.transpose().array();
}

CameraProfile profile_from_json(const nlohmann::json& j, const std::filesystem::path& origin) {
  return ProfileReader(origin).read_json(j);
}

nlohmann::json profile_to_json(const CameraProfile& p) {
  json j;
  j["format"] = "pyrocam-camera-profile";
  j["version"] = kProfileFormatVersion;
  j["name"] = p.name;
  j["description"] = p.description;
  if (p.mosaic.kind == MosaicLayout::Kind::kBayer) {
    j["mosaic"] = {{"type", "bayer"}, {"pattern", p.mosaic.pattern}};
  } else {
    json rows = json::array();
    for (int y = 0; y < p.mosaic.period_height; ++y) {
      json row = json::array();
      for (int x = 0; x < p.mosaic.period_width; ++x) row.push_back(p.mosaic.band_at(x, y));
      rows.push_back(row);
    }
    j["mosaic"] = {{"type", "snapshot"}, {"band_map", rows}};
  }
  j["wavelength_grid_nm"] = {
      {"start", p.grid.start_nm()}, {"stop", p.grid.stop_nm()}, {"step", p.grid.step_nm()}};
  auto values = [](const Eigen::VectorXd& v) {
    return json{{"values", std::vector<double>(v.data(), v.data() + v.size())}};
  };
  json bands = json::array();
  for (int b = 0; b < p.band_count(); ++b)
    bands.push_back({{"name", p.band_names[b]},
                     {"qe", values(p.sensor_qe.row(b).transpose())},
                     {"gain", p.band_gain[b]}});
  j["bands"] = bands;
  j["optics"] = json::array({values(p.optics_transmission)});
  j["filter_pass_band_nm"] = {p.filter_pass_band_nm[0], p.filter_pass_band_nm[1]};
  j["bit_depth"] = p.bit_depth;
  j["dark_offset_dn"] = p.dark_offset_dn;
  j["etendue_m2_sr"] = p.etendue_m2_sr;
  const NoiseModel& n = p.noise;
  j["noise"] = {{"system_gain_dn_per_e", n.system_gain_dn_per_e},
                {"read_noise_e", n.read_noise_e},
                {"full_well_e", n.full_well_e},
                {"dark_current_e_per_s", n.dark_current_e_per_s},
                {"dark_fpn_dn", n.dark_fpn_dn},
                {"prnu", n.prnu}};
  const Thresholds& t = p.thresholds;
  j["thresholds"] = {{"calibration_dim_dn", t.calibration_dim_dn},
                     {"calibration_saturation_dn", t.calibration_saturation_dn},
                     {"inference_dim_dn", t.inference_dim_dn},
                     {"inference_saturation_dn", t.inference_saturation_dn}};
  auto names = [&](const std::vector<int>& idx) {
    json a = json::array();
    for (int i : idx) a.push_back(p.band_names[i]);
    return a;
  };
  j["normalisation"] = {{"numerators", names(p.normalisation.numerators)},
                        {"reference", names(p.normalisation.reference)}};
  const UnitVariation& u = p.unit_variation;
  j["unit_variation"] = {{"leak_range_nm", {u.leak_range_nm[0], u.leak_range_nm[1]}},
                         {"leak_system_qe", u.leak_system_qe},
                         {"scale_sigma", u.scale_sigma},
                         {"tilt_sigma", u.tilt_sigma},
                         {"shift_sigma_nm", u.shift_sigma_nm},
                         {"filter_shift_sigma_nm", u.filter_shift_sigma_nm},
                         {"ripple_rms", u.ripple_rms},
                         {"ripple_period_nm", {u.ripple_period_nm[0], u.ripple_period_nm[1]}}};
  return j;
}

CameraProfile load_profile(const std::filesystem::path& path) {
  require_regular_file(path, "camera profile");
  return ProfileReader(path).read();
}

std::filesystem::path builtin_profile_dir() {
  if (const char* env = std::getenv("PYROCAM_PROFILE_DIR"); env && *env) return env;
  const std::filesystem::path installed = PYROCAM_PROFILES_INSTALL_DIR;
  if (std::filesystem::exists(installed / "rgb-reference.json")) return installed;
  return PYROCAM_PROFILES_SRC_DIR;
}

CameraProfile load_profile_by_name(const std::string& name_or_path) {
  std::filesystem::path p(name_or_path);
  if (p.extension() != ".json") {
    // A path to something else was looked up as a shipped profile's name: "/etc/passwd.json:
    // camera profile not found".
    if (name_or_path.find('/') != std::string::npos)
      throw InputError(name_or_path +
                       ": not a camera profile (a profile is a .json file, or a shipped one's "
                       "name: rgb-reference, nir5x5-reference)");
    p = builtin_profile_dir() / (name_or_path + ".json");
  }
  return load_profile(p);
}

Eigen::VectorXd electron_rates(const CameraProfile& profile, const Eigen::MatrixXd& system_qe,
                               double temperature_k, double emissivity) {
  return profile.etendue_m2_sr *
         band_photon_integrals(system_qe, profile.grid, temperature_k, emissivity);
}

Eigen::VectorXd signal_rates(const CameraProfile& profile, const Eigen::MatrixXd& system_qe,
                             double temperature_k, double emissivity) {
  return electron_rates(profile, system_qe, temperature_k, emissivity)
      .cwiseProduct(profile.dn_per_electron());
}

Eigen::VectorXd normalised_ratios(const Normalisation& norm, const Eigen::VectorXd& signals) {
  double ref = 0;
  for (int b : norm.reference) ref += signals[b];
  ref /= static_cast<double>(norm.reference.size());
  Eigen::VectorXd x(static_cast<Eigen::Index>(norm.numerators.size()));
  for (std::size_t i = 0; i < norm.numerators.size(); ++i)
    x[static_cast<Eigen::Index>(i)] = signals[norm.numerators[i]] / ref;
  return x;
}

}  // namespace pyrocam
