// Camera profile reading: the shipped profiles, and every rejection the format promises.
#include <gtest/gtest.h>

#include <fstream>

#include "pyrocam/core/profile.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;
using test::write_text;

TEST(Profile, shipped_rgb_reference_loads) {
  const CameraProfile p = load_profile_by_name("rgb-reference");
  EXPECT_EQ(p.name, "rgb-reference");
  ASSERT_EQ(p.band_count(), 3);
  EXPECT_EQ(p.mosaic.kind, MosaicLayout::Kind::kBayer);
  EXPECT_EQ(p.mosaic.band_at(0, 0), p.band_index("R"));
  EXPECT_EQ(p.mosaic.band_at(1, 1), p.band_index("B"));
  EXPECT_EQ(p.bit_depth, 8);
  EXPECT_DOUBLE_EQ(p.dark_offset_dn, 50);
  EXPECT_DOUBLE_EQ(p.band_gain[0], 1);
  EXPECT_DOUBLE_EQ(p.band_gain[1], 2);
  EXPECT_DOUBLE_EQ(p.band_gain[2], 4);
  const Eigen::MatrixXd q = p.system_qe();
  EXPECT_GE(q.minCoeff(), 0);
  EXPECT_LE(q.maxCoeff(), 1);
  // The BP550-type filter passes green light and blocks 800 nm.
  const auto g = p.grid.index_of(540), nir = p.grid.index_of(800);
  EXPECT_GT(q(1, g), 100 * q(1, nir));
}

TEST(Profile, shipped_nir5x5_reference_loads) {
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  ASSERT_EQ(p.band_count(), 25);
  EXPECT_EQ(p.mosaic.kind, MosaicLayout::Kind::kSnapshot);
  EXPECT_EQ(p.mosaic.period_width, 5);
  EXPECT_EQ(p.mosaic.band_at(7, 6), 7);  // row 1, column 2 of the 5x5 cell
  EXPECT_EQ(p.grid.step_nm(), 1);
  EXPECT_EQ(p.normalisation.reference.size(), 8u);
  EXPECT_EQ(p.normalisation.reference.front(), 8);  // b9, 1-based names
  // Band 1's first Fabry-Perot peak in the IMEC file is at 915.5 nm.
  Eigen::Index peak;
  p.sensor_qe.row(0).segment(p.grid.index_of(880), 60).maxCoeff(&peak);
  EXPECT_NEAR(p.grid.nm()[p.grid.index_of(880) + peak], 915.5, 3.0);
}

// A minimal valid profile in a scratch folder, with a CSV curve beside it.
class ProfileFiles : public ::testing::Test {
 protected:
  ScratchDir dir{"profile"};
  std::string qe_csv =
      "# comment\nwavelength_nm,red,green,blue\n400,0.1,0.2,0.3\n500,0.2,0.3,0.4\n"
      "600,0.3,0.4,0.5\n700,0.2,0.1,0.1\n";
  std::string mosaic = R"({"type": "bayer", "pattern": "RGGB"})";
  std::string extra;

  std::filesystem::path write() {
    write_text(dir / "curves/qe.csv", qe_csv);
    write_text(dir / "p.json", R"({
      "format": "pyrocam-camera-profile", "version": 1, "name": "t",
      "mosaic": )" + mosaic + R"(,
      "wavelength_grid_nm": {"start": 400, "stop": 700, "step": 10},
      "bands": [
        {"name": "R", "qe": {"file": "curves/qe.csv", "column": "red"}},
        {"name": "G", "qe": {"file": "curves/qe.csv", "column": "green"}},
        {"name": "B", "qe": {"file": "curves/qe.csv", "column": "blue"}}],
      )" + extra + R"(
      "normalisation": {"numerators": ["R", "B"], "reference": ["G"]}})");
    return dir / "p.json";
  }

  // Loading must fail with an InputError whose message names `file` and contains `problem`.
  void expect_rejected(const std::string& file, const std::string& problem) {
    try {
      load_profile(write());
      ADD_FAILURE() << "accepted a profile that should fail with: " << problem;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(file), std::string::npos) << msg;
      EXPECT_NE(msg.find(problem), std::string::npos) << msg;
    }
  }
};

