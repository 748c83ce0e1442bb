// mosaicfuse and pyrocamsrc's bracket: each fused mosaic is, sample by sample, the number of the
// most exposed of the last `frames` frames that has one, scaled to the most exposed frame held,
// whose exposure the buffer then carries; frames without an exposure pass unchanged with a
// warning.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "bracket_support.h"

namespace pyrocam::test {
namespace {

using FuseRun = BracketRun<float>;
FuseRun run(const std::string& launch, const std::function<void(GstElement*)>& prepare = {}) {
  return run_bracket<float>(launch, prepare);
}

std::string chain(const std::string& fuse) {
  return "pyrocamsrc scene=melt-pool bracket=1,0.333,0.111 num-buffers=9 ! "
         "video/x-bayer,width=64,height=48 ! darksub dark-level=50 ! " +
         fuse + " ! fakesink name=sink";
}

TEST(MosaicFuse, EachSampleFromTheMostExposedOfTheLastFramesScaledToIt) {
  REQUIRE_ELEMENT("mosaicfuse");
  const FuseRun plain = run(chain("mosaicfuse frames=1")),
                fused = run(chain("mosaicfuse frames=3"));
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(plain.frames.size(), 9u);
  ASSERT_EQ(fused.frames.size(), 9u);
  std::size_t from_earlier = 0, plain_numbers = 0, fused_numbers = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    const std::size_t first = k >= 2 ? k - 2 : 0;
    // The reference: the most exposed frame held (the latest of equals).
    double reference = 0;
    for (std::size_t j = first; j <= k; ++j)
      reference = std::max(reference, plain.frames[j].exposure_us);
    EXPECT_EQ(fused.frames[k].exposure_us, reference) << "frame " << k;
    const std::size_t n = plain.frames[k].values.size();
    ASSERT_EQ(fused.frames[k].values.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      // The expected sample: the most exposed of k-2..k with a number, the latest on ties.
      float want = std::numeric_limits<float>::infinity();
      double best = 0;
      for (std::size_t j = first; j <= k; ++j) {
        const float v = plain.frames[j].values[i];
        if (std::isfinite(v) && plain.frames[j].exposure_us >= best) {
          best = plain.frames[j].exposure_us;
          want = v * static_cast<float>(reference / best);
        }
      }
      ASSERT_EQ(fused.frames[k].values[i], want) << "frame " << k << " sample " << i;
      from_earlier += want != plain.frames[k].values[i];
      plain_numbers += std::isfinite(plain.frames[k].values[i]);
      fused_numbers += std::isfinite(want);
    }
  }
  // Each fused mosaic says how many of its samples are still saturated; darksub's frames too.
  std::size_t saturated_plain = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    for (const FuseRun* r : {&plain, &fused}) {
      const auto& v = r->frames[k].values;
      EXPECT_EQ(r->frames[k].saturated,
                std::count(v.begin(), v.end(), std::numeric_limits<float>::infinity()))
          << "frame " << k;
    }
    saturated_plain += static_cast<std::size_t>(std::max(0LL, plain.frames[k].saturated));
  }
  EXPECT_GT(saturated_plain, 0u);  // the long exposures saturate the pool
  // The bracket matters here: samples came from other frames, and more of them are numbers.
  EXPECT_GT(from_earlier, 0u);
  EXPECT_GT(fused_numbers, plain_numbers);
  EXPECT_TRUE(plain.warnings.empty() && fused.warnings.empty());
}

bool same_bits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(MosaicFuse, AFrameOutOfTimeOrderStartsTheFusionAnewWithOneWarning) {
  REQUIRE_ELEMENT("mosaicfuse");
  FrameBackInTime sixth{6};
  const FuseRun plain = run(chain("mosaicfuse frames=1")),
                fused = run(chain("mosaicfuse name=fuse frames=3"),
                            [&](GstElement*pipeline) { sixth.probe(pipeline, "fuse"); });
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(fused.frames.size(), 9u);
  ASSERT_EQ(fused.warnings.size(), 1u);
  EXPECT_NE(fused.warnings[0].find("out of time order"), std::string::npos) << fused.warnings[0];
  // The 6th mosaic is fused with nothing before it; the 5th still was.
  EXPECT_TRUE(same_bits(fused.frames[5].values, plain.frames[5].values));
  EXPECT_EQ(fused.frames[5].exposure_us, plain.frames[5].exposure_us);
  EXPECT_FALSE(same_bits(fused.frames[4].values, plain.frames[4].values));
}

TEST(MosaicFuse, FramesWithoutAnExposurePassUnchangedWithOneWarning) {
  REQUIRE_ELEMENT("mosaicfuse");
  const std::string source =
      "videotestsrc num-buffers=3 ! video/x-raw,format=GRAY8,width=8,height=4 ! "
      "darksub pattern=rggb dark-level=0 ! ";
  const FuseRun r = run(source + "mosaicfuse frames=3 ! fakesink name=sink"),
                same = run(source + "fakesink name=sink");
  ASSERT_TRUE(r.eos);
  ASSERT_EQ(r.frames.size(), 3u);
  ASSERT_EQ(same.frames.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(r.frames[k].values, same.frames[k].values);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("without its exposure"), std::string::npos) << r.warnings[0];
}

}  // namespace
}  // namespace pyrocam::test
