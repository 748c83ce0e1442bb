// Model files, baselines and estimators (fast checks; a furnace campaign's rates are in
// test_furnace_rates.cpp, the accuracy targets of the whole calibration in the targets suite).
#include <gtest/gtest.h>

#include <fstream>

#include "pyrocam/calibration/baselines.h"
#include "pyrocam/calibration/calibrate.h"
#include "pyrocam/calibration/rate_extraction.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;

// A model whose network is a tiny hand-made one: enough to test files and estimators that do
// not depend on the network's accuracy.
ThermalModel small_model(const CameraProfile& p) {
  ThermalModel m;
  m.camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  m.datasheet_qe = p.system_qe();
  m.qe_solver = "datasheet";
  const int inputs = static_cast<int>(p.normalisation.numerators.size());
  Standardizer st{Eigen::VectorXd::Zero(inputs), Eigen::VectorXd::Ones(inputs)};
  MlpLayer l1{Eigen::MatrixXd::Constant(4, inputs, 0.1), Eigen::VectorXd::Constant(4, 0.2)};
  MlpLayer l2{Eigen::MatrixXd::Constant(1, 4, 0.3), Eigen::VectorXd::Constant(1, 0.0)};
  m.mlp = Mlp(MlpInputTransform::kNone, st, MlpOutputTransform::kNone, 1500, 500, {l1, l2});
  m.uncertainty.temperature_c = {500, 3500};
  m.uncertainty.u_calibration_c = {2, 4};
  m.uncertainty.u_emissivity_c = {1, 3};
  m.provenance = {{"tool", "test"}};
  return m;
}

TEST(ModelFile, round_trips) {
  ScratchDir dir("model");
  const ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  save_model(m, dir / "m.json");
  EXPECT_FALSE(std::filesystem::exists(dir / "m.json.partial"));
  const ThermalModel back = load_model(dir / "m.json");
  EXPECT_EQ(back.profile().name, "rgb-reference");
  EXPECT_TRUE(back.camera.system_qe.isApprox(m.camera.system_qe, 1e-15));
  EXPECT_TRUE(back.profile().system_qe().isApprox(m.profile().system_qe(), 1e-15));
  const double x[2] = {0.7, 0.3};
  EXPECT_EQ(back.mlp.predict(x), m.mlp.predict(x));
  EXPECT_NEAR(back.uncertainty.systematic_u_c(2000), std::sqrt(3.0 * 3 + 2 * 2), 1e-12);
}

TEST(ModelFile, keeps_the_qe_model_term_and_adds_it) {
  ScratchDir dir("model-qe-term");
  ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  const double without = m.uncertainty.systematic_u_c(2000);
  m.uncertainty.u_qe_model_c.assign(m.uncertainty.temperature_c.size(), 4.0);
  save_model(m, dir / "m.json");
  const ThermalModel back = load_model(dir / "m.json");
  EXPECT_EQ(back.uncertainty.u_qe_model_c, m.uncertainty.u_qe_model_c);
  EXPECT_NEAR(back.uncertainty.systematic_u_c(2000), std::sqrt(without * without + 16), 1e-12);
}

TEST(ModelFile, keeps_the_hottest_calibrated_temperature_and_none_when_not_known) {
  ScratchDir dir("model-calibrated-top");
  ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  save_model(m, dir / "unknown.json");
  EXPECT_TRUE(std::isnan(load_model(dir / "unknown.json").calibrated_up_to_c));
  m.calibrated_up_to_c = 1100;
  save_model(m, dir / "m.json");
  EXPECT_EQ(load_model(dir / "m.json").calibrated_up_to_c, 1100);
}

