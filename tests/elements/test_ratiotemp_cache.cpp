// ratiotemp's table-cache: the lookup table's filled blocks kept between runs.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "element_support.h"
#include "pyrocam/runtime/model.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

std::string rgb_model_path() {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(dir ? dir : ".") + "/test-model-rgb.json";
}

// table-cache: the first run keeps the lookup table's blocks in the folder (a file named by the
// model's fingerprint), the next starts with them and writes the same temperatures; an altered
// cache is not used and changes nothing; nor does running without a cache.
TEST(RatioTempTableCache, a_second_run_reads_the_cache_and_gives_the_same_codes) {
  REQUIRE_ELEMENT("ratiotemp");
  ScratchDir dir("ratiotemp-cache");
  const std::string cache = (dir / "cache").string();
  const std::string file = cache + "/lut-" + load_model(rgb_model_path()).fingerprint + ".bin";
  const auto run = [&](const std::string& table_cache, const std::string& out) {
    const BusResult r = run_pipeline(
        "pyrocamsrc scene=plate seed=3 num-buffers=3 ! video/x-bayer,width=64,height=48 ! "
        "darksub dark-level=50 ! demosaic25 ! ratiotemp method=lut model=\"" +
        rgb_model_path() + "\" table-cache=\"" + table_cache +
        "\" ! filesink name=sink location=\"" + out + "\"");
    EXPECT_TRUE(r.eos && !r.error) << r.message << " " << r.debug;
    std::ifstream in(out, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  const std::string first = run(cache, (dir / "first.raw").string());
  ASSERT_EQ(first.size(), 3u * 64 * 48 * 2);
  ASSERT_TRUE(std::filesystem::exists(file));
  const auto written = std::filesystem::last_write_time(file);
  EXPECT_EQ(run(cache, (dir / "second.raw").string()), first);
  EXPECT_EQ(std::filesystem::last_write_time(file), written) << "nothing new to keep";
  {
    std::fstream f(file, std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(200);
    f.put('\x7f');
  }
  EXPECT_EQ(run(cache, (dir / "third.raw").string()), first);
  EXPECT_EQ(run("", (dir / "fourth.raw").string()), first);
}

}  // namespace
}  // namespace pyrocam::test
