// pyrocam-calib prebuild: the prebuilt lookup table of an existing colour model, which ratiotemp
// then reads at start; none for a 5x5 model (no lookup table), with the reason.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <string>

#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/prebuilt_tables.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;
namespace fs = std::filesystem;

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// Runs pyrocam-calib; returns its exit code, stderr into `err`.
int calib(const std::string& args, const ScratchDir& dir, std::string& err) {
  const fs::path err_file = dir / "stderr.txt";
  const std::string command = "timeout 120 '" + std::string(PYROCAM_CALIB_TOOL) + "' " + args +
                              " < /dev/null > /dev/null 2> " + q(err_file);
  const int status = std::system(command.c_str());
  err = read_all(err_file);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

fs::path test_model(const std::string& name) {
  const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
  return fs::path(dir ? dir : ".") / name;
}

TEST(CliPrebuild, writes_the_table_beside_an_existing_model_that_ratiotemp_then_reads) {
  ScratchDir dir("cli-prebuild");
  const fs::path model = dir / "old-model.json";
  fs::copy_file(test_model("test-model-rgb.json"), model);
  std::string err;
  ASSERT_EQ(calib("prebuild --model " + q(model) + " --max-blocks 64", dir, err), 0) << err;
  const fs::path table = dir / "old-model.json.lut";
  ASSERT_TRUE(fs::exists(table));
  const auto m = std::make_shared<const ThermalModel>(load_model(model));
  const std::string text = read_all(table);
  EXPECT_EQ(text.rfind("pyrocam lookup-table cache", 0), 0u);
  EXPECT_NE(text.substr(0, 200).find(m->fingerprint), std::string::npos) << "tied to the model";
  EstimatorSelector s(m);
  s.set_prebuilt_tables(prebuilt_tables_file(model.string()));
  ASSERT_EQ(s.select(MethodRequest::kAuto).method, Method::kLut);
  EXPECT_EQ(s.prebuilt_problem(), "");
  EXPECT_GE(s.prebuilt_blocks_read(), 64u);
  EXPECT_TRUE(s.lut_check_skipped()) << "the file carries the check's verdict";

  // --out elsewhere; the model's own table stays as it was.
  const fs::path other = dir / "elsewhere.lut";
  ASSERT_EQ(calib("prebuild --model " + q(model) + " --max-blocks 8 --out " + q(other), dir, err),
            0)
      << err;
  EXPECT_TRUE(fs::exists(other));
  EXPECT_EQ(read_all(table), text);

  // --out the model itself: refused, the model as it was.
  const std::string json = read_all(model);
  EXPECT_EQ(calib("prebuild --model " + q(model) + " --max-blocks 8 --out " + q(model), dir, err),
            1);
  EXPECT_NE(err.find("is not a lookup table"), std::string::npos) << err;
  EXPECT_EQ(read_all(model), json);
  // --out a folder: said as such (it was "not a lookup table (the model itself?)").
  EXPECT_EQ(
      calib("prebuild --model " + q(model) + " --max-blocks 8 --out " + q(dir.path()), dir, err),
      1);
  EXPECT_NE(err.find("is a folder, not a lookup table file"), std::string::npos) << err;

  // An unknown command is named (CLI11 said only "A subcommand is required").
  EXPECT_EQ(calib("bogus --model " + q(model), dir, err), 2);
  EXPECT_NE(err.find("unknown command 'bogus'"), std::string::npos) << err;
}

TEST(CliPrebuild, a_5x5_model_gets_no_table_and_the_reason_n) {
  ScratchDir dir("cli-prebuild-5x5");
  const fs::path model = dir / "nir.json";
  fs::copy_file(test_model("test-model-nir5x5.json"), model);
  std::string err;
  EXPECT_EQ(calib("prebuild --model " + q(model), dir, err), 1);
  EXPECT_NE(err.find("no prebuilt lookup table"), std::string::npos) << err;
  EXPECT_NE(err.find("needs two"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(dir / "nir.json.lut"));
  // --out the model itself: the model stays (a stale table there would be removed).
  const std::string json = read_all(model);
  EXPECT_EQ(calib("prebuild --model " + q(model) + " --out " + q(model), dir, err), 1);
  EXPECT_EQ(read_all(model), json);
  // An error, so also with --quiet (which kept it back: exit 1 without a word).
  EXPECT_EQ(calib("-q prebuild --model " + q(model), dir, err), 1);
  EXPECT_NE(err.find("error: no prebuilt lookup table"), std::string::npos) << err;
  // Not a model, or an impossible block count: refused before anything is written.
  EXPECT_EQ(calib("prebuild --model " + q(dir / "missing.json"), dir, err), 2);
  EXPECT_EQ(calib("prebuild --model " + q(model) + " --max-blocks 0", dir, err), 2);
}

}  // namespace
}  // namespace pyrocam