TEST_F(ProfileFiles, relative_paths_resolve_against_the_profile_folder) {
  const CameraProfile p = load_profile(write());
  ASSERT_EQ(p.grid.size(), 31);
  EXPECT_NEAR(p.sensor_qe(0, p.grid.index_of(450)), 0.15, 1e-12);  // interpolated
  EXPECT_NEAR(p.sensor_qe(2, p.grid.index_of(700)), 0.1, 1e-12);
}

TEST_F(ProfileFiles, rejects_missing_profile_n) {
  EXPECT_THROW(load_profile(dir / "nothing.json"), InputError);
}

TEST_F(ProfileFiles, rejects_missing_curve_file_n) {
  extra = R"("optics": ["curves/lens.csv"],)";
  expect_rejected("p.json", "'curves/lens.csv' not found");
}

TEST_F(ProfileFiles, rejects_wrong_column_count_n) {
  qe_csv = "wavelength_nm,red,green,blue\n400,0.1,0.2,0.3\n500,0.2,0.3\n700,0.1,0.1,0.1\n";
  expect_rejected("qe.csv:3", "3 columns, the header has 4");
}

TEST_F(ProfileFiles, rejects_wavelengths_not_increasing_n) {
  qe_csv =
      "wavelength_nm,red,green,blue\n400,0.1,0.2,0.3\n600,0.2,0.3,0.4\n550,0.1,0.1,0.1\n"
      "700,0.1,0.1,0.1\n";
  expect_rejected("qe.csv", "wavelengths not increasing");
}

TEST_F(ProfileFiles, rejects_negative_qe_n) {
  qe_csv = "wavelength_nm,red,green,blue\n400,0.1,0.2,0.3\n550,-0.2,0.3,0.4\n700,0.1,0.1,0.1\n";
  expect_rejected("qe.csv [red]", "negative value");
}

TEST_F(ProfileFiles, rejects_non_numeric_curve_values_n) {
  qe_csv = "wavelength_nm,red,green,blue\n400,0.1,abc,0.3\n700,0.1,0.1,0.1\n";
  expect_rejected("qe.csv:2", "'abc' in column 'green' is not a number");
}

TEST_F(ProfileFiles, rejects_curve_not_covering_the_grid_n) {
  qe_csv = "wavelength_nm,red,green,blue\n450,0.1,0.2,0.3\n700,0.1,0.1,0.1\n";
  expect_rejected("qe.csv", "the profile's grid needs 400");
}

TEST_F(ProfileFiles, rejects_unknown_layout_n) {
  mosaic = R"({"type": "hexagonal"})";
  expect_rejected("p.json", "unknown mosaic type 'hexagonal'");
}

TEST_F(ProfileFiles, rejects_unknown_bayer_pattern_n) {
  mosaic = R"({"type": "bayer", "pattern": "RGBG"})";
  expect_rejected("p.json", "unknown Bayer pattern 'RGBG'");
}

TEST_F(ProfileFiles, rejects_band_count_not_matching_mosaic_n) {
  mosaic = R"({"type": "snapshot", "band_map": [[0, 1], [2, 3]]})";
  expect_rejected("p.json", "mosaic uses 4 bands, 3 are described");
}

TEST_F(ProfileFiles, rejects_a_band_index_beyond_an_int_n) {
  // get<int> of 1e300 is an undefined conversion; the value is checked first.
  mosaic = R"({"type": "snapshot", "band_map": [[0, 1], [2, 1e300]]})";
  expect_rejected("p.json", "mosaic.band_map holds 1e+300; band indices are whole numbers 0..63");
}

