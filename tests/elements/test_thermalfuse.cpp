// thermalfuse and pyrocamsrc's bracket: the frames cycle through the bracket's exposures, each
// carrying its own; each fused frame is, pixel by pixel, the reading of the most exposed of the
// last `frames` frames that has one; frames without an exposure pass unchanged with a warning.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "bracket_support.h"

namespace pyrocam::test {
namespace {

using FuseRun = BracketRun<std::uint16_t>;
FuseRun run(const std::string& launch, const std::function<void(GstElement*)>& prepare = {}) {
  return run_bracket<std::uint16_t>(launch, prepare);
}

std::string chain(const std::string& fuse) {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(
             "pyrocamsrc scene=melt-pool bracket=1,0.333,0.111 num-buffers=9 ! "
             "video/x-bayer,width=160,height=120 ! darksub dark-level=50 ! demosaic25 ! "
             "ratiotemp method=likelihood model=") +
         (dir ? dir : ".") + "/test-model-rgb.json ! " + fuse + " ! fakesink name=sink";
}

// The expected fused frame k: pixel by pixel, the reading of the most exposed of frames
// first..k of `plain` that reads it, the latest on ties.
std::vector<std::uint16_t> expected_fusion(const FuseRun& plain, std::size_t first, std::size_t k) {
  std::vector<std::uint16_t> want(plain.frames[k].values.size(), 0);
  for (std::size_t i = 0; i < want.size(); ++i) {
    double best = 0;
    for (std::size_t j = first; j <= k; ++j) {
      const std::uint16_t c = plain.frames[j].values[i];
      if (c != 0 && plain.frames[j].exposure_us >= best) {
        want[i] = c;
        best = plain.frames[j].exposure_us;
      }
    }
  }
  return want;
}

TEST(ThermalFuse, EachPixelFromTheMostExposedOfTheLastFramesThatReadsIt) {
  REQUIRE_ELEMENT("thermalfuse");
  const FuseRun plain = run(chain("thermalfuse frames=1")),
                fused = run(chain("thermalfuse frames=3"));
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(plain.frames.size(), 9u);
  ASSERT_EQ(fused.frames.size(), 9u);
  // The bracket: the automatic exposure, a third and a ninth of it, again and again.
  const double e0 = plain.frames[0].exposure_us;
  ASSERT_GT(e0, 0);
  for (std::size_t k = 0; k < 9; ++k) {
    const double factor[] = {1, 0.333, 0.111};
    EXPECT_NEAR(plain.frames[k].exposure_us, e0 * factor[k % 3], 1e-9 * e0);
    EXPECT_EQ(fused.frames[k].exposure_us, plain.frames[k].exposure_us);
  }
  std::size_t from_earlier = 0, plain_readings = 0, fused_readings = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    const std::size_t n = plain.frames[k].values.size();
    ASSERT_EQ(fused.frames[k].values.size(), n);
    const std::vector<std::uint16_t> expected = expected_fusion(plain, k >= 2 ? k - 2 : 0, k);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint16_t want = expected[i];
      ASSERT_EQ(fused.frames[k].values[i], want) << "frame " << k << " pixel " << i;
      from_earlier += want != plain.frames[k].values[i];
      plain_readings += plain.frames[k].values[i] != 0;
      fused_readings += want != 0;
    }
  }
  // A pixel saturated at the shortest exposure held is saturated at every one: the fused
  // frame carries that frame's saturation.
  bool saturated_long = false;
  for (std::size_t k = 0; k < 9; ++k) {
    std::size_t least = k;
    for (std::size_t j = k >= 2 ? k - 2 : 0; j <= k; ++j)
      if (plain.frames[j].exposure_us < plain.frames[least].exposure_us) least = j;
    ASSERT_GE(plain.frames[k].saturated, 0) << "frame " << k;
    EXPECT_EQ(fused.frames[k].saturated, plain.frames[least].saturated) << "frame " << k;
    saturated_long |= plain.frames[k].saturated > plain.frames[least].saturated;
  }
  EXPECT_TRUE(saturated_long);  // the long exposures saturate more of the pool
  // The bracket matters here: the fusion took readings from earlier frames and read more.
  EXPECT_GT(from_earlier, 0u);
  EXPECT_GT(fused_readings, plain_readings);
  EXPECT_TRUE(plain.warnings.empty() && fused.warnings.empty());
}