// JSON has no NaN: a term that is not a number is refused when saving (it would be written as
// null and the model refused when loaded), and no file is left.
TEST(ModelFile, refuses_to_save_an_uncertainty_that_is_not_a_number_n) {
  ScratchDir dir("model-nan");
  ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  m.uncertainty.u_qe_model_c = {NAN, 4.0};
  try {
    save_model(m, dir / "m.json");
    ADD_FAILURE() << "saved";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("uncertainty.u_qe_model_c[0] is not a number"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "m.json"));
  EXPECT_FALSE(std::filesystem::exists(dir / "m.json.partial"));
}

class ModelFileDamage : public ::testing::Test {
 protected:
  void SetUp() override {
    save_model(small_model(load_profile_by_name("rgb-reference")), dir / "m.json");
    std::ifstream in(dir / "m.json");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  void expect_rejected(const std::string& damaged, const std::string& needle) {
    test::write_text(dir / "bad.json", damaged);
    try {
      load_model(dir / "bad.json");
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos) << e.what();
    }
  }
  ScratchDir dir{"damage"};
  std::string text;
};

TEST_F(ModelFileDamage, rejects_a_truncated_file_n) {
  expect_rejected(text.substr(0, text.size() / 2), "truncated or corrupt");
}

TEST_F(ModelFileDamage, rejects_an_edited_file_n) {
  std::string edited = text;
  const auto pos = edited.find("\"qe_solver\": \"datasheet\"");
  ASSERT_NE(pos, std::string::npos);
  edited.replace(pos, 24, "\"qe_solver\": \"datasheef\"");
  expect_rejected(edited, "checksum mismatch");
}

TEST_F(ModelFileDamage, rejects_a_second_payload_after_the_signed_one_n) {
  // The checksum is taken from the file's text when it can be; the parser keeps the last payload.
  nlohmann::json payload = nlohmann::json::parse(text)["payload"];
  payload["qe_solver"] = "datasheef";
  std::string doubled = text;
  doubled.insert(doubled.rfind('}'), ", \"payload\": " + payload.dump());
  expect_rejected(doubled, "checksum mismatch");
}

TEST_F(ModelFileDamage, reads_the_same_model_written_in_another_layout) {
  // Other white space (checked from the text), another spelling of a string (checked by the
  // dump of what was parsed): the same payload, the same fingerprint.
  const ThermalModel original = load_model(dir / "m.json");
  std::string spelled = text;
  const auto pos = spelled.find("\"qe_solver\": \"datasheet\"");
  ASSERT_NE(pos, std::string::npos);
  spelled.replace(pos, 24, "\"qe_solver\": \"\\u0064atasheet\"");
  for (const std::string& layout : {nlohmann::json::parse(text).dump(4), spelled}) {
    test::write_text(dir / "other.json", layout);
    const ThermalModel m = load_model(dir / "other.json");
    EXPECT_EQ(m.fingerprint, original.fingerprint);
    EXPECT_EQ(m.qe_solver, "datasheet");
  }
}

TEST_F(ModelFileDamage, rejects_another_version_n) {
  std::string edited = text;
  const auto pos = edited.rfind("\"version\": 1");  // the file's, written last
  ASSERT_NE(pos, std::string::npos);
  edited.replace(pos, 12, "\"version\": 9");
  expect_rejected(edited, "model format version 9");
}

TEST_F(ModelFileDamage, rejects_an_mlp_with_an_unknown_transform_n) {
  // Consistent file (checksum recomputed) written by some other build.
  nlohmann::json file = nlohmann::json::parse(text);
  file["payload"]["mlp"]["output_transform"] = "kelvin_squared";
  file["checksum_fnv1a64"] = fnv1a_hex(file["payload"].dump());
  expect_rejected(file.dump(),
                  "MLP: mlp json: unsupported \"output_transform\" \"kelvin_squared\"");
}