TEST_F(ProfileFiles, rejects_a_mosaic_period_above_16_n) {
  std::string row = "0";
  for (int b = 1; b < 17; ++b) row += ", " + std::to_string(b);
  mosaic = R"({"type": "snapshot", "band_map": [[)" + row + "]]}";
  expect_rejected("p.json", "mosaic.band_map is 17x1; a mosaic period is at most 16 on a side");
}

TEST_F(ProfileFiles, rejects_a_wavelength_grid_of_10_pow_12_samples_n) {
  write();
  std::ifstream in(dir / "p.json");
  std::string text(std::istreambuf_iterator<char>(in), {});
  text.replace(text.find("\"step\": 10"), 10, "\"step\": 3e-10");
  write_text(dir / "p.json", text);
  try {
    load_profile(dir / "p.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("p.json: wavelength_grid_nm 400.0..700.0 step 3e-10 nm has "
                                   "more than 100001 samples"),
        std::string::npos)
        << e.what();
  }
}

TEST_F(ProfileFiles, rejects_a_dim_threshold_of_zero_n) {
  extra = R"("thresholds": {"inference_dim_dn": 0},)";
  expect_rejected("p.json", "thresholds: need 0 < dim < saturation <= 255 DN");
}

TEST_F(ProfileFiles, rejects_a_profile_nested_too_deep_n) {
  extra = R"("description": )" + std::string(100, '[') + std::string(100, ']') + ",";
  expect_rejected("p.json", "JSON nested deeper than 64 levels");
}

TEST_F(ProfileFiles, rejects_a_directory_as_curve_file_n) {
  extra = R"("optics": ["curves/lens"],)";
  std::filesystem::create_directories(dir / "curves/lens");
  expect_rejected("curves/lens", "is a directory");
}

TEST_F(ProfileFiles, rejects_other_format_versions_n) {
  write();
  std::string text;
  {
    std::ifstream in(dir / "p.json");
    text.assign(std::istreambuf_iterator<char>(in), {});
  }
  text.replace(text.find("\"version\": 1"), 12, "\"version\": 7");
  write_text(dir / "p.json", text);
  try {
    load_profile(dir / "p.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("version 7"), std::string::npos) << e.what();
  }
}

TEST_F(ProfileFiles, rejects_invalid_json_n) {
  write();
  write_text(dir / "p.json", "{\"format\": ");
  try {
    load_profile(dir / "p.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("not valid JSON"), std::string::npos) << e.what();
  }
}

TEST_F(ProfileFiles, rejects_unknown_band_in_normalisation_n) {
  write();
  std::ifstream in(dir / "p.json");
  std::string text(std::istreambuf_iterator<char>(in), {});
  text.replace(text.find("\"reference\": [\"G\"]"), 18, "\"reference\": [\"Q\"]");
  write_text(dir / "p.json", text);
  EXPECT_THROW(load_profile(dir / "p.json"), InputError);
}

TEST(ImecXml, reads_25_bands_at_1nm_from_the_factory_file) {
  const auto bands =
      read_imec_band_responses(std::filesystem::path(PYROCAM_TEST_PROFILE_DIR) / "curves" /
                               "imec_CMV2K-SSM5x5-665_975-13.8.15.1_HS02-NIR.xml");
  ASSERT_EQ(bands.size(), 25u);
  EXPECT_EQ(bands[0].wavelength_nm.size(), 601u);
  EXPECT_DOUBLE_EQ(bands[24].wavelength_nm.back(), 1000.0);
}

TEST(ImecXml, rejects_a_file_of_another_kind_n) {
  ScratchDir dir("imec");
  write_text(dir / "x.xml", "<?xml version=\"1.0\"?><other/>");
  EXPECT_THROW(read_imec_band_responses(dir / "x.xml"), InputError);
  write_text(dir / "y.xml", "<not xml");
  EXPECT_THROW(read_imec_band_responses(dir / "y.xml"), InputError);
}

}  // namespace
}  // namespace pyrocam
