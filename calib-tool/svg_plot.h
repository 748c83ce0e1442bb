// Minimal inline SVG line/point plots for the self-contained calibration report.
#pragma once

#include <cmath>
#include <string>
#include <vector>

namespace pyrocam::cli {

struct Series {
  std::string label;
  std::vector<double> x, y;
  std::string colour = "#1f77b4";
  bool points = false;  // markers instead of a line
  bool dashed = false;
  std::vector<std::string> labels = {};  // text beside each point ("" for none)
};

struct PlotSpec {
  std::string title, x_label, y_label;
  bool log_y = false;
  int width = 640, height = 360;
  std::string id = "";  // the <svg> element's id ("" for none)
  // An x range shaded and named on the plot (e.g. the furnace's temperatures); none if empty.
  double shade_from = NAN, shade_to = NAN;
  std::string shade_label = "";
};

// An <svg> element with axes, ticks, the series and their legend (right of the plot, each entry
// drawn as its series is); NaN points are skipped. A log axis is ticked on whole decades.
std::string svg_plot(const PlotSpec& spec, const std::vector<Series>& series);

// HTML-escapes text.
std::string html_escape(const std::string& s);

}  // namespace pyrocam::cli
