// The prebuilt lookup table shipped beside a colour model: the blocks it holds (the band around
// the locus, nearest first), readings from a table read back from it bit for bit those of a table
// filled as pixels need it, and a file that is altered, another model's or holds other values
// refused, adding nothing. Models: the small calibrated models the build makes (tests/data).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <set>
#include <string>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/runtime/prebuilt_tables.h"
#include "runtime/estimator_test_support.h"
#include "runtime/lut_tables.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void write_bytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

// Pixels, and pairs of float images, equal bit for bit (NaN where the other is NaN).
int differing(const cv::Mat& a, const cv::Mat& b) {
  int differ = 0;
  for (int i = 0; i < a.cols; ++i) {
    const float x = a.at<float>(0, i), y = b.at<float>(0, i);
    differ += !(std::memcmp(&x, &y, sizeof x) == 0 || (std::isnan(x) && std::isnan(y)));
  }
  return differ;
}

// One prebuilt table of the colour test model for every test (it takes seconds).
class PrebuiltTable : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new ScratchDir("prebuilt-table");
    file_ = new std::string((*dir_ / "test-model-rgb.json.lut").string());
    result_ = prebuild_tables(test_model("test-model-rgb.json"), *file_);
  }
  static void TearDownTestSuite() {
    delete file_;
    delete dir_;
  }
  static ScratchDir* dir_;
  static std::string* file_;
  static PrebuiltTables result_;
};
ScratchDir* PrebuiltTable::dir_ = nullptr;
std::string* PrebuiltTable::file_ = nullptr;
PrebuiltTables PrebuiltTable::result_;

TEST(PrebuiltTables, the_file_is_the_models_path_plus_lut) {
  EXPECT_EQ(prebuilt_tables_file("/data/rgb-model.json"), "/data/rgb-model.json.lut");
}

// The band holds the block of every noise-free locus sample, nearest first: each block once,
// all inside the table, more of them the more standard deviations it reaches.
TEST(PrebuiltTables, the_band_holds_the_locus_blocks_once_each) {
  const auto model = test_model("test-model-rgb.json");
  const auto lut = make_estimator(model, Method::kLut);
  const TemperatureEstimator::TableGrid g = lut->table_grid();
  ASSERT_GT(g.block_size, 0);
  const std::vector<std::uint32_t> band = locus_band(*model, g);
  const std::set<std::uint32_t> unique(band.begin(), band.end());
  EXPECT_EQ(unique.size(), band.size());
  EXPECT_LT(*unique.rbegin(), static_cast<std::uint32_t>(g.across * g.down));
  EXPECT_LT(locus_band(*model, g, 1).size(), band.size());
  const Locus locus =
      make_locus(model->camera, model->min_temperature_c, model->max_temperature_c, 10);
  for (Eigen::Index i = 0; i < locus.size(); ++i) {
    const auto bx = static_cast<std::uint32_t>((locus.ratios(i, 0) - g.x0) / g.block_size);
    const auto by = static_cast<std::uint32_t>((locus.ratios(i, 1) - g.y0) / g.block_size);
    EXPECT_EQ(unique.count(by * static_cast<std::uint32_t>(g.across) + bx), 1u)
        << locus.temperature_c[i] << " degC";
  }
  // A 5x5 model has no lookup table, so no band.
  EXPECT_THROW(locus_band(*test_model("test-model-nir5x5.json"), g), InputError);
  EXPECT_THROW(lut->fill_tables({static_cast<std::uint32_t>(g.across * g.down)}), InputError);
}

// Blocks a table fills for these pixels: empty, or starting from the prebuilt file; and whether
// both read every pixel alike, bit for bit.
struct Fills {
  std::size_t lazy = 0, prebuilt = 0;
  int differing = -1;
};
Fills fills(const std::string& file, const NoisyPixels& px) {
  const auto model = test_model("test-model-rgb.json");
  const std::vector<cv::Mat> planes = as_planes(px);
  Fills f;
  const PlaneEstimator lazy(model, Method::kLut);
  const std::size_t empty = lazy.estimator().fill_tables({});
  cv::Mat lazy_c;
  lazy.estimate(planes, lazy_c);
  f.lazy = lazy.estimator().fill_tables({}) - empty;
  const PlaneEstimator prebuilt(model, Method::kLut);
  prebuilt.estimator().load_tables(file);
  const std::size_t loaded = prebuilt.estimator().fill_tables({});
  cv::Mat prebuilt_c;
  prebuilt.estimate(planes, prebuilt_c);
  f.prebuilt = prebuilt.estimator().fill_tables({}) - loaded;
  f.differing = differing(lazy_c, prebuilt_c);
  return f;
}

