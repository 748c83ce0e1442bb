// Exposure-bracket fusion: each pixel from the most exposed frame that reads it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>

#include "detail/random.h"
#include "pyrocam/core/error.h"
#include "pyrocam/runtime/bracket_fusion.h"

namespace pyrocam {
namespace {

// A 1x4 frame of codes.
cv::Mat frame(std::uint16_t a, std::uint16_t b, std::uint16_t c, std::uint16_t d) {
  return (cv::Mat_<std::uint16_t>(1, 4) << a, b, c, d);
}

std::vector<std::uint16_t> codes(const cv::Mat& m) {
  return {m.begin<std::uint16_t>(), m.end<std::uint16_t>()};
}

TEST(BracketFusion, EachPixelFromTheMostExposedFrameThatReadsIt) {
  BracketFusion fusion(2);
  cv::Mat out;
  // Long exposure: the core (pixel 0) saturated, the rim (pixel 1) reads.
  fusion.add(frame(0, 15000, 0, 17000), 1000, out);
  EXPECT_EQ(codes(out), codes(frame(0, 15000, 0, 17000))) << "nothing before it";
  // Short exposure: the core reads, the rim too dim; pixel 3 reads in both: the long one's.
  fusion.add(frame(25000, 0, 0, 17005), 100, out);
  EXPECT_EQ(codes(out), codes(frame(25000, 15000, 0, 17000)));
  // The next long frame replaces the first: only the last two frames count.
  fusion.add(frame(0, 15100, 0, 0), 1000, out);
  EXPECT_EQ(codes(out), codes(frame(25000, 15100, 0, 17005)));
  // In place, and ties go to the latest.
  cv::Mat in_place = frame(26000, 15200, 9, 0);
  fusion.add(in_place, 1000, in_place);
  EXPECT_EQ(codes(in_place), codes(frame(26000, 15200, 9, 0)));
}

TEST(BracketFusion, OneFrameIsNoFusionAndANewSizeStartsAnew) {
  BracketFusion single(1);
  cv::Mat out;
  single.add(frame(1, 0, 3, 0), 10, out);
  single.add(frame(0, 2, 0, 4), 1, out);
  EXPECT_EQ(codes(out), codes(frame(0, 2, 0, 4)));
  BracketFusion fusion(3);
  fusion.add(frame(1, 1, 1, 1), 10, out);
  fusion.add(cv::Mat_<std::uint16_t>(2, 2, std::uint16_t{0}), 1, out);
  EXPECT_EQ(cv::countNonZero(out), 0) << "the 1x4 frame is not laid over a 2x2 one";
  EXPECT_EQ(fusion.held(), 1u);
}

TEST(BracketFusion, ParsesExposureFactors) {
  EXPECT_EQ(parse_bracket(""), std::vector<double>{});
  EXPECT_EQ(parse_bracket("1,0.1"), (std::vector<double>{1, 0.1}));
  EXPECT_EQ(parse_bracket("2"), std::vector<double>{2});
  for (const char* bad : {"1,", ",1", "1,,2", "0", "-1", "1e9", "x", "1;2", "nan",
                          "1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1,1"})
    EXPECT_THROW(parse_bracket(bad), InputError) << bad;
}

TEST(BracketFusion, BadInputIsRefused) {
  EXPECT_THROW(BracketFusion(0), InputError);
  EXPECT_THROW(BracketFusion(kMaxBracketFrames + 1), InputError);
  BracketFusion fusion(2);
  cv::Mat out;
  EXPECT_THROW(fusion.add(frame(1, 2, 3, 4), 0, out), InputError);
  EXPECT_THROW(fusion.add(frame(1, 2, 3, 4), NAN, out), InputError);
  EXPECT_THROW(fusion.add(cv::Mat_<float>(1, 4, 1.f), 10, out), InputError);
}

constexpr float kSat = std::numeric_limits<float>::infinity();
constexpr float kNone = std::numeric_limits<float>::quiet_NaN();

// A 1x5 dark-subtracted mosaic.
cv::Mat mosaic(float a, float b, float c, float d, float e) {
  return (cv::Mat_<float>(1, 5) << a, b, c, d, e);
}

void expect_samples(const cv::Mat& m, std::vector<float> want) {
  ASSERT_EQ(m.total(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    const float v = m.at<float>(0, static_cast<int>(i));
    if (std::isnan(want[i]))
      EXPECT_TRUE(std::isnan(v)) << i;
    else
      EXPECT_EQ(v, want[i]) << i;
  }
}

// A period longer than the 1x5 test mosaics: no sample has a neighbour of its band.
constexpr int kNoNeighbours = 16;

TEST(MosaicBracketFusion, EachSampleFromTheMostExposedFrameScaledToIt) {
  MosaicBracketFusion fusion(3, kNoNeighbours);
  cv::Mat out;
  // Long exposure (light 900): samples 0 and 4 saturated, 3 no reading.
  EXPECT_EQ(fusion.add(mosaic(kSat, 150, 12, kNone, kSat), 900, out), 900);
  expect_samples(out, {kSat, 150, 12, kNone, kSat});
  // A third of it: sample 0 reads, 4 is still saturated.
  EXPECT_EQ(fusion.add(mosaic(100, 50.5f, 4, kNone, kSat), 300, out), 900);
  expect_samples(out, {300, 150, 12, kNone, kSat});
  // A ninth: sample 4 reads now, scaled by 9; sample 3 has no number in any frame: NaN; the
  // most exposed frame is still the reference.
  cv::Mat in_place = mosaic(40, 17, 1.5f, kSat, 100);
  EXPECT_EQ(fusion.add(in_place, 100, in_place), 900);
  expect_samples(in_place, {300, 150, 12, kNone, 900});
  // The next frame replaces the long one: the reference is the frame of light 300 now.
  EXPECT_EQ(fusion.add(mosaic(kSat, kSat, kSat, kSat, kSat), 50, out), 300);
  expect_samples(out, {100, 50.5f, 4, kNone, 300});
}

TEST(MosaicBracketFusion, SaturatedEverywhereStaysSaturatedAndBadInputIsRefused) {
  MosaicBracketFusion fusion(2, kNoNeighbours);
  cv::Mat out;
  fusion.add(mosaic(kSat, 1, 2, 3, 4), 10, out);
  fusion.add(mosaic(kSat, 1, 2, 3, 4), 5, out);
  EXPECT_EQ(out.at<float>(0, 0), kSat);
  // A new size starts anew: nothing to fuse with.
  cv::Mat wide = cv::Mat(1, 6, CV_32F, cv::Scalar(7));
  EXPECT_EQ(fusion.add(wide, 1, out), 1);
  EXPECT_EQ(cv::countNonZero(out != 7), 0);
  EXPECT_THROW(fusion.add(cv::Mat(1, 5, CV_16U, cv::Scalar(1)), 10, out), InputError);
  EXPECT_THROW(fusion.add(mosaic(1, 2, 3, 4, 5), 0, out), InputError);
  EXPECT_THROW(fusion.add(mosaic(1, 2, 3, 4, 5), std::nan(""), out), InputError);
  EXPECT_THROW(MosaicBracketFusion(0, 2), InputError);
  EXPECT_THROW(MosaicBracketFusion(kMaxBracketFrames + 1, 2), InputError);
  EXPECT_THROW(MosaicBracketFusion(2, 0), InputError);
  EXPECT_THROW(MosaicBracketFusion(2, 17), InputError);
}

TEST(MosaicBracketFusion, ASampleNearTheLevelNextToASaturatedOneIsTakenFromAShorterFrame) {
  MosaicBracketFusion fusion(2, 2);
  cv::Mat out;
  // Long frame, one row of a Bayer mosaic (period 2): sample 6 saturated. Its band's samples
  // within two cells (4 pixels: 2, 4, 8, 10) are its neighbours; 10 is below 85 % of the
  // frame's largest (100), not near the level. The odd samples are another band's.
  const cv::Mat long_frame =
      (cv::Mat_<float>(1, 14) << 100, 100, 96, 100, 98, 100, kSat, 100, 97, 100, 60, 100, 99, 100);
  fusion.add(long_frame, 10, out);
  fusion.add(cv::Mat(1, 14, CV_32F, cv::Scalar(9)), 1, out);
  expect_samples(out, {100, 100, 90, 100, 90, 100, 90, 100, 90, 100, 60, 100, 99, 100});
  // Where the shorter frame's sample is near the level next to a saturated one too, the first
  // frame with a number is taken still. The level is one for every exposure: the largest
  // number seen, 100, in each frame's own DN.
  MosaicBracketFusion both(2, 2);
  both.add(long_frame, 10, out);
  both.add((cv::Mat_<float>(1, 14) << 9, 9, 90, 9, kSat, 9, kSat, 9, 9, 9, 9, 9, 9, 9), 1, out);
  expect_samples(out, {100, 100, 96, 100, 98, 100, kSat, 100, 90, 100, 60, 100, 99, 100});
}

// Consecutive frames are compared on the samples both expose well (16 DN up to 85 % of the
// largest number seen), scaled to one exposure: a still scene agrees, an edge that moved between
// them does not where the bound on the noise cannot explain the difference.
TEST(MosaicBracketFusion, ConsecutiveFramesDisagreeWhereAnEdgeMoved) {
  constexpr int kW = 200;
  // 200 DN left of `edge`, 50 right of it, times `scale`; one sample at 400 (the largest number
  // seen: samples up to 340 compare).
  auto frame = [](int edge, float scale) {
    cv::Mat m(1, kW, CV_32F);
    for (int x = 0; x < kW; ++x) m.at<float>(0, x) = (x < edge ? 200.f : 50.f) * scale;
    m.at<float>(0, kW - 1) = 400 * scale;
    return m;
  };
  MosaicBracketFusion still(2, 2), moving(2, 2);
  cv::Mat out;
  still.add(frame(100, 1), 3, out);
  EXPECT_EQ(still.last_agreement().compared, 0u);  // nothing before it
  still.add(frame(100, 1.f / 3), 1, out);
  EXPECT_EQ(still.last_agreement().compared, kW - 1u);
  EXPECT_EQ(still.last_agreement().disagreeing, 0u);
  // The edge 10 samples further on in the second frame: there the long frame says 50 and the
  // short one 200 (scaled), 150 apart, beyond 4 sqrt(50 + 4 + (66.7 + 4) 9) + 10 = 115.
  moving.add(frame(100, 1), 3, out);
  moving.add(frame(110, 1.f / 3), 1, out);
  MosaicBracketFusion::Agreement sum = moving.last_agreement();
  EXPECT_EQ(sum.compared, kW - 1u);
  EXPECT_EQ(sum.disagreeing, 10u);
  EXPECT_FALSE(sum.moved());          // fewer than 20 samples
  moving.add(frame(120, 1), 3, out);  // and on again, now the long frame
  sum += moving.last_agreement();
  EXPECT_EQ(sum.disagreeing, 20u);
  EXPECT_TRUE(sum.moved());
  moving.reset();
  EXPECT_EQ(moving.last_agreement().compared, 0u);
}

// A uniform surface whose samples lie near the saturation level in the long frame: the fused
// samples' mean is the surface's. Taken wherever it is below the level, a sample is kept where
// its own noise pulled it down: the mean of a normal cut at z standard deviations above its
// mean is phi(z) low, 0.40 at z = 0 and 0.35 at 0.5 (measured so before the neighbours
// decided). Decided by its 24 neighbours of the band, the lean is phi(z) Phi(z)^24 (the sample
// alone saturating), at most 0.033 (z = 1.84); at the mosaic's border, with fewer neighbours,
// more. The mean of 160 000 fused samples of at most 1.8 standard deviations (the short
// frame's, scaled by 3) has a standard error of 0.005: the bound of 0.08 leaves 0.02 for the
// border (2 % of the samples) and 5 standard errors.
TEST(MosaicBracketFusion, SamplesNearTheSaturationLevelKeepTheSurfacesMean) {
  constexpr int kSide = 400;
  constexpr float kLevel = 200, kSigma = 3;
  Random random(29);
  for (double z : {-0.5, 0.0, 0.5, 1.0, 1.84, 2.5}) {
    const double mean = kLevel - z * kSigma;
    cv::Mat long_frame(kSide, kSide, CV_32F), short_frame(kSide, kSide, CV_32F);
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x) {
        const double v = mean + kSigma * random.normal();
        long_frame.at<float>(y, x) = v >= kLevel ? kSat : static_cast<float>(v);
        // A third of the light: the shot noise of a third of the signal.
        short_frame.at<float>(y, x) =
            static_cast<float>(mean / 3 + kSigma / std::sqrt(3.0) * random.normal());
      }
    MosaicBracketFusion fusion(2, 2);
    cv::Mat out;
    fusion.add(long_frame, 3, out);
    fusion.add(short_frame, 1, out);
    ASSERT_EQ(cv::countNonZero(out != out), 0);
    EXPECT_NEAR(cv::mean(out)[0], mean, 0.08 * kSigma) << "surface " << z << " sigma below";
  }
}

}  // namespace
}  // namespace pyrocam
