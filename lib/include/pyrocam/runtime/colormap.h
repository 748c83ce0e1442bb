// False-colour display of temperature images: palettes, a lookup table from the 16-bit
// temperature code (0.1 K, 0 = no reading) straight to 8-bit 4-channel pixels, a smoothed auto
// range, isotherm (alarm) colouring and a scale bar with labelled ticks in degC.
#pragma once

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace pyrocam {

enum class Palette { kIron, kInferno, kRainbow, kGrey };
Palette parse_palette(const std::string& name);  // "iron", "inferno", "rainbow", "grey"
std::string palette_name(Palette palette);

struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};
// 256 colours from cold (index 0) to hot (255).
const std::array<Rgb, 256>& palette_colors(Palette palette);

// Byte order of the 4-channel output pixels in memory.
enum class ChannelOrder { kRGBA, kBGRA };

// The narrowest temperature range a colour map accepts: one temperature code (0.1 K). A
// narrower range cannot tell two readings apart, and its scale-bar ticks would be steps below
// the resolution of a double.
constexpr double kMinColormapSpanC = 0.1;

struct ColormapSettings {
  Palette palette = Palette::kIron;
  double min_c = 500, max_c = 2500;  // mapped to the ends of the palette (clamped beyond)
  std::uint32_t invalid_argb = 0;    // colour of code 0 (no reading); 0 = transparent
  std::optional<double> isotherm_c;  // pixels at or above it get isotherm_argb
  std::uint32_t isotherm_argb = 0xFF00FF00u;
  ChannelOrder order = ChannelOrder::kRGBA;

  bool operator==(const ColormapSettings& o) const {
    return palette == o.palette && min_c == o.min_c && max_c == o.max_c &&
           invalid_argb == o.invalid_argb && isotherm_c == o.isotherm_c &&
           isotherm_argb == o.isotherm_argb && order == o.order;
  }
  bool operator!=(const ColormapSettings& o) const { return !(*this == o); }
};

// A 65536-entry table from temperature code to output pixel: mapping a frame is one load per
// pixel. Rebuilding (about 0.1 ms) happens only when the settings change.
class ThermalColormap {
 public:
  // Throws InputError unless min_c and max_c are finite and max_c - min_c >= kMinColormapSpanC.
  void configure(const ColormapSettings& settings);
  const ColormapSettings& settings() const { return settings_; }
  // decikelvin CV_16U -> out CV_8UC4 of the same size (allocated if it does not fit).
  void apply(const cv::Mat& decikelvin, cv::Mat& out) const;
  // The output pixel of one code, as bytes in memory order.
  std::array<std::uint8_t, 4> pixel(std::uint16_t code) const;

 private:
  ColormapSettings settings_;
  bool configured_ = false;
  std::vector<std::uint32_t> lut_;
};

// Bytes of an ARGB colour (0xAARRGGBB) in the given memory order, packed as a native uint32.
std::uint32_t pack_argb(std::uint32_t argb, ChannelOrder order);

// Lowest and highest valid (non-zero) temperature in degC; nullopt when no pixel is valid.
std::optional<std::pair<double, double>> valid_range_c(const cv::Mat& decikelvin);

// The valid range without its extremes: `trim_percent` (0..kMaxTrimPercent) of the valid
// readings cut at each end, so that a few wild pixels (mixed pixels at sharp edges) do not
// stretch an auto range; 0 = valid_range_c. With n readings and k = floor(n * trim / 100), the
// ends are the (k+1)-th lowest and highest codes: an object hotter than the rest that covers
// more than trim_percent of the readings still sets the top. One pass and a histogram of the
// 65536 codes. Throws InputError for a trim outside 0..kMaxTrimPercent or non-CV_16U input.
inline constexpr double kMaxTrimPercent = 10;
std::optional<std::pair<double, double>> trimmed_range_c(const cv::Mat& decikelvin,
                                                         double trim_percent);

