// The library's own exp, log, pow, sin and cos (the same bits on every machine): within 2 ulp of
// the C library's over the ranges the library uses, exact where the answer is, and the edges
// (overflow, underflow, zero, NaN) as std:: gives them.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "detail/portable_math.h"

namespace pyrocam {
namespace {

// Distance in units in the last place between two finite doubles of the same sign.
std::int64_t ulps(double a, double b) {
  std::int64_t ia, ib;
  std::memcpy(&ia, &a, sizeof a);
  std::memcpy(&ib, &b, sizeof b);
  return ia > ib ? ia - ib : ib - ia;
}

// Both libraries are within about 1 ulp of the true value, so they are within 2 of each other.
constexpr std::int64_t kUlps = 2;

TEST(PortableMath, exp_and_expm1_match_the_c_library) {
  for (double x = -740; x < 709; x += 0.0137) {
    ASSERT_LE(ulps(portable::exp(x), std::exp(x)), kUlps) << x;
  }
  for (double x = -0.6; x < 0.6; x += 1.3e-4) {
    if (x == 0) continue;
    ASSERT_LE(ulps(portable::expm1(x), std::expm1(x)), kUlps) << x;
  }
  for (double x : {1e-300, 1e-20, 1e-9, -1e-9, 3.0, 40.0})
    EXPECT_LE(ulps(portable::expm1(x), std::expm1(x)), kUlps) << x;
  EXPECT_EQ(portable::exp(0.0), 1.0);
  EXPECT_LE(ulps(portable::exp(1.0), M_E), 1);
  EXPECT_EQ(portable::exp(710.0), std::numeric_limits<double>::infinity());
  EXPECT_EQ(portable::exp(-746.0), 0.0);
  EXPECT_TRUE(std::isnan(portable::exp(NAN)));
  EXPECT_EQ(portable::exp(-INFINITY), 0.0);
}

TEST(PortableMath, log_and_pow_match_the_c_library) {
  for (double x = 1e-300; x < 1e300; x *= 1.0123) {
    ASSERT_LE(ulps(portable::log(x), std::log(x)), kUlps) << x;
  }
  for (double x = 0.5; x < 2; x += 1e-4) {
    if (x == 1) continue;
    ASSERT_LE(ulps(portable::log(x), std::log(x)), kUlps) << x;
  }
  EXPECT_LE(ulps(portable::log(4.9406564584124654e-324), std::log(4.9406564584124654e-324)), 1);
  EXPECT_EQ(portable::log(1.0), 0.0);
  EXPECT_LE(ulps(portable::log(2.0), M_LN2), 1);
  EXPECT_LE(ulps(portable::log(10.0), M_LN10), 1);
  EXPECT_EQ(portable::log(0.0), -INFINITY);
  EXPECT_TRUE(std::isnan(portable::log(-1.0)));
  EXPECT_TRUE(std::isnan(portable::log(NAN)));
  // pow through exp(y log x): its error grows with |y log x|, about 1e-15 relative here.
  for (double x : {0.9, 0.999, 1.26, 10.0, 1e-3})
    for (double y : {0.5, 1.0, 3.0, 17.0, -2.5, 100.0})
      EXPECT_NEAR(portable::pow(x, y) / std::pow(x, y), 1.0, 1e-13) << x << "^" << y;
  EXPECT_EQ(portable::pow(7.0, 0.0), 1.0);
}

TEST(PortableMath, sin_and_cos_match_the_c_library) {
  for (double x = -400; x < 400; x += 0.00731) {
    const double s = portable::sin(x), c = portable::cos(x);
    // Near a zero the relative error of the reduced argument dominates: compare absolutely there.
    ASSERT_NEAR(s, std::sin(x), 4e-16 * std::max(1.0, std::fabs(x) / 16)) << x;
    ASSERT_NEAR(c, std::cos(x), 4e-16 * std::max(1.0, std::fabs(x) / 16)) << x;
    if (std::fabs(s) > 0.1) {
      ASSERT_LE(ulps(s, std::sin(x)), kUlps) << x;
    }
    if (std::fabs(c) > 0.1) {
      ASSERT_LE(ulps(c, std::cos(x)), kUlps) << x;
    }
  }
  EXPECT_EQ(portable::sin(0.0), 0.0);
  EXPECT_EQ(portable::cos(0.0), 1.0);
  EXPECT_TRUE(std::isnan(portable::sin(INFINITY)));
  EXPECT_TRUE(std::isnan(portable::cos(NAN)));
}

}  // namespace
}  // namespace pyrocam