TEST_F(ModelFileDamage, reads_an_mlp_of_format_version_1) {
  // Written before the transforms: no transform keys, meaning none.
  nlohmann::json file = nlohmann::json::parse(text);
  nlohmann::json& mlp = file["payload"]["mlp"];
  ASSERT_EQ(mlp["input_transform"], "none");
  ASSERT_EQ(mlp["output_transform"], "none");
  mlp.erase("input_transform");
  mlp.erase("output_transform");
  mlp["version"] = 1;
  file["checksum_fnv1a64"] = fnv1a_hex(file["payload"].dump());
  test::write_text(dir / "v1.json", file.dump());
  const ThermalModel old = load_model(dir / "v1.json");
  const ThermalModel now = load_model(dir / "m.json");
  const double x[2] = {0.7, 0.2};
  EXPECT_EQ(old.mlp.predict(x), now.mlp.predict(x));
}

// The checksum is FNV-1a 64 as published (offset basis 14695981039346656037), so that another
// tool can check or sign a model; models signed with the basis used before (a digit short) load.
TEST_F(ModelFileDamage, checksum_is_standard_fnv1a_and_the_earlier_basis_still_loads) {
  const auto fnv1a = [](const std::string& t, std::uint64_t h) {
    for (unsigned char c : t) h = (h ^ c) * 1099511628211ull;
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return std::string(buf);
  };
  EXPECT_EQ(fnv1a_hex(""), "cbf29ce484222325");   // the offset basis itself
  EXPECT_EQ(fnv1a_hex("a"), "af63dc4c8601ec8c");  // a published test vector
  nlohmann::json file = nlohmann::json::parse(text);
  const std::string payload = file["payload"].dump();
  EXPECT_EQ(file["checksum_fnv1a64"], fnv1a(payload, 14695981039346656037ull));
  file["checksum_fnv1a64"] = fnv1a(payload, 1469598103934665603ull);
  test::write_text(dir / "earlier.json", file.dump(1));
  EXPECT_NO_THROW(load_model(dir / "earlier.json"));
  file["checksum_fnv1a64"] = fnv1a(payload, 1469598103934665604ull);
  expect_rejected(file.dump(1), "checksum mismatch");
}

TEST_F(ModelFileDamage, rejects_a_missing_file_n) {
  EXPECT_THROW(load_model(dir / "none.json"), InputError);
}

// A consistent file (checksum recomputed) whose payload was changed by `edit`: what another
// program, or a corrupted copy re-signed by hand, could hand the loader.
class ModelFileContent : public ModelFileDamage {
 protected:
  template <class Edit>
  void expect_edit_rejected(Edit edit, const std::string& needle) {
    nlohmann::json file = nlohmann::json::parse(text);
    edit(file["payload"]);
    file["checksum_fnv1a64"] = fnv1a_hex(file["payload"].dump());
    expect_rejected(file.dump(), needle);
  }
};

TEST_F(ModelFileContent, rejects_json_nested_a_million_levels_deep_n) {
  // Serialising it for the checksum recursed once per level and overflowed the stack.
  const int depth = 1000000;
  expect_rejected("{\"format\": \"pyrocam-thermal-model\", \"version\": 1, \"payload\": {\"x\": " +
                      std::string(depth, '[') + std::string(depth, ']') + "}}",
                  "JSON nested deeper than 64 levels");
}

TEST_F(ModelFileDamage, rejects_a_file_larger_than_any_model_n) {
  // Parsing holds about the file's size again in memory: a huge file is refused unread (a valid
  // model padded with white space, which the parser would otherwise accept).
  std::string padded = text;
  padded.insert(padded.size() - 1, std::string(kModelMaxFileBytes, ' '));
  expect_rejected(padded, "MB, more than any model (at most 64 MB)");
}

TEST_F(ModelFileContent, rejects_a_wavelength_grid_of_10_pow_12_samples_n) {
  // The grid was allocated (8 TB) from three numbers before its curves were checked.
  expect_edit_rejected(
      [](nlohmann::json& p) {
        auto& g = p["profile"]["wavelength_grid_nm"];
        g["step"] = (g["stop"].get<double>() - g["start"].get<double>()) / 1e12;
      },
      "wavelength_grid_nm 350.0..1100.0 step 7.5e-10 nm has more than 100001 samples");
}

