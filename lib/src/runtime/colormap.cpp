#include "pyrocam/runtime/colormap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <iomanip>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/core/temperature_codes.h"

namespace pyrocam {
namespace {

struct Stop {
  double at;
  Rgb color;
};

std::array<Rgb, 256> interpolate(const std::vector<Stop>& stops) {
  std::array<Rgb, 256> table{};
  for (int i = 0; i < 256; ++i) {
    const double t = i / 255.0;
    std::size_t k = 1;
    while (k + 1 < stops.size() && stops[k].at < t) ++k;
    const Stop& a = stops[k - 1];
    const Stop& b = stops[k];
    const double f = std::clamp((t - a.at) / (b.at - a.at), 0.0, 1.0);
    auto mix = [f](std::uint8_t u, std::uint8_t v) {
      return static_cast<std::uint8_t>(std::lround(u + (v - u) * f));
    };
    table[static_cast<std::size_t>(i)] = {mix(a.color.r, b.color.r), mix(a.color.g, b.color.g),
                                          mix(a.color.b, b.color.b)};
  }
  return table;
}

std::array<Rgb, 256> make_palette(Palette palette) {
  switch (palette) {
    case Palette::kIron:  // "ironbow" of thermography
      return interpolate({{0.00, {0, 0, 0}},
                          {0.12, {30, 0, 95}},
                          {0.28, {100, 0, 155}},
                          {0.42, {175, 15, 130}},
                          {0.56, {225, 60, 50}},
                          {0.70, {248, 125, 0}},
                          {0.85, {255, 200, 30}},
                          {1.00, {255, 255, 230}}});
    case Palette::kInferno:  // matplotlib's inferno, sampled every 1/8
      return interpolate({{0.000, {0, 0, 4}},
                          {0.125, {31, 12, 72}},
                          {0.250, {85, 15, 109}},
                          {0.375, {136, 34, 106}},
                          {0.500, {186, 54, 85}},
                          {0.625, {227, 89, 51}},
                          {0.750, {249, 140, 10}},
                          {0.875, {249, 201, 50}},
                          {1.000, {252, 255, 164}}});
    case Palette::kRainbow:  // blue, cyan, green, yellow, red
      return interpolate({{0.00, {0, 0, 255}},
                          {0.25, {0, 255, 255}},
                          {0.50, {0, 255, 0}},
                          {0.75, {255, 255, 0}},
                          {1.00, {255, 0, 0}}});
    case Palette::kGrey:
      return interpolate({{0.0, {0, 0, 0}}, {1.0, {255, 255, 255}}});
  }
  throw InputError("unknown palette");
}

std::uint32_t pack_bytes(std::uint8_t r, std::uint8_t g, std::uint8_t b, std::uint8_t a,
                         ChannelOrder order) {
  const std::uint8_t bytes[4] = {order == ChannelOrder::kRGBA ? r : b, g,
                                 order == ChannelOrder::kRGBA ? b : r, a};
  std::uint32_t v;
  std::memcpy(&v, bytes, 4);
  return v;
}

std::string format_tick(double value, double step) {
  std::ostringstream s;
  const int decimals = step >= 1 || !(step > 0)
                           ? 0
                           : std::min(9, static_cast<int>(std::ceil(-std::log10(step) - 1e-9)));
  s << std::fixed << std::setprecision(decimals) << value;
  return s.str();
}

}  // namespace

Palette parse_palette(const std::string& name) {
  if (name == "iron") return Palette::kIron;
  if (name == "inferno") return Palette::kInferno;
  if (name == "rainbow") return Palette::kRainbow;
  if (name == "grey" || name == "gray") return Palette::kGrey;
  throw InputError("unknown palette '" + name + "' (use iron, inferno, rainbow or grey)");
}

std::string palette_name(Palette palette) {
  switch (palette) {
    case Palette::kIron:
      return "iron";
    case Palette::kInferno:
      return "inferno";
    case Palette::kRainbow:
      return "rainbow";
    case Palette::kGrey:
      return "grey";
  }
  return "?";
}

const std::array<Rgb, 256>& palette_colors(Palette palette) {
  static const std::array<std::array<Rgb, 256>, 4> tables = {
      make_palette(Palette::kIron), make_palette(Palette::kInferno),
      make_palette(Palette::kRainbow), make_palette(Palette::kGrey)};
  return tables[static_cast<std::size_t>(palette)];
}

std::uint32_t pack_argb(std::uint32_t argb, ChannelOrder order) {
  return pack_bytes(static_cast<std::uint8_t>(argb >> 16), static_cast<std::uint8_t>(argb >> 8),
                    static_cast<std::uint8_t>(argb), static_cast<std::uint8_t>(argb >> 24), order);
}

void ThermalColormap::configure(const ColormapSettings& s) {
  if (!(std::isfinite(s.min_c) && std::isfinite(s.max_c) && s.max_c - s.min_c >= kMinColormapSpanC))
    throw InputError("colour map: the temperature range " + std::to_string(s.min_c) + ".." +
                     std::to_string(s.max_c) + " degC is narrower than " +
                     std::to_string(kMinColormapSpanC) + " degC");
  if (configured_ && s == settings_) return;
  settings_ = s;
  configured_ = true;
  lut_.resize(65536);
  const auto& colors = palette_colors(s.palette);
  const std::uint32_t invalid = pack_argb(s.invalid_argb, s.order);
  const std::uint32_t isotherm = pack_argb(s.isotherm_argb, s.order);
  const double scale = 255.0 / (s.max_c - s.min_c);
  lut_[0] = invalid;
  for (std::uint32_t code = 1; code < 65536; ++code) {
    const double t = code_to_celsius(static_cast<std::uint16_t>(code));
    if (s.isotherm_c && t >= *s.isotherm_c) {
      lut_[code] = isotherm;
      continue;
    }
    const long index = std::clamp(std::lround((t - s.min_c) * scale), 0L, 255L);
    const Rgb& c = colors[static_cast<std::size_t>(index)];
    lut_[code] = pack_bytes(c.r, c.g, c.b, 255, s.order);
  }
}

void ThermalColormap::apply(const cv::Mat& decikelvin, cv::Mat& out) const {
  if (!configured_) throw InputError("colour map: not configured");
  if (decikelvin.type() != CV_16U) throw InputError("colour map: input must be CV_16U");
  out.create(decikelvin.size(), CV_8UC4);
  const std::uint32_t* lut = lut_.data();
  for (int y = 0; y < decikelvin.rows; ++y) {
    const std::uint16_t* in = decikelvin.ptr<std::uint16_t>(y);
    std::uint8_t* o = out.ptr<std::uint8_t>(y);
    for (int x = 0; x < decikelvin.cols; ++x) std::memcpy(o + 4 * x, &lut[in[x]], 4);
  }
}

std::array<std::uint8_t, 4> ThermalColormap::pixel(std::uint16_t code) const {
  if (!configured_) throw InputError("colour map: not configured");
  std::array<std::uint8_t, 4> bytes{};
  std::memcpy(bytes.data(), &lut_[code], 4);
  return bytes;
}

std::optional<std::pair<double, double>> valid_range_c(const cv::Mat& decikelvin) {
  if (decikelvin.type() != CV_16U) throw InputError("valid range: input must be CV_16U");
  std::uint16_t lo = 65535, hi = 0;
  for (int y = 0; y < decikelvin.rows; ++y) {
    const std::uint16_t* in = decikelvin.ptr<std::uint16_t>(y);
    for (int x = 0; x < decikelvin.cols; ++x) {
      const std::uint16_t v = in[x];
      // 0 (no reading) never lowers the minimum: map it to 65535 there.
      lo = std::min<std::uint16_t>(lo, static_cast<std::uint16_t>(v - 1));
      hi = std::max(hi, v);
    }
  }
  if (hi == 0) return std::nullopt;
  return std::make_pair(code_to_celsius(static_cast<std::uint16_t>(lo + 1)), code_to_celsius(hi));
}

std::optional<std::pair<double, double>> trimmed_range_c(const cv::Mat& decikelvin,
                                                         double trim_percent) {
  if (decikelvin.type() != CV_16U) throw InputError("trimmed range: input must be CV_16U");
  if (!(trim_percent >= 0 && trim_percent <= kMaxTrimPercent))
    throw InputError("trimmed range: trim must be 0.." + std::to_string(kMaxTrimPercent) +
                     " percent");
  if (trim_percent == 0) return valid_range_c(decikelvin);
  std::vector<std::uint32_t> histogram(65536, 0);
  for (int y = 0; y < decikelvin.rows; ++y) {
    const std::uint16_t* in = decikelvin.ptr<std::uint16_t>(y);
    for (int x = 0; x < decikelvin.cols; ++x) ++histogram[in[x]];
  }
  std::uint64_t n = 0;
  for (std::size_t c = 1; c < histogram.size(); ++c) n += histogram[c];
  if (n == 0) return std::nullopt;
  const auto k =
      static_cast<std::uint64_t>(std::floor(static_cast<double>(n) * trim_percent / 100));
  std::size_t lo = 1, hi = 65535;
  for (std::uint64_t below = 0;; ++lo) {  // the first code with more than k readings at or below
    below += histogram[lo];
    if (below > k) break;
  }
  for (std::uint64_t above = 0;; --hi) {
    above += histogram[hi];
    if (above > k) break;
  }
  return std::make_pair(code_to_celsius(static_cast<std::uint16_t>(lo)),
                        code_to_celsius(static_cast<std::uint16_t>(hi)));
}

void AutoRange::update(std::optional<std::pair<double, double>> frame_range, double weight) {
  if (frame_range) {
    const double w = std::clamp(weight, 1e-6, 1.0);
    if (!have_) {
      min_ = frame_range->first;
      max_ = frame_range->second;
      have_ = true;
    } else {
      // Widen at once: a reading outside the range would be painted as its end, a colour that
      // names another temperature. Narrow smoothly, so that the view does not flicker.
      min_ = std::min(min_ + w * (frame_range->first - min_), frame_range->first);
      max_ = std::max(max_ + w * (frame_range->second - max_), frame_range->second);
    }
  }
  if (have_ && max_ - min_ < kMinSpanC) {
    const double mid = 0.5 * (min_ + max_);
    min_ = mid - 0.5 * kMinSpanC;
    max_ = mid + 0.5 * kMinSpanC;
  }
}

std::vector<double> nice_ticks(double min_c, double max_c, int target) {
  std::vector<double> ticks;
  if (!(std::isfinite(min_c) && std::isfinite(max_c) && max_c > min_c) || target < 1) return ticks;
  const double raw = (max_c - min_c) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  // Ticks by index, not by adding step, so that a step below the resolution of the values
  // cannot stall the loop; and never more than the bound, however the rounding falls.
  const double first = std::ceil(min_c / step - 1e-9);
  const double last = std::floor(max_c / step + 1e-9);
  const int max_ticks = 2 * target + 2;
  for (int i = 0; i < max_ticks && first + i <= last; ++i) {
    const double v = (first + i) * step;
    ticks.push_back(std::abs(v) < 1e-9 * step ? 0.0 : v);
  }
  return ticks;
}

ScaleBarLayout scale_bar_layout(cv::Size image, double min_c, double max_c) {
  ScaleBarLayout l;
  if (image.height < 48 || image.width < 64 ||
      !(std::isfinite(min_c) && std::isfinite(max_c) && max_c - min_c >= kMinColormapSpanC))
    return l;
  l.font_scale = std::clamp(image.height / 700.0, 0.3, 0.8);
  int baseline = 0;
  const cv::Size unit = cv::getTextSize("degC", l.font, l.font_scale, l.thickness, &baseline);
  const int bar_w = std::max(6, image.width / 40);
  const int margin = std::max(4, image.height / 30);
  // The bar spans rows [top, bottom); the unit is written above it, right-aligned.
  const int top = margin + unit.height + 6, bottom = image.height - margin;
  const int right = image.width - margin, left = right - bar_w;
  l.bar = cv::Rect(left, top, bar_w, bottom - top);
  l.unit = cv::Rect(right - unit.width, top - 5 - unit.height, unit.width, unit.height);
  const int span = bottom - top;
  const auto ticks = nice_ticks(min_c, max_c, std::clamp(span / 40, 2, 8));
  const double step = ticks.size() > 1 ? ticks[1] - ticks[0] : 1.0;
  for (double t : ticks) {
    ScaleBarLayout::Tick tick;
    tick.text = format_tick(t, step);
    tick.y = bottom - 1 - static_cast<int>(std::lround((t - min_c) / (max_c - min_c) * (span - 1)));
    const cv::Size size = cv::getTextSize(tick.text, l.font, l.font_scale, l.thickness, &baseline);
    // Centred on its tick, but never up into the unit's row (a range ending on a tick) nor
    // below the image.
    const int base = std::clamp(tick.y + size.height / 2,
                                l.unit.y + l.unit.height + 3 + size.height, image.height - 1);
    tick.label = cv::Rect(left - 8 - size.width, base - size.height, size.width, size.height);
    l.ticks.push_back(tick);
  }
  return l;
}

void draw_scale_bar(cv::Mat& image, Palette palette, double min_c, double max_c,
                    ChannelOrder order) {
  if (image.type() != CV_8UC4) throw InputError("scale bar: image must be CV_8UC4");
  const ScaleBarLayout l = scale_bar_layout(image.size(), min_c, max_c);
  if (l.bar.empty()) return;
  const auto& colors = palette_colors(palette);
  auto scalar = [order](std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    return order == ChannelOrder::kRGBA ? cv::Scalar(r, g, b, 255) : cv::Scalar(b, g, r, 255);
  };
  const int top = l.bar.y, bottom = l.bar.y + l.bar.height;
  const int left = l.bar.x, right = l.bar.x + l.bar.width;
  for (int y = top; y < bottom; ++y) {
    const auto index = std::lround(255.0 * (bottom - 1 - y) / std::max(1, l.bar.height - 1));
    const Rgb& c = colors[static_cast<std::size_t>(index)];
    cv::line(image, {left, y}, {right - 1, y}, scalar(c.r, c.g, c.b));
  }
  cv::rectangle(image, {left - 1, top - 1}, {right, bottom}, scalar(255, 255, 255));
  auto label_at = [&](const std::string& text, const cv::Rect& box) {
    // A dark outline keeps the label legible on any background.
    const cv::Point at{box.x, box.y + box.height};
    cv::putText(image, text, at, l.font, l.font_scale, scalar(0, 0, 0), l.thickness + 2,
                cv::LINE_AA);
    cv::putText(image, text, at, l.font, l.font_scale, scalar(255, 255, 255), l.thickness,
                cv::LINE_AA);
  };
  label_at("degC", l.unit);
  for (const ScaleBarLayout::Tick& t : l.ticks) {
    cv::line(image, {left - 5, t.y}, {left - 1, t.y}, scalar(255, 255, 255));
    label_at(t.text, t.label);
  }
}

std::string peak_label(double peak_c, bool saturated, double above_range_c, double systematic_u_c) {
  char text[64];
  if (!std::isnan(above_range_c)) {
    std::snprintf(text, sizeof text, "peak > %.0f degC (above range)", above_range_c);
    return text;
  }
  if (std::isnan(peak_c)) return saturated ? "saturated, no reading" : "";
  if (saturated)
    std::snprintf(text, sizeof text, "peak >= %.0f degC (saturated)", peak_c);
  else if (std::isfinite(systematic_u_c) && systematic_u_c >= 0)
    std::snprintf(text, sizeof text, "peak %.0f degC +/-%.0f sys", peak_c, systematic_u_c);
  else
    std::snprintf(text, sizeof text, "peak %.0f degC", peak_c);
  return text;
}

void draw_peak_marker(cv::Mat& image, int x, int y, double peak_c, ChannelOrder order,
                      bool saturated, double above_range_c, double systematic_u_c) {
  if (image.type() != CV_8UC4) throw InputError("peak marker: image must be CV_8UC4");
  const bool found = x >= 0 && y >= 0 && !(std::isnan(peak_c) && std::isnan(above_range_c));
  const std::string text =
      peak_label(found ? peak_c : NAN, saturated, above_range_c, systematic_u_c);
  if (text.empty()) return;
  auto scalar = [order](std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    return order == ChannelOrder::kRGBA ? cv::Scalar(r, g, b, 255) : cv::Scalar(b, g, r, 255);
  };
  if (found) {
    const int radius = std::max(4, std::min(image.cols, image.rows) / 30);
    cv::circle(image, {x, y}, radius, scalar(0, 0, 0), 3, cv::LINE_AA);
    cv::circle(image, {x, y}, radius, scalar(0, 255, 255), 1, cv::LINE_AA);
  }
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  const double scale = 0.5;
  int baseline = 0;
  const cv::Size size = cv::getTextSize(text, font, scale, 1, &baseline);
  const cv::Point at{4, 4 + size.height};
  cv::putText(image, text, at, font, scale, scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(image, text, at, font, scale, scalar(255, 255, 255), 1, cv::LINE_AA);
}

void blend_overlay(const cv::Mat& overlay, ChannelOrder overlay_order, cv::Mat& image,
                   ChannelOrder image_order) {
  if (overlay.type() != CV_8UC4 || image.type() != CV_8UC4 || overlay.size() != image.size())
    throw InputError(
        "blend_overlay: the overlay and the image must be 4-channel 8-bit images "
        "of one size");
  // Byte of the image that receives overlay byte c (0..2); the alpha is byte 3 in both orders.
  const bool swap = overlay_order != image_order;
  const int to[3] = {swap ? 2 : 0, 1, swap ? 0 : 2};
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* o = overlay.ptr<std::uint8_t>(y);
    std::uint8_t* p = image.ptr<std::uint8_t>(y);
    for (int x = 0; x < image.cols; ++x, o += 4, p += 4) {
      const unsigned a = o[3];
      if (a == 0) continue;
      for (int c = 0; c < 3; ++c) {
        const unsigned v = o[c] * a + p[to[c]] * (255u - a);
        p[to[c]] = static_cast<std::uint8_t>((v + 127u) / 255u);
      }
    }
  }
}

}  // namespace pyrocam