// A table read back from the prebuilt file holds the blocks it was given, with the verdict of the
// check, and reads every pixel bit for bit as a table filled as the pixels need it: single
// pixels from the dim threshold up (whose noise scatters them over many blocks), and well exposed
// ones, more of whose blocks it holds.
TEST_F(PrebuiltTable, readings_are_those_of_a_table_filled_as_pixels_need_it) {
  ASSERT_EQ(result_.problem, "");
  ASSERT_GT(result_.blocks, 1000u);
  EXPECT_LE(result_.blocks, 8192u);
  const auto model = test_model("test-model-rgb.json");
  const PlaneEstimator prebuilt(model, Method::kLut);
  EXPECT_EQ(prebuilt.estimator().load_tables(*file_), result_.blocks);
  EXPECT_EQ(prebuilt.estimator().tables_verdict(), lut_check_verdict());

  const double saturation = saturation_signal_dn(*model);
  const Fills all =
      fills(*file_, noisy_pixels(*model, kSweepC, 400, 15, 200, saturation, 0.02, 23));
  EXPECT_EQ(all.differing, 0);
  EXPECT_GT(all.lazy, 0u);
  EXPECT_LT(all.prebuilt, all.lazy);
  const Fills bright =
      fills(*file_, noisy_pixels(*model, kSweepC, 400, 120, 200, saturation, 0, 29));
  EXPECT_EQ(bright.differing, 0);
  // Well exposed pixels lie nearer the locus: more of their blocks are there.
  EXPECT_LT(bright.prebuilt * 3, bright.lazy * 2) << bright.prebuilt << " of " << bright.lazy;
  EXPECT_LT(bright.prebuilt * all.lazy, all.prebuilt * bright.lazy);
}

// Through the selector as ratiotemp uses it: the prebuilt table spares the check, the grid's
// derivation and gives its blocks; the cache written after it keeps its blocks and the run's own.
TEST_F(PrebuiltTable, the_selector_reads_it_before_the_cache_and_skips_the_check) {
  ASSERT_EQ(result_.problem, "");
  ScratchDir cache("prebuilt-cache");
  const auto model = test_model("test-model-rgb.json");
  const std::string cache_file = table_cache_file(*model, cache.path().string());
  EstimatorSelector s(model);
  s.set_prebuilt_tables(*file_);
  s.set_table_cache(cache_file);
  ASSERT_EQ(s.select(MethodRequest::kAuto).method, Method::kLut);
  EXPECT_EQ(s.prebuilt_blocks_read(), result_.blocks);
  EXPECT_EQ(s.prebuilt_problem(), "");
  EXPECT_TRUE(s.lut_check_skipped());
  EXPECT_EQ(s.save_table_cache(), 0u) << "nothing beyond the prebuilt blocks";
  // Its table is on the grid the file names (not derived again): the same as derived, the
  // same readings as a table filled as pixels need it.
  const TemperatureEstimator::TableGrid derived = make_estimator(model, Method::kLut)->table_grid();
  const TemperatureEstimator::TableGrid named = s.estimator(Method::kLut).estimator().table_grid();
  EXPECT_EQ(derived.x0, named.x0);
  EXPECT_EQ(derived.y0, named.y0);
  EXPECT_EQ(derived.block_size, named.block_size);
  EXPECT_EQ(derived.across, named.across);
  EXPECT_EQ(derived.down, named.down);
  const NoisyPixels px =
      noisy_pixels(*model, {700, 3300}, 200, 15, 40, saturation_signal_dn(*model), 0, 5);
  cv::Mat out, lazy;
  s.estimator(Method::kLut).estimate(as_planes(px), out);
  PlaneEstimator(model, Method::kLut).estimate(as_planes(px), lazy);
  EXPECT_EQ(differing(lazy, out), 0);
  EXPECT_GT(s.save_table_cache(), result_.blocks) << "the run's own blocks after the prebuilt";
}