TEST_F(ModelFileContent, rejects_mlp_weights_of_1e308_n) {
  expect_edit_rejected([](nlohmann::json& p) { p["mlp"]["layers"][0]["weights"][1][0] = 1e308; },
                       "layers[0] has a weight or bias of 1e+308");
}

TEST_F(ModelFileContent, rejects_an_mlp_bias_of_1e300_n) {
  expect_edit_rejected([](nlohmann::json& p) { p["mlp"]["layers"][1]["bias"][0] = -1e300; },
                       "layers[1] has a weight or bias of 1e+300");
}

TEST_F(ModelFileContent, rejects_an_mlp_layer_wider_than_supported_before_allocating_n) {
  // 2000 columns in row 0 and 2000 rows: refused from the sizes, not after reading rows.
  expect_edit_rejected(
      [](nlohmann::json& p) {
        nlohmann::json rows = nlohmann::json::array();
        rows.push_back(std::vector<double>(2000, 0.0));
        for (int r = 1; r < 2000; ++r) rows.push_back(nlohmann::json::array());
        p["mlp"]["layers"][0]["weights"] = rows;
      },
      "layers[0].weights is 2000 x 2000; a layer is at most 1024 wide");
}

TEST_F(ModelFileContent, rejects_a_temperature_range_of_huge_width_n) {
  expect_edit_rejected(
      [](nlohmann::json& p) {
        p["temperature_range_c"] = {500, 1e300};
      },
      "temperature_range_c[1] is 1e+300, outside 0..5000");
}

TEST_F(ModelFileContent, rejects_a_temperature_range_below_zero_celsius_n) {
  expect_edit_rejected(
      [](nlohmann::json& p) {
        p["temperature_range_c"] = {-400, 1000};
      },
      "temperature_range_c[0] is -400, outside 0..5000");
}

TEST_F(ModelFileContent, rejects_a_calibrated_top_outside_the_range_n) {
  const std::string needle = "calibrated_up_to_c must be a temperature within temperature_range_c";
  expect_edit_rejected([](nlohmann::json& p) { p["calibrated_up_to_c"] = 4000; }, needle);
  expect_edit_rejected([](nlohmann::json& p) { p["calibrated_up_to_c"] = "1100"; }, needle);
  expect_edit_rejected([](nlohmann::json& p) { p["calibrated_up_to_c"] = nullptr; }, needle);
}

TEST_F(ModelFileContent, rejects_a_negative_coverage_factor_n) {
  // -5 gave an all-zero uncertainty image.
  expect_edit_rejected([](nlohmann::json& p) { p["uncertainty"]["coverage_factor"] = -5; },
                       "uncertainty.coverage_factor is -5");
}

TEST_F(ModelFileContent, rejects_an_empty_uncertainty_table_n) {
  expect_edit_rejected(
      [](nlohmann::json& p) {
        for (const char* key : {"temperature_c", "u_calibration_c", "u_emissivity_c"})
          p["uncertainty"][key] = nlohmann::json::array();
      },
      "uncertainty.temperature_c is empty");
}

TEST_F(ModelFileContent, rejects_a_negative_uncertainty_n) {
  expect_edit_rejected([](nlohmann::json& p) { p["uncertainty"]["u_calibration_c"][1] = -4; },
                       "uncertainty.u_calibration_c[1] is -4");
}

TEST_F(ModelFileContent, rejects_an_uncertainty_table_out_of_order_n) {
  expect_edit_rejected(
      [](nlohmann::json& p) {
        p["uncertainty"]["temperature_c"] = {3500, 500};
      },
      "uncertainty.temperature_c must increase");
}

TEST_F(ModelFileContent, rejects_a_dim_threshold_far_below_zero_n) {
  expect_edit_rejected(
      [](nlohmann::json& p) { p["profile"]["thresholds"]["inference_dim_dn"] = -1e300; },
      "thresholds: need 0 < dim < saturation <= 255 DN");
}

