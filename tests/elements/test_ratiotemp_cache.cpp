// ratiotemp's lookup-table files: the table-cache (the blocks a run filled, kept for the next) and
// the prebuilt table beside the model (<model>.lut, written by pyrocam-calib).
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam/runtime/model.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

std::string rgb_model_path() {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(dir ? dir : ".") + "/test-model-rgb.json";
}

// The colour test model copied into `dir` without its prebuilt table.
std::string model_alone(const ScratchDir& dir) {
  const std::string copy = (dir / "model.json").string();
  std::filesystem::copy_file(rgb_model_path(), copy);
  return copy;
}

// A pipeline run to its end: the file it wrote and the warnings on the bus.
struct PlateRun {
  bool ok = false;
  std::string codes;
  std::vector<std::string> warnings;
  bool warned(const std::string& part) const {
    for (const auto& w : warnings)
      if (w.find(part) != std::string::npos) return true;
    return false;
  }
};

PlateRun run_plate(const std::string& model, const std::string& table_cache,
                   const std::string& out) {
  PlateRun r;
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(
      ("pyrocamsrc scene=plate seed=3 num-buffers=3 ! video/x-bayer,width=64,height=48 ! "
       "darksub dark-level=50 ! demosaic25 ! ratiotemp method=lut model=\"" +
       model + "\" table-cache=\"" + table_cache + "\" ! filesink location=\"" + out + "\"")
          .c_str(),
      &error);
  if (!pipeline) {
    ADD_FAILURE() << (error ? error->message : "no pipeline");
    g_clear_error(&error);
    return r;
  }
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  while (
      GstMessage* m = gst_bus_timed_pop_filtered(
          bus, scaled_timeout(20 * GST_SECOND),
          static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR | GST_MESSAGE_WARNING))) {
    const GstMessageType type = GST_MESSAGE_TYPE(m);
    if (type == GST_MESSAGE_WARNING) {
      GError* w = nullptr;
      gst_message_parse_warning(m, &w, nullptr);
      r.warnings.push_back(w->message);
      g_error_free(w);
    }
    r.ok = type == GST_MESSAGE_EOS;
    gst_message_unref(m);
    if (type != GST_MESSAGE_WARNING) break;
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
  std::ifstream in(out, std::ios::binary);
  r.codes.assign(std::istreambuf_iterator<char>(in), {});
  return r;
}

// table-cache: the first run keeps the lookup table's blocks in the folder (a file named by the
// model's fingerprint), the next starts with them and writes the same temperatures; an altered
// cache is not used and changes nothing; nor does running without a cache, or with one that
// cannot be written (a warning says so).
TEST(RatioTempTableCache, a_second_run_reads_the_cache_and_gives_the_same_codes) {
  REQUIRE_ELEMENT("ratiotemp");
  ScratchDir dir("ratiotemp-cache");
  const std::string model = model_alone(dir);
  const std::string cache = (dir / "cache").string();
  const std::string file = cache + "/lut-" + load_model(model).fingerprint + ".bin";
  const auto run = [&](const std::string& table_cache, const std::string& out) {
    const PlateRun r = run_plate(model, table_cache, out);
    EXPECT_TRUE(r.ok);
    return r.codes;
  };
  const std::string first = run(cache, (dir / "first.raw").string());
  ASSERT_EQ(first.size(), 3u * 64 * 48 * 2);
  ASSERT_TRUE(std::filesystem::exists(file));
  // Set an hour back, so that a rewrite shows whatever the file system's time resolution.
  const auto written = std::filesystem::last_write_time(file) - std::chrono::hours(1);
  std::filesystem::last_write_time(file, written);
  EXPECT_EQ(run(cache, (dir / "second.raw").string()), first);
  EXPECT_EQ(std::filesystem::last_write_time(file), written) << "nothing new to keep";
  {
    std::fstream f(file, std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(200);
    f.put('\x7f');
  }
  EXPECT_EQ(run(cache, (dir / "third.raw").string()), first);
  EXPECT_EQ(run("", (dir / "fourth.raw").string()), first);
  // A cache that cannot be kept (its folder under a file): the same codes, and a warning why.
  const PlateRun unkept =
      run_plate(model, (dir / "first.raw").string() + "/cache", (dir / "fifth.raw").string());
  EXPECT_TRUE(unkept.ok);
  EXPECT_EQ(unkept.codes, first);
  EXPECT_TRUE(unkept.warned("The lookup table's cache cannot be kept")) << unkept.warnings.size();
}

// The prebuilt table beside the model: read at start (no warning), the same codes as without
// it; an altered one is refused with a warning on the bus naming it and why, and changes no code;
// without one and without a cache, a warning that the start is cold.
TEST(RatioTempPrebuiltTable, it_is_read_and_gives_the_same_codes_an_altered_one_a_warning_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const std::string prebuilt = rgb_model_path() + ".lut";
  ASSERT_TRUE(std::filesystem::exists(prebuilt)) << "calibrate writes it beside a colour model";
  ScratchDir dir("ratiotemp-prebuilt");
  const std::string model = model_alone(dir);
  const PlateRun cold = run_plate(model, "", (dir / "cold.raw").string());
  ASSERT_TRUE(cold.ok);
  ASSERT_EQ(cold.codes.size(), 3u * 64 * 48 * 2);
  EXPECT_TRUE(cold.warned("No prebuilt lookup table beside model")) << cold.warnings.size();
  // table-cache="": no cache to look in (the warning said "none in the table cache").
  EXPECT_TRUE(cold.warned("and no table cache (table-cache is empty)")) << cold.warnings.size();

  std::filesystem::copy_file(prebuilt, model + ".lut");
  const PlateRun with = run_plate(model, "", (dir / "with.raw").string());
  EXPECT_TRUE(with.ok);
  EXPECT_TRUE(with.warnings.empty()) << with.warnings.front();
  EXPECT_EQ(with.codes, cold.codes);

  {
    std::fstream f(model + ".lut", std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(static_cast<std::streamoff>(std::filesystem::file_size(model + ".lut") / 2));
    f.put('\x7f');
  }
  const PlateRun altered = run_plate(model, "", (dir / "altered.raw").string());
  EXPECT_TRUE(altered.ok);
  ASSERT_EQ(altered.warnings.size(), 1u);
  EXPECT_TRUE(altered.warned("Prebuilt lookup table " + model + ".lut not used"))
      << altered.warnings[0];
  EXPECT_TRUE(altered.warned("truncated or altered")) << altered.warnings[0];
  EXPECT_EQ(altered.codes, cold.codes);
}

}  // namespace
}  // namespace pyrocam::test
