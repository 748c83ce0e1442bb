// mosaicfuse and pyrocamsrc's bracket: each fused mosaic is, sample by sample, the number of the
// most exposed of the last `frames` frames that has one (not near the level next to a saturated
// sample of its band, where another has one), scaled to the most exposed frame held,
// whose exposure the buffer then carries; frames without an exposure pass unchanged with a
// warning.
#include <algorithm>
#include <cmath>
#include <cstdio>
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

std::string chain(const std::string& fuse, const std::string& camera = "") {
  return camera.empty() ? "pyrocamsrc scene=melt-pool bracket=3,1,0.333 num-buffers=9 ! "
                          "video/x-bayer,width=64,height=48 ! darksub dark-level=50 ! " +
                              fuse + " ! fakesink name=sink"
                        : camera + " ! darksub dark-level=50 ! " + fuse + " ! fakesink name=sink";
}

// Whether sample i of a width-wide mosaic (cells of `period`) is near the level (at least 85 %
// of the largest number seen, this frame's included) with a sample of its band within two cells
// saturated: the fusion takes it only where no frame has a sample free of that.
std::vector<bool> near_saturated(const std::vector<float>& v, int width, int period,
                                 float& largest) {
  for (float x : v)
    if (std::isfinite(x)) largest = std::max(largest, x);
  const int height = static_cast<int>(v.size()) / width;
  std::vector<bool> near(v.size(), false);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      if (!(v[y * width + x] >= 0.85f * largest)) continue;
      for (int dy = -2 * period; dy <= 2 * period; dy += period)
        for (int dx = -2 * period; dx <= 2 * period; dx += period) {
          const int yy = y + dy, xx = x + dx;
          if (yy >= 0 && yy < height && xx >= 0 && xx < width &&
              v[yy * width + xx] == std::numeric_limits<float>::infinity())
            near[y * width + x] = true;
        }
    }
  return near;
}

// The rule for frames where they are (follow-motion=false; pyrocamsrc's pool moves).
void expect_fused(const std::string& camera, int width, int period) {
  const FuseRun plain = run(chain("mosaicfuse frames=1", camera)),
                fused = run(chain("mosaicfuse frames=3 follow-motion=false", camera));
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(plain.frames.size(), 9u);
  ASSERT_EQ(fused.frames.size(), 9u);
  std::vector<std::vector<bool>> near;
  float largest = 0;
  for (const auto& f : plain.frames)
    near.push_back(near_saturated(f.values, width, period, largest));
  std::size_t from_earlier = 0, plain_numbers = 0, fused_numbers = 0, by_neighbours = 0;
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
      // The expected sample: the most exposed of k-2..k with a number not near a saturated
      // one (the latest on ties), else the most exposed with a number.
      float want = std::numeric_limits<float>::infinity(), any = want;
      double best = 0, best_any = 0;
      for (std::size_t j = first; j <= k; ++j) {
        const float v = plain.frames[j].values[i];
        const double e = plain.frames[j].exposure_us;
        const float scaled = v * static_cast<float>(reference / e);
        if (std::isfinite(v) && e >= best_any) best_any = e, any = scaled;
        if (std::isfinite(v) && !near[j][i] && e >= best) best = e, want = scaled;
      }
      if (best == 0) want = any;
      ASSERT_EQ(fused.frames[k].values[i], want) << "frame " << k << " sample " << i;
      from_earlier += want != plain.frames[k].values[i];
      by_neighbours += want != any;
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
  // The bracket matters here: samples came from other frames, and more of them are numbers;
  // and some near the level were taken from a shorter frame for their neighbours.
  EXPECT_GT(from_earlier, 0u);
  EXPECT_GT(fused_numbers, plain_numbers);
  EXPECT_GT(by_neighbours, 0u);
  EXPECT_TRUE(plain.warnings.empty() && fused.warnings.empty());
}

TEST(MosaicFuse, EachSampleFromTheMostExposedOfTheLastFramesScaledToIt) {
  REQUIRE_ELEMENT("mosaicfuse");
  expect_fused("", 64, 2);
}

