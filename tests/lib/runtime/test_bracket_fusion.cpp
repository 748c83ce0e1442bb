// Exposure-bracket fusion: each pixel from the most exposed frame that reads it.
#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/core.hpp>

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

}  // namespace
}  // namespace pyrocam