TEST_F(ModelFileContent, rejects_a_saturation_threshold_above_the_bit_depth_n) {
  expect_edit_rejected(
      [](nlohmann::json& p) { p["profile"]["thresholds"]["inference_saturation_dn"] = 4000; },
      "thresholds: need 0 < dim < saturation <= 255 DN");
}

TEST_F(ModelFileContent, rejects_a_negative_system_qe_n) {
  expect_edit_rejected([](nlohmann::json& p) { p["system_qe"][2][10] = -0.5; },
                       "system_qe[2][10] is -0.5; QE values must be finite and >= 0");
}

TEST_F(ModelFileContent, rejects_a_bit_depth_beyond_an_int_n) {
  // Converting 1e300 to int is undefined; the value is checked as a number first.
  expect_edit_rejected([](nlohmann::json& p) { p["profile"]["bit_depth"] = 1e300; },
                       "profile.bit_depth is 1e+300; expected a whole number within 8..16");
}

TEST_F(ModelFileContent, rejects_a_directory_as_model_file_n) {
  std::filesystem::create_directory(dir / "model.json");
  try {
    load_model(dir / "model.json");
    ADD_FAILURE() << "accepted a directory";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("model.json: model file is a directory"),
              std::string::npos)
        << e.what();
  }
}

TEST(Baselines, ohno_inverts_the_noise_free_locus) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  const CameraModel cam{p, p.system_qe(), Eigen::VectorXd::Ones(3)};
  const OhnoEstimator ohno(make_locus(cam, 500, 3500, 1));
  for (double t : {612.3, 1000.0, 1777.7, 2950.5})
    EXPECT_NEAR(ohno.temperature_c(cam.rates(t) * 1e-3), t, 0.3) << t;
  EXPECT_TRUE(std::isnan(ohno.temperature_c(Eigen::Vector3d(0, 0, 0))));
}

// The paper's triangular solution in (r, g): off a three-sample locus, by hand 1005.88 degC (in
// (r, g, b), where b moves with both, 1007.37).
TEST(Baselines, ohno_measures_distances_in_r_g_as_the_paper) {
  Locus locus;
  locus.temperature_c = Eigen::Vector3d(1000, 1010, 1020);
  locus.rates.resize(3, 3);
  locus.rates << 0.5, 0.3, 0.2, 0.45, 0.33, 0.22, 0.4, 0.36, 0.24;
  locus.rates *= 7;  // chromaticities are scale free
  const OhnoEstimator ohno(locus);
  EXPECT_NEAR(ohno.temperature_c(Eigen::Vector3d(0.46, 0.30, 0.24) * 3), 1005.882, 0.001);
}

TEST(Baselines, two_colour_is_exact_for_narrow_bands_without_blue) {
  // Monochromatic R (650 nm) and G (550 nm) under Wien's approximation: the formula is exact.
  const double lr = 650e-9, lg = 550e-9;
  auto wien = [](double l, double t_k) { return std::pow(l, -5) * std::exp(-kC2 / (l * t_k)); };
  std::vector<Eigen::VectorXd> meas, sim;
  std::vector<double> temps;
  for (double t = 800; t <= 1400; t += 50) {
    const double tk = celsius_to_kelvin(t);
    meas.push_back(Eigen::Vector3d(wien(lr, tk), wien(lg, tk), 0));
    sim.push_back(meas.back());
    temps.push_back(t);
  }
  const TwoColourEstimator e = TwoColourEstimator::fit(meas, sim, temps, 0, 1, 2);
  for (std::size_t i = 0; i < temps.size(); ++i)
    EXPECT_NEAR(e.temperature_c(meas[i]), temps[i], 0.5);
  EXPECT_NEAR(e.params().lambda_r_nm, 650, 2);
  EXPECT_NEAR(e.params().lambda_g_nm, 550, 2);
}