// Altered, cut short, another model's, values this machine does not compute (a valid file
// otherwise), larger than any table file (refused unread): refused with the reason, nothing added,
// the check run, the readings unchanged.
TEST_F(PrebuiltTable, a_corrupt_or_foreign_file_is_refused_and_the_readings_stay_n) {
  ASSERT_EQ(result_.problem, "");
  const auto model = test_model("test-model-rgb.json");
  const std::string bytes = read_bytes(*file_);
  std::string altered = bytes;
  altered[altered.size() / 2] ^= 0x10;
  // The first block's first node changed and the checksum made again: a well-formed file.
  std::string other_values = bytes.substr(0, bytes.size() - 17);
  const std::size_t first_node = other_values.find('\n', other_values.find('\n') + 1) + 1 + 4;
  other_values[first_node] ^= 0x01;
  other_values += lut::table_checksum(other_values.data(), other_values.size()) + "\n";
  ThermalModel renamed = *model;
  renamed.fingerprint = "0123456789abcdef";
  const auto other_model = std::make_shared<const ThermalModel>(renamed);

  const NoisyPixels px =
      noisy_pixels(*model, kSweepC, 50, 15, 200, saturation_signal_dn(*model), 0.02, 7);
  const std::vector<cv::Mat> planes = as_planes(px);
  cv::Mat reference;
  PlaneEstimator(model, Method::kLut).estimate(planes, reference);

  struct Case {
    std::string name, content, reason;
    std::shared_ptr<const ThermalModel> model;
  };
  const std::vector<Case> cases = {
      {"altered", altered, "truncated or altered", model},
      {"short", bytes.substr(0, bytes.size() / 3), "truncated or altered", model},
      {"text", "pyrocam thermal model\n", "not a lookup-table file", model},
      {"other-values", other_values, "other values than this machine computes", model},
      {"other-model", bytes, "another model", other_model},
      // Past the most a file may hold (8192 blocks of 1160 bytes and its header).
      {"huge", bytes + std::string(std::size_t{10} << 20, '\0'), "larger than any table file",
       model}};
  ScratchDir dir("prebuilt-bad");
  for (const Case& c : cases) {
    const std::string path = (dir / (c.name + ".lut")).string();
    write_bytes(path, c.content);
    EstimatorSelector s(c.model);
    s.set_prebuilt_tables(path);
    ASSERT_EQ(s.select(MethodRequest::kLut).problem, "") << c.name;
    EXPECT_EQ(s.prebuilt_blocks_read(), 0u) << c.name;
    EXPECT_NE(s.prebuilt_problem().find(c.reason), std::string::npos)
        << c.name << ": " << s.prebuilt_problem();
    EXPECT_FALSE(s.lut_check_skipped()) << c.name;
    cv::Mat out;
    s.estimator(Method::kLut).estimate(planes, out);
    if (c.model == model) {
      EXPECT_EQ(differing(reference, out), 0) << c.name;
    }
  }
  // A directory in its place: named as such (its size read as an absurd one before).
  std::filesystem::create_directory(dir / "folder.lut");
  EstimatorSelector folder(model);
  folder.set_prebuilt_tables((dir / "folder.lut").string());
  ASSERT_EQ(folder.select(MethodRequest::kLut).problem, "");
  EXPECT_EQ(folder.prebuilt_blocks_read(), 0u);
  EXPECT_NE(folder.prebuilt_problem().find("is not a regular file"), std::string::npos)
      << folder.prebuilt_problem();
  // Not there: no problem, nothing read.
  EstimatorSelector missing(model);
  missing.set_prebuilt_tables((dir / "missing.lut").string());
  ASSERT_EQ(missing.select(MethodRequest::kLut).problem, "");
  EXPECT_EQ(missing.prebuilt_blocks_read(), 0u);
  EXPECT_EQ(missing.prebuilt_problem(), "");
}

// A 5x5 model has no lookup table: none is written, and a table left there by an earlier model
// of that name (of any version) is removed; a file there that is not a table is left as it is.
TEST(PrebuiltTables, a_5x5_model_gets_none_and_a_stale_file_goes_n) {
  ScratchDir dir("prebuilt-5x5");
  const std::string file = (dir / "model.json.lut").string();
  write_bytes(file, "{\"not\": \"a table\"}\n");
  const PrebuiltTables kept = prebuild_tables(test_model("test-model-nir5x5.json"), file);
  EXPECT_EQ(kept.blocks, 0u);
  EXPECT_NE(kept.problem.find("is not a lookup table"), std::string::npos) << kept.problem;
  EXPECT_TRUE(std::filesystem::exists(file));
  write_bytes(file, "pyrocam lookup-table cache 3\nleft from an earlier colour model\n");
  const PrebuiltTables t = prebuild_tables(test_model("test-model-nir5x5.json"), file);
  EXPECT_EQ(t.blocks, 0u);
  EXPECT_NE(t.problem.find("needs two"), std::string::npos) << t.problem;
  EXPECT_FALSE(std::filesystem::exists(file));
  // A model not loaded from a file has no fingerprint to tie a table to.
  ThermalModel unnamed = *test_model("test-model-rgb.json");
  unnamed.fingerprint.clear();
  EXPECT_THROW(prebuild_tables(std::make_shared<const ThermalModel>(unnamed), file), InputError);
}

}  // namespace
}  // namespace pyrocam::test
