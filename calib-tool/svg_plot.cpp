#include "svg_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>

#include "pyrocam/runtime/colormap.h"

namespace pyrocam::cli {
namespace {

std::string fmt(double v) {
  char buf[32];
  if (v != 0 && (std::abs(v) >= 1e5 || std::abs(v) < 1e-3))
    std::snprintf(buf, sizeof buf, "%.2g", v);
  else
    std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// The library's ticks (bounded however small the step); a degenerate axis gets one tick.
std::vector<double> axis_ticks(double lo, double hi) {
  std::vector<double> t = nice_ticks(lo, hi, 6);
  if (t.empty()) t.push_back(lo);
  return t;
}

// A tick's label with the digits that tell it from its neighbours `step` away (an axis of R^2
// values from 0.9999990 to 0.9999998 otherwise reads 1, 1, 1).
std::string tick_label(double v, double step) {
  if (!(step > 0) || !std::isfinite(step)) return fmt(v);
  const int exponent = static_cast<int>(std::floor(std::log10(step)));
  const double mantissa = step / std::pow(10.0, exponent);
  const int extra = std::abs(mantissa - std::round(mantissa)) > 1e-6 ? 1 : 0;  // 2.5, 0.25
  char buf[48];
  if (v == 0 || (std::abs(v) < 1e5 && std::abs(v) >= 1e-3)) {
    std::snprintf(buf, sizeof buf, "%.*f", std::clamp(extra - exponent, 0, 15), v);
  } else {
    const int magnitude = static_cast<int>(std::floor(std::log10(std::abs(v))));
    std::snprintf(buf, sizeof buf, "%.*g", std::clamp(magnitude - exponent + 1 + extra, 2, 15), v);
  }
  return buf;
}

// Ticks of a log axis (values are log10): whole decades, every second or more where there are
// many; the library's ticks where fewer than two whole decades lie on the axis.
std::vector<double> decade_ticks(double lo, double hi) {
  const int first = static_cast<int>(std::ceil(lo - 1e-9)),
            last = static_cast<int>(std::floor(hi + 1e-9));
  if (last - first < 1) return axis_ticks(lo, hi);
  const int every = (last - first) / 8 + 1;
  std::vector<double> t;
  for (int k = first; k <= last; k += every) t.push_back(k);
  return t;
}

// 10 to a whole power as 10 with a superscript; other values as plain numbers.
std::string decade_label(double log_value) {
  const double k = std::round(log_value);
  if (std::abs(log_value - k) > 1e-9) return fmt(std::pow(10, log_value));
  return "10<tspan dy='-5' font-size='8'>" + std::to_string(static_cast<int>(k)) + "</tspan>";
}

std::vector<std::string> tick_labels(const std::vector<double>& ticks) {
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 0;
  std::vector<std::string> labels;
  for (double v : ticks) labels.push_back(tick_label(v, step));
  return labels;
}

}  // namespace

std::string html_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string svg_plot(const PlotSpec& spec, const std::vector<Series>& series) {
  const double inf = std::numeric_limits<double>::infinity();
  double x0 = inf, x1 = -inf, y0 = inf, y1 = -inf;
  auto ty = [&](double y) { return spec.log_y ? std::log10(y) : y; };
  for (const auto& s : series)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i]) || (spec.log_y && s.y[i] <= 0)) continue;
      x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, ty(s.y[i])), y1 = std::max(y1, ty(s.y[i]));
    }
  if (!std::isfinite(x0)) x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  if (x1 == x0) x1 = x0 + 1;
  if (y1 == y0) y1 = y0 + (y0 == 0 ? 1 : std::abs(y0) * 0.1);
  const double pad = 0.05 * (y1 - y0);
  y0 -= pad, y1 += pad;
  // The legend goes right of the plot, so that it never covers the data.
  const int legend_width = 170;
  const int l = 70, r = 20 + legend_width, t = 30, b = 45;
  const int w = spec.width, h = spec.height;
  auto px = [&](double x) { return l + (x - x0) / (x1 - x0) * (w - l - r); };
  auto py = [&](double y) { return h - b - (y - y0) / (y1 - y0) * (h - t - b); };

  std::ostringstream o;
  o << "<svg xmlns='http://www.w3.org/2000/svg'";
  if (!spec.id.empty()) o << " id='" << html_escape(spec.id) << "'";
  o << " width='" << w << "' height='" << h << "' font-family='sans-serif' font-size='11'>";
  o << "<rect width='100%' height='100%' fill='white'/>";
  o << "<text x='" << w / 2 << "' y='16' text-anchor='middle' font-size='13'>"
    << html_escape(spec.title) << "</text>";
  o << "<rect x='" << l << "' y='" << t << "' width='" << w - l - r << "' height='" << h - t - b
    << "' fill='none' stroke='#333'/>";
  if (std::isfinite(spec.shade_from) && std::isfinite(spec.shade_to)) {
    const double a = px(std::clamp(spec.shade_from, x0, x1)),
                 z = px(std::clamp(spec.shade_to, x0, x1));
    o << "<rect x='" << a << "' y='" << t << "' width='" << std::max(0.0, z - a) << "' height='"
      << h - t - b << "' fill='#fff3d6'/><text x='" << (a + z) / 2 << "' y='" << t + 12
      << "' text-anchor='middle' fill='#a07000'>" << html_escape(spec.shade_label) << "</text>";
  }
  const std::vector<double> x_ticks = axis_ticks(x0, x1),
                            y_ticks = spec.log_y ? decade_ticks(y0, y1) : axis_ticks(y0, y1);
  const std::vector<std::string> x_labels = tick_labels(x_ticks), y_labels = tick_labels(y_ticks);
  for (std::size_t i = 0; i < x_ticks.size(); ++i) {
    const double v = x_ticks[i];
    o << "<line x1='" << px(v) << "' x2='" << px(v) << "' y1='" << t << "' y2='" << h - b
      << "' stroke='#eee'/><text x='" << px(v) << "' y='" << h - b + 14 << "' text-anchor='middle'>"
      << x_labels[i] << "</text>";
  }
  for (std::size_t i = 0; i < y_ticks.size(); ++i) {
    const double v = y_ticks[i];
    o << "<line x1='" << l << "' x2='" << w - r << "' y1='" << py(v) << "' y2='" << py(v)
      << "' stroke='#eee'/><text x='" << l - 4 << "' y='" << py(v) + 4 << "' text-anchor='end'>"
      << (spec.log_y ? decade_label(v) : y_labels[i]) << "</text>";
  }
  o << "<text x='" << (l + w - r) / 2 << "' y='" << h - 8 << "' text-anchor='middle'>"
    << html_escape(spec.x_label) << "</text>";
  o << "<text transform='translate(14," << (t + h - b) / 2 << ") rotate(-90)' text-anchor='middle'>"
    << html_escape(spec.y_label) << "</text>";
  int legend_y = t + 14;
  for (const auto& s : series) {
    std::ostringstream path;
    bool pen = false;
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      const bool ok = std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && (!spec.log_y || s.y[i] > 0);
      if (!ok) {
        pen = false;
        continue;
      }
      if (s.points) {
        o << "<circle cx='" << px(s.x[i]) << "' cy='" << py(ty(s.y[i])) << "' r='2.5' fill='"
          << s.colour << "'/>";
      } else {
        path << (pen ? " L" : " M") << px(s.x[i]) << "," << py(ty(s.y[i]));
        pen = true;
      }
      if (i < s.labels.size() && !s.labels[i].empty()) {
        // Beside the point, on its left near the plot's right edge (so that it is not cut).
        const bool left = px(s.x[i]) > w - r - 60;
        o << "<text x='" << px(s.x[i]) + (left ? -5 : 5) << "' y='" << py(ty(s.y[i])) - 5
          << "' fill='" << s.colour << "'" << (left ? " text-anchor='end'" : "") << ">"
          << html_escape(s.labels[i]) << "</text>";
      }
    }
    if (!s.points)
      o << "<path d='" << path.str() << "' fill='none' stroke='" << s.colour
        << "' stroke-width='1.5'" << (s.dashed ? " stroke-dasharray='5,3'" : "") << "/>";
    // The entry drawn as the series is: a marker, a line or a dashed line.
    const int lx = w - legend_width + 10;
    if (s.points)
      o << "<circle cx='" << lx + 8 << "' cy='" << legend_y - 4 << "' r='3' fill='" << s.colour
        << "'/>";
    else
      o << "<line x1='" << lx << "' x2='" << lx + 16 << "' y1='" << legend_y - 4 << "' y2='"
        << legend_y - 4 << "' stroke='" << s.colour << "' stroke-width='2'"
        << (s.dashed ? " stroke-dasharray='4,2'" : "") << "/>";
    o << "<text x='" << lx + 22 << "' y='" << legend_y << "'>" << html_escape(s.label) << "</text>";
    legend_y += 14;
  }
  o << "</svg>";
  return o.str();
}

}  // namespace pyrocam::cli