TEST(Estimators, likelihood_fit_inverts_noise_free_signals_and_drops_saturated_bands) {
  const ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  const auto est = make_estimator(std::make_shared<const ThermalModel>(m), Method::kLikelihood);
  est->set_allow_partial(true);
  const auto strict = make_estimator(std::make_shared<const ThermalModel>(m),
                                     Method::kLikelihood);  // every band needed (default)
  for (double t : {700.0, 1234.5, 2000.0, 3000.0}) {
    Eigen::VectorXd s = m.camera.rates(t);
    s *= 150 / s.maxCoeff();  // an exposure that puts the brightest band at 150 DN
    EXPECT_NEAR(est->temperature_c(s.data()), t, 0.5) << t;
    // With two bands left the locus may reach the same ratio twice: a reading, if any, must
    // be the right one.
    Eigen::VectorXd sat = s;
    Eigen::Index brightest;
    sat.maxCoeff(&brightest);
    sat[brightest] = INFINITY;
    const double two_bands = est->temperature_c(sat.data());
    EXPECT_NEAR(strict->temperature_c(s.data()), t, 0.5) << t;
    EXPECT_TRUE(std::isnan(strict->temperature_c(sat.data()))) << t << " partial, not allowed";
    if (std::isfinite(two_bands)) {
      EXPECT_NEAR(two_bands, t, 1.0) << t << " without its brightest band";
    }
  }
  // 25 bands: one saturated band leaves plenty.
  const ThermalModel nir = small_model(load_profile_by_name("nir5x5-reference"));
  const auto nir_est =
      make_estimator(std::make_shared<const ThermalModel>(nir), Method::kLikelihood);
  nir_est->set_allow_partial(true);
  for (double t : {1100.0, 2345.6}) {
    Eigen::VectorXd s = nir.camera.rates(t);
    s *= 150 / s.maxCoeff();
    s[12] = INFINITY;
    EXPECT_NEAR(nir_est->temperature_c(s.data()), t, 0.5) << t;
  }
  const double dim[3] = {5, 5, 5};
  EXPECT_TRUE(std::isnan(est->temperature_c(dim)));
}

TEST(Estimators, mlp_method_needs_every_band_valid) {
  const ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  const auto est = make_estimator(std::make_shared<const ThermalModel>(m), Method::kMlp);
  const double ok[3] = {100, 120, 60}, saturated[3] = {INFINITY, 120, 60}, dim[3] = {100, 12, 60},
               nan[3] = {100, NAN, 60};
  EXPECT_TRUE(std::isfinite(est->temperature_c(ok)));
  EXPECT_TRUE(std::isnan(est->temperature_c(saturated)));
  EXPECT_TRUE(std::isnan(est->temperature_c(dim)));
  EXPECT_TRUE(std::isnan(est->temperature_c(nan)));
}

TEST(Estimators, likelihood_rejects_a_range_narrower_than_its_coarse_step_n) {
  ThermalModel m = small_model(load_profile_by_name("rgb-reference"));
  m.min_temperature_c = 1000;
  m.max_temperature_c = 1015;
  try {
    make_estimator(std::make_shared<const ThermalModel>(m), Method::kLikelihood);
    ADD_FAILURE() << "a 15 degC range was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("spans less than 20 degC"), std::string::npos) << e.what();
  }
  m.max_temperature_c = 1040;
  EXPECT_NO_THROW(make_estimator(std::make_shared<const ThermalModel>(m), Method::kLikelihood));
}

TEST(Estimators, lut_method_rejects_a_multispectral_model_n) {
  const ThermalModel m = small_model(load_profile_by_name("nir5x5-reference"));
  EXPECT_THROW(make_estimator(std::make_shared<const ThermalModel>(m), Method::kLut), InputError);
  EXPECT_THROW(parse_method("neural"), InputError);
}

}  // namespace
}  // namespace pyrocam