// The neighbours of a 5x5 mosaic's sample are 5 pixels apart (the caps' pattern says so).
TEST(MosaicFuse, A5x5MosaicsNeighboursAreItsBandsSamples) {
  REQUIRE_ELEMENT("mosaicfuse");
  expect_fused(
      "pyrocamsrc profile=nir5x5-reference scene=melt-pool bracket=3,1,0.333 num-buffers=9 "
      "! video/x-raw,width=100,height=60",
      100, 5);
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

// Over a moving pool the bracket's frames disagree on the samples of its steep sides: one
// warning, the fusion going on; over a still plate none (its frames agree on every sample).
TEST(MosaicFuse, AMovingSceneGetsOneWarningAStillOneNone) {
  REQUIRE_ELEMENT("mosaicfuse");
  auto camera = [](const std::string& scene) {
    return "pyrocamsrc " + scene +
           " bracket=3,1,0.333 num-buffers=24 ! video/x-bayer,width=320,height=240";
  };
  const FuseRun moving = run(chain("mosaicfuse frames=3", camera("scene=melt-pool"))),
                still = run(chain("mosaicfuse frames=3", camera("scene=plate temperature=1500")));
  ASSERT_TRUE(moving.eos && still.eos);
  EXPECT_EQ(moving.frames.size(), 24u);
  ASSERT_EQ(moving.warnings.size(), 1u);
  EXPECT_NE(moving.warnings[0].find("The scene moves"), std::string::npos) << moving.warnings[0];
  EXPECT_TRUE(still.warnings.empty()) << still.warnings[0];
}

// Following the moving pool (the default), the fused samples agree with the latest frame's
// where that one exposes them well: each fused sample, scaled back to the latest frame's
// exposure, against that frame's own, beyond the bound mosaicfuse's motion check uses (4
// standard deviations of 1 DN of shot variance per DN and a 4 DN^2 floor, and 5 %).
TEST(MosaicFuse, FollowingAMovingPoolTheFusedSamplesAgreeWithTheLatestFrame) {
  REQUIRE_ELEMENT("mosaicfuse");
  const std::string camera =
      "pyrocamsrc scene=melt-pool bracket=3,1,0.333 num-buffers=24 ! "
      "video/x-bayer,width=320,height=240";
  const FuseRun plain = run(chain("mosaicfuse frames=1", camera)),
                followed = run(chain("mosaicfuse frames=3", camera)),
                still = run(chain("mosaicfuse frames=3 follow-motion=false", camera));
  ASSERT_TRUE(plain.eos && followed.eos && still.eos);
  ASSERT_EQ(followed.frames.size(), 24u);
  ASSERT_EQ(still.frames.size(), 24u);
  auto disagreeing = [&](const FuseRun& fused, std::size_t& compared) {
    std::size_t count = 0;
    compared = 0;
    for (std::size_t k = 6; k < 24; ++k) {  // from the third cycle: the velocity found
      const auto& latest = plain.frames[k].values;
      const double back = plain.frames[k].exposure_us / fused.frames[k].exposure_us;
      for (std::size_t i = 0; i < latest.size(); ++i) {
        const double v = latest[i], f = fused.frames[k].values[i] * back;
        if (!(v >= 16 && v <= 150) || !std::isfinite(f) || f == v) continue;
        ++compared;
        count += std::abs(f - v) > 4 * std::sqrt(v + 4 + (f + 4) * back) + 0.05 * std::max(f, v);
      }
    }
    return count;
  };
  std::size_t compared_followed, compared_still;
  const std::size_t off_followed = disagreeing(followed, compared_followed),
                    off_still = disagreeing(still, compared_still);
  std::printf(
      "fused samples from earlier frames off the latest frame's: %zu of %zu followed, %zu "
      "of %zu not\n",
      off_followed, compared_followed, off_still, compared_still);
  EXPECT_GT(off_still, 20u);  // the pool moves: without following its sides disagree
  EXPECT_LT(off_followed, off_still / 3);
  // Both warn once that the scene moves, and say whether they follow it.
  ASSERT_EQ(followed.warnings.size(), 1u);
  EXPECT_NE(followed.warnings[0].find("follows it"), std::string::npos) << followed.warnings[0];
  ASSERT_EQ(still.warnings.size(), 1u);
  EXPECT_NE(still.warnings[0].find("follow-motion=true"), std::string::npos) << still.warnings[0];
}

}  // namespace
}  // namespace pyrocam::test
