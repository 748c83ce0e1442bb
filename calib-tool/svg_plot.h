// Minimal inline SVG line/point plots for the self-contained calibration report.
#pragma once

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
};

// An <svg> element with axes, ticks, a legend and the series; NaN points are skipped.
std::string svg_plot(const PlotSpec& spec, const std::vector<Series>& series);

// HTML-escapes text.
std::string html_escape(const std::string& s);

}  // namespace pyrocam::cli
