// The report's plots: tick labels tell neighbouring ticks apart at any scale.
#include <gtest/gtest.h>

#include <algorithm>
#include <regex>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "svg_plot.h"

namespace pyrocam::cli {
namespace {

// The labels of one axis: text anchored at its end (y) or middle (x), in order.
std::vector<std::string> axis_labels(const std::string& svg, const std::string& anchor) {
  std::vector<std::string> out;
  const std::regex label("text-anchor='" + anchor + "'>([^<]*)</text>");
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), label); it != std::sregex_iterator();
       ++it)
    out.push_back((*it)[1]);
  return out;
}

std::string plot(const std::vector<double>& x, const std::vector<double>& y) {
  return svg_plot({"t", "x", "y"}, {Series{"s", x, y}});
}

TEST(SvgPlot, tick_labels_differ_on_an_axis_much_narrower_than_its_values) {
  // Slope fits' R^2 over a calibration: 0.9999990 to 0.9999998 (the y ticks read 1, 1, 1).
  const std::vector<std::string> y =
      axis_labels(plot({700, 900, 1100}, {0.999999, 0.9999994, 0.9999998}), "end");
  ASSERT_GE(y.size(), 3u);
  EXPECT_EQ(std::set<std::string>(y.begin(), y.end()).size(), y.size());
  for (const std::string& l : y) EXPECT_EQ(l.rfind("0.99999", 0), 0u) << l;
  // Temperatures keep their plain form; the x ticks lie on a 100 degC step.
  const std::vector<std::string> x = axis_labels(plot({700, 900, 1100}, {1, 2, 3}), "middle");
  EXPECT_NE(std::find(x.begin(), x.end(), "800"), x.end());
  EXPECT_NE(std::find(x.begin(), x.end(), "1000"), x.end());
}

TEST(SvgPlot, tick_labels_of_large_and_small_values) {
  for (const auto& [lo, hi] : {std::pair{1.2e6, 1.21e6}, {2e-5, 2.4e-5}, {-0.5, 0.5}}) {
    const std::vector<std::string> y = axis_labels(plot({0, 1}, {lo, hi}), "end");
    ASSERT_GE(y.size(), 2u) << lo;
    EXPECT_EQ(std::set<std::string>(y.begin(), y.end()).size(), y.size()) << lo;
  }
}

}  // namespace
}  // namespace pyrocam::cli