// Auto range that does not flicker and never paints a reading as another temperature: it widens
// at once to take in a frame's range (a reading beyond an end would get that end's colour) and
// narrows as an exponential moving average of the frames' ranges, `weight` (0..1] being the
// share of the newest frame (1 = no smoothing). The range is kept at least min_span_c wide.
class AutoRange {
 public:
  void reset() { have_ = false; }
  // Updates with a frame's range (nullopt: no valid pixel, keeps the last range).
  void update(std::optional<std::pair<double, double>> frame_range, double weight);
  bool valid() const { return have_; }
  double min_c() const { return min_; }
  double max_c() const { return max_; }

  static constexpr double kMinSpanC = 1.0;

 private:
  bool have_ = false;
  double min_ = 0, max_ = 0;
};

// Tick values (degC) at a 1, 2 or 5 x 10^k step, about `target` of them within [min_c, max_c];
// never more than 2 * target + 2 (a range too narrow for its magnitude gives fewer or none).
std::vector<double> nice_ticks(double min_c, double max_c, int target = 5);

// Where a scale bar's parts go on an image of `image` size (empty bar: none drawn). Boxes are
// the text's extent above its baseline, as cv::getTextSize gives it.
struct ScaleBarLayout {
  struct Tick {
    std::string text;
    int y = 0;       // row of the tick mark
    cv::Rect label;  // its label, left of the bar
  };
  cv::Rect bar;   // the gradient
  cv::Rect unit;  // "degC", above the bar
  std::vector<Tick> ticks;
  int font = 0;  // cv::FONT_HERSHEY_SIMPLEX
  double font_scale = 0.5;
  int thickness = 1;
};
ScaleBarLayout scale_bar_layout(cv::Size image, double min_c, double max_c);

// Draws a vertical scale bar (palette gradient, hot at the top) with tick labels in degC at the
// right edge of a CV_8UC4 image; opaque, so it shows when overlaid. Too small an image (under
// 48 px high or 64 px wide) or a range narrower than kMinColormapSpanC (or not finite) gets none.
void draw_scale_bar(cv::Mat& image, Palette palette, double min_c, double max_c,
                    ChannelOrder order);

// The peak readout: "peak 2213 degC"; where light saturated the camera in the frame (parts
// without a reading that are hotter than what reads), "peak >= 2213 degC (saturated)", or
// "saturated, no reading" without a peak; "" without either (NaN: no peak). Where parts are
// hotter than the model's range, which ends at above_range_c (NaN: none are), "peak > 3500 degC
// (above range)" whatever reads. With the expanded systematic uncertainty of a reading at the peak
// (SystematicUncertaintyTable; NaN: not known), a peak that reads says it: "peak 2213 degC
// +/-38 sys".
std::string peak_label(double peak_c, bool saturated, double above_range_c = NAN,
                       double systematic_u_c = NAN);

// Marks the peak of a temperature image on its CV_8UC4 colouring: a ring around (x, y) and
// peak_label at the top left (outlined, legible on any background), so that a live view or a
// snapshot shows the object's peak and where it is. No ring for a peak at x or y < 0 or a NaN
// temperature, no label where peak_label is empty. With above_range_c, (x, y) is where the part
// hotter than the range is, and the ring goes there. Throws InputError for another image type.
void draw_peak_marker(cv::Mat& image, int x, int y, double peak_c, ChannelOrder order,
                      bool saturated = false, double above_range_c = NAN,
                      double systematic_u_c = NAN);

// Lays a colour map's CV_8UC4 output (straight alpha, bytes in `overlay_order`) over a CV_8UC4
// image of the same size in place (bytes in `image_order`): each colour byte becomes
// (overlay * alpha + image * (255 - alpha)) / 255, rounded to nearest; the image's fourth byte
// is kept. Throws InputError for other types or sizes.
void blend_overlay(const cv::Mat& overlay, ChannelOrder overlay_order, cv::Mat& image,
                   ChannelOrder image_order);

}  // namespace pyrocam