TEST(ThermalFuse, FramesWithoutAnExposurePassUnchangedWithOneWarning) {
  REQUIRE_ELEMENT("thermalfuse");
  const FuseRun r =
      run("videotestsrc num-buffers=3 ! video/x-raw,format=GRAY16_LE,width=8,height=4 ! "
          "thermalfuse ! fakesink name=sink");
  ASSERT_TRUE(r.eos);
  ASSERT_EQ(r.frames.size(), 3u);
  const FuseRun same =
      run("videotestsrc num-buffers=3 ! video/x-raw,format=GRAY16_LE,width=8,height=4 ! "
          "fakesink name=sink");
  ASSERT_EQ(same.frames.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(r.frames[k].values, same.frames[k].values);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("without its exposure"), std::string::npos) << r.warnings[0];
}

TEST(ThermalFuse, AFrameOutOfTimeOrderStartsTheFusionAnewWithOneWarning) {
  REQUIRE_ELEMENT("thermalfuse");
  FrameBackInTime sixth{6};
  const FuseRun plain = run(chain("thermalfuse frames=1")),
                fused = run(chain("thermalfuse name=fuse frames=3"),
                            [&](GstElement*pipeline) { sixth.probe(pipeline, "fuse"); });
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(fused.frames.size(), 9u);
  ASSERT_EQ(fused.warnings.size(), 1u);
  EXPECT_NE(fused.warnings[0].find("out of time order"), std::string::npos) << fused.warnings[0];
  // The 6th frame is fused with nothing before it, the next ones with no frame before it; those
  // before as ever.
  for (std::size_t k = 0; k < 9; ++k) {
    const std::size_t first = k < 5 ? (k >= 2 ? k - 2 : 0) : std::max<std::size_t>(5, k - 2);
    EXPECT_EQ(fused.frames[k].values, expected_fusion(plain, first, k)) << "frame " << k;
  }
  // And that is not what fusing across it gives.
  EXPECT_NE(fused.frames[5].values, expected_fusion(plain, 3, 5));
}

// A frame without an image (GAP: darksub capturing a dark) passes with no reading, and the
// fusion starts anew after it: fused with the frames before, it showed their readings (20 of a
// pool's pixels after a dark capture began).
TEST(ThermalFuse, AFrameWithoutAnImageHasNoReadingAndStartsTheFusionAnew) {
  REQUIRE_ELEMENT("thermalfuse");
  GapFrame sixth{6};
  const FuseRun plain = run(chain("thermalfuse frames=1")),
                fused = run(chain("thermalfuse name=fuse frames=3"),
                            [&](GstElement*pipeline) { sixth.probe(pipeline, "fuse"); });
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(fused.frames.size(), 9u);
  EXPECT_TRUE(fused.warnings.empty());
  const std::vector<std::uint16_t> none(fused.frames[5].values.size(), 0);
  EXPECT_EQ(fused.frames[5].values, none);
  for (std::size_t k = 0; k < 9; ++k) {
    if (k == 5) continue;
    const std::size_t first = k < 5 ? (k >= 2 ? k - 2 : 0) : std::max<std::size_t>(6, k - 2);
    EXPECT_EQ(fused.frames[k].values, expected_fusion(plain, first, k)) << "frame " << k;
  }
  EXPECT_NE(expected_fusion(plain, 3, 5), none);  // what fusing across it gave
}

TEST(ThermalFuse, ABadBracketStopsTheCameraWithAClearError) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const BusResult r = run_pipeline("pyrocamsrc bracket=1,zero num-buffers=2 ! fakesink name=sink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"bracket", "zero"});
}

}  // namespace
// A bracket step past the camera's range is taken at its end, with one warning and the
// exposure the frame was taken with in its meta: a cold plate's automatic exposure is already
// the longest (10 s), and 9 times it was 90 s, whose simulated dark current filled full pixels
// to below the saturation level (read as 1100-1300 degC over a 600 degC 5x5 plate).
TEST(ThermalFuse, ABracketStepPastTheCamerasRangeIsHeldToItWithOneWarning) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const BracketRun<std::uint8_t> r = run_bracket<std::uint8_t>(
      "pyrocamsrc scene=plate temperature=300 bracket=9,1,0.5 num-buffers=6 ! "
      "video/x-bayer,width=40,height=20 ! fakesink name=sink");
  ASSERT_TRUE(r.eos);
  ASSERT_EQ(r.frames.size(), 6u);
  for (std::size_t k = 0; k < 6; ++k)
    EXPECT_EQ(r.frames[k].exposure_us, k % 3 == 2 ? 5e6 : 1e7) << "frame " << k;
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("9e+07 us (9 times 1e+07 us) is longer than the camera's longest"),
            std::string::npos)
      << r.warnings[0];
}

}  // namespace pyrocam::test
