// False-colour mapping: palettes, lookup table, invalid and isotherm colours, auto range, ticks.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "pyrocam/core/error.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/colormap.h"

namespace pyrocam {
namespace {

std::uint16_t code_of(double t_c) {
  return static_cast<std::uint16_t>(std::lround((t_c + 273.15) * 10));
}

TEST(Colormap, palettes_run_from_dark_to_bright) {
  for (Palette p : {Palette::kIron, Palette::kInferno, Palette::kGrey}) {
    const auto& c = palette_colors(p);
    EXPECT_LT(c[0].r + c[0].g + c[0].b, 30) << palette_name(p);
    EXPECT_GT(c[255].r + c[255].g + c[255].b, 600) << palette_name(p);
    EXPECT_EQ(parse_palette(palette_name(p)), p);
  }
  EXPECT_EQ(palette_colors(Palette::kRainbow)[0].b, 255);
  EXPECT_EQ(palette_colors(Palette::kRainbow)[255].r, 255);
  EXPECT_THROW(parse_palette("jet"), InputError);
}

TEST(Colormap, maps_range_ends_invalid_and_isotherm) {
  ThermalColormap map;
  ColormapSettings s;
  s.palette = Palette::kGrey;
  s.min_c = 1000;
  s.max_c = 2000;
  s.order = ChannelOrder::kBGRA;
  s.invalid_argb = 0x80102030;
  map.configure(s);
  cv::Mat in = (cv::Mat_<std::uint16_t>(1, 4) << 0, code_of(900), code_of(1500), code_of(2500));
  cv::Mat out;
  map.apply(in, out);
  ASSERT_EQ(out.type(), CV_8UC4);
  const auto px = [&](int x) { return out.at<cv::Vec4b>(0, x); };
  EXPECT_EQ(px(0), cv::Vec4b(0x30, 0x20, 0x10, 0x80));  // B G R A of 0x80102030
  EXPECT_EQ(px(1), cv::Vec4b(0, 0, 0, 255));
  EXPECT_NEAR(px(2)[0], 128, 1);
  EXPECT_EQ(px(3), cv::Vec4b(255, 255, 255, 255));
  s.isotherm_c = 1400;
  s.isotherm_argb = 0xFFFF0000;  // red
  map.configure(s);
  map.apply(in, out);
  EXPECT_EQ(px(2), cv::Vec4b(0, 0, 255, 255));
  EXPECT_EQ(px(1), cv::Vec4b(0, 0, 0, 255));
  EXPECT_EQ(map.pixel(0)[3], 0x80);
  s.min_c = s.max_c;
  EXPECT_THROW(map.configure(s), InputError);
}

TEST(Colormap, default_invalid_colour_is_transparent) {
  ThermalColormap map;
  map.configure({});
  EXPECT_EQ(map.pixel(0), (std::array<std::uint8_t, 4>{0, 0, 0, 0}));
  EXPECT_EQ(map.pixel(code_of(1500))[3], 255);
}

TEST(Colormap, valid_range_skips_no_reading) {
  cv::Mat in = (cv::Mat_<std::uint16_t>(2, 2) << 0, code_of(1200), code_of(800), 0);
  const auto r = valid_range_c(in);
  ASSERT_TRUE(r);
  EXPECT_NEAR(r->first, 800, 0.06);
  EXPECT_NEAR(r->second, 1200, 0.06);
  EXPECT_FALSE(valid_range_c(cv::Mat(2, 2, CV_16U, cv::Scalar(0))));
}

TEST(Colormap, auto_range_widens_at_once_narrows_smoothly_and_keeps_a_span) {
  AutoRange r;
  r.update(std::make_pair(1000.0, 2000.0), 0.5);
  EXPECT_EQ(r.min_c(), 1000);
  // Hotter: the top takes in the new maximum at once, the bottom rises half way.
  r.update(std::make_pair(1200.0, 2200.0), 0.5);
  EXPECT_EQ(r.min_c(), 1100);
  EXPECT_EQ(r.max_c(), 2200);
  r.update(std::nullopt, 0.5);
  EXPECT_EQ(r.max_c(), 2200);
  // Cooler: the bottom at once, the top half way down.
  r.update(std::make_pair(900.0, 1800.0), 0.5);
  EXPECT_EQ(r.min_c(), 900);
  EXPECT_EQ(r.max_c(), 2000);
  AutoRange flat;
  flat.update(std::make_pair(1500.0, 1500.0), 1);
  EXPECT_DOUBLE_EQ(flat.max_c() - flat.min_c(), AutoRange::kMinSpanC);
}

TEST(Colormap, nice_ticks) {
  EXPECT_EQ(nice_ticks(500, 2500, 5), (std::vector<double>{500, 1000, 1500, 2000, 2500}));
  EXPECT_EQ(nice_ticks(1013, 1087, 4), (std::vector<double>{1020, 1040, 1060, 1080}));
  EXPECT_TRUE(nice_ticks(5, 5).empty());
}

TEST(Colormap, nice_ticks_of_a_range_below_the_resolution_stay_bounded_n) {
  // One ulp above 1000: adding the step to 1000 does not change it, so a loop by addition
  // never ends.
  const double hi = std::nextafter(1000.0, 2000.0);
  EXPECT_LE(nice_ticks(1000, hi, 8).size(), 18u);
  EXPECT_LE(nice_ticks(1e300, std::nextafter(1e300, 2e300), 5).size(), 12u);
  EXPECT_TRUE(nice_ticks(0, std::numeric_limits<double>::infinity()).empty());
  EXPECT_TRUE(nice_ticks(std::nan(""), 1).empty());
  for (int target = 1; target <= 8; ++target)
    EXPECT_LE(nice_ticks(-273.15, 10000, target).size(), 2u * target + 2u) << target;
}

TEST(Colormap, rejects_a_range_narrower_than_one_code) {
  ThermalColormap map;
  ColormapSettings s;
  s.min_c = 1000;
  s.max_c = std::nextafter(1000.0, 2000.0);
  EXPECT_THROW(map.configure(s), InputError);
  s.max_c = 1000 + kMinColormapSpanC / 2;
  EXPECT_THROW(map.configure(s), InputError);
  s.max_c = 1000 + kMinColormapSpanC;
  EXPECT_NO_THROW(map.configure(s));
  // The scale bar of a degenerate range is left out, not drawn forever.
  cv::Mat img(240, 320, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  draw_scale_bar(img, Palette::kIron, 1000, std::nextafter(1000.0, 2000.0), ChannelOrder::kRGBA);
  EXPECT_EQ(cv::countNonZero(img.reshape(1)), 0);
  draw_scale_bar(img, Palette::kIron, 1000, 1000.1, ChannelOrder::kRGBA);
  EXPECT_GT(cv::countNonZero(img.reshape(1)), 0);
}

TEST(Colormap, scale_bar_is_drawn_opaque_at_the_right_edge) {
  cv::Mat img(240, 320, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  draw_scale_bar(img, Palette::kIron, 1000, 2000, ChannelOrder::kRGBA);
  // The bar's hot end is bright and opaque; the left half of the image is untouched.
  int opaque_right = 0;
  for (int y = 0; y < 240; ++y)
    for (int x = 0; x < 320; ++x) {
      const auto& p = img.at<cv::Vec4b>(y, x);
      if (x < 160) {
        ASSERT_EQ(p[3], 0) << x << "," << y;
      }
      if (x >= 300 && p[3] == 255) ++opaque_right;
    }
  EXPECT_GT(opaque_right, 1000);
  cv::Mat tiny(20, 20, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  draw_scale_bar(tiny, Palette::kIron, 1000, 2000, ChannelOrder::kRGBA);
  EXPECT_EQ(cv::countNonZero(tiny.reshape(1)), 0);
}

TEST(Colormap, scale_bar_labels_keep_clear_of_the_unit_and_each_other) {
  // Ranges ending on a tick put the top label at the bar's top, right under "degC".
  for (const cv::Size size : {cv::Size(320, 240), cv::Size(640, 480), cv::Size(1920, 1080)})
    for (const auto& [lo, hi] :
         {std::pair{500.0, 2500.0}, std::pair{1000.0, 2000.0}, std::pair{1013.0, 1087.0}}) {
      SCOPED_TRACE(std::to_string(size.width) + "x" + std::to_string(size.height) + " " +
                   std::to_string(lo) + "-" + std::to_string(hi));
      const ScaleBarLayout l = scale_bar_layout(size, lo, hi);
      ASSERT_FALSE(l.bar.empty());
      ASSERT_GE(l.ticks.size(), 2u);
      for (std::size_t i = 0; i < l.ticks.size(); ++i) {
        EXPECT_TRUE((l.ticks[i].label & l.unit).empty()) << l.ticks[i].text;
        EXPECT_GE(l.ticks[i].label.y, 0);
        EXPECT_LE(l.ticks[i].label.y + l.ticks[i].label.height, size.height);
        for (std::size_t j = i + 1; j < l.ticks.size(); ++j)
          EXPECT_TRUE((l.ticks[i].label & l.ticks[j].label).empty())
              << l.ticks[i].text << " " << l.ticks[j].text;
      }
    }
  EXPECT_TRUE(scale_bar_layout(cv::Size(20, 20), 500, 2500).bar.empty());
}

// Codes of a plate at 730..740 degC over a w x h frame, the top rows without a reading.
cv::Mat plate_codes(int w, int h) {
  cv::Mat codes(h, w, CV_16U, cv::Scalar(0));
  for (int y = 2; y < h; ++y)
    for (int x = 0; x < w; ++x)
      codes.at<std::uint16_t>(y, x) = temperature_code(730.0 + 10.0 * x / (w - 1));
  return codes;
}

TEST(Colormap, trimmed_range_ignores_a_few_wild_pixels) {
  cv::Mat codes = plate_codes(200, 102);  // 20000 readings
  for (int i = 0; i < 20; ++i) {          // 0.1 %: mixed pixels at 3000 and 300 degC
    codes.at<std::uint16_t>(10 + i, 7 * i) = temperature_code(3000);
    codes.at<std::uint16_t>(50 + i, 7 * i) = temperature_code(300);
  }
  const auto raw = valid_range_c(codes);
  ASSERT_TRUE(raw);
  EXPECT_NEAR(raw->second, 3000, 0.1);
  const auto trimmed = trimmed_range_c(codes, 0.5);
  ASSERT_TRUE(trimmed);
  EXPECT_NEAR(trimmed->first, 730, 0.2);
  EXPECT_NEAR(trimmed->second, 740, 0.2);
  // The auto range follows the plate, not the outliers.
  AutoRange range;
  for (int frame = 0; frame < 30; ++frame) range.update(trimmed_range_c(codes, 0.5), 0.1);
  EXPECT_NEAR(range.min_c(), 730, 0.3);
  EXPECT_NEAR(range.max_c(), 740, 0.3);
  // 0: the valid range itself; no reading: none; trims beyond 0..10 % are refused.
  EXPECT_EQ(trimmed_range_c(codes, 0), raw);
  EXPECT_FALSE(trimmed_range_c(cv::Mat(4, 4, CV_16U, cv::Scalar(0)), 0.5));
  EXPECT_THROW(trimmed_range_c(codes, -1), InputError);
  EXPECT_THROW(trimmed_range_c(codes, 10.5), InputError);
  EXPECT_THROW(trimmed_range_c(cv::Mat(4, 4, CV_32F), 0.5), InputError);
}

TEST(Colormap, trimmed_range_keeps_a_melt_pool_of_one_percent_at_the_top) {
  cv::Mat codes = plate_codes(200, 102);
  // A melt pool of 200 readings (1 % of them, fewer of the frame) at 1700..1900 degC.
  for (int i = 0; i < 200; ++i)
    codes.at<std::uint16_t>(40 + i / 20, 90 + i % 20) = temperature_code(1700.0 + i);
  const auto r = trimmed_range_c(codes, 0.5);
  ASSERT_TRUE(r);
  // The hottest 0.5 % are trimmed: the top lies in the pool, at its median.
  EXPECT_GE(r->second, 1700);
  EXPECT_NEAR(r->second, 1800, 1);
  EXPECT_NEAR(r->first, 730, 0.2);
  // With the most trim allowed, a pool of over 10 % still sets it.
  cv::Mat big = plate_codes(20, 12);  // 200 readings, 21 of them in the pool
  for (int x = 0; x < 20; ++x) big.at<std::uint16_t>(11, x) = temperature_code(1800);
  big.at<std::uint16_t>(10, 0) = temperature_code(1800);
  EXPECT_NEAR(trimmed_range_c(big, 10)->second, 1800, 0.1);
}

}  // namespace
}  // namespace pyrocam

namespace pyrocam {
namespace {

TEST(PeakMarker, RingsThePeakAndLabelsItOrDrawsNothingWithoutOne) {
  cv::Mat image(120, 160, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  draw_peak_marker(image, -1, -1, NAN, ChannelOrder::kRGBA);
  EXPECT_EQ(cv::countNonZero(image.reshape(1)), 0);
  draw_peak_marker(image, 100, 80, 2213.4, ChannelOrder::kRGBA);
  // The ring: opaque pixels around (100, 80) but not at its centre; the label at the top left.
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  const cv::Mat& alpha = channels[3];
  EXPECT_GT(cv::countNonZero(alpha(cv::Rect(90, 70, 21, 21))), 10);
  EXPECT_EQ(alpha.at<std::uint8_t>(80, 100), 0);
  EXPECT_GT(cv::countNonZero(alpha(cv::Rect(0, 0, 130, 20))), 50);
  EXPECT_EQ(cv::countNonZero(alpha(cv::Rect(0, 30, 80, 40))), 0);  // nothing elsewhere
  cv::Mat grey(8, 8, CV_8U, cv::Scalar(0));
  EXPECT_THROW(draw_peak_marker(grey, 1, 1, 1000, ChannelOrder::kRGBA), InputError);
}

// Where light saturated the camera, the readout says the peak is a lower bound, and says so
// without a peak too (nothing read).
TEST(PeakMarker, SaysWhenThePeakIsALowerBound) {
  EXPECT_EQ(peak_label(2213.4, false), "peak 2213 degC");
  EXPECT_EQ(peak_label(2213.4, false, NAN, 37.6), "peak 2213 degC +/-38 sys");
  EXPECT_EQ(peak_label(2213.4, true, NAN, 37.6), "peak >= 2213 degC (saturated)");  // a bound
  EXPECT_EQ(peak_label(2213.4, false, 3500, 37.6), "peak > 3500 degC (above range)");
  EXPECT_EQ(peak_label(NAN, false, NAN, 37.6), "");
  EXPECT_EQ(peak_label(2213.4, true), "peak >= 2213 degC (saturated)");
  EXPECT_EQ(peak_label(NAN, true), "saturated, no reading");
  EXPECT_EQ(peak_label(NAN, false), "");
  // Hotter than the model's range: the range's end, whatever reads.
  EXPECT_EQ(peak_label(2213.4, false, 3500), "peak > 3500 degC (above range)");
  EXPECT_EQ(peak_label(NAN, true, 2000), "peak > 2000 degC (above range)");
  cv::Mat image(120, 160, CV_8UC4, cv::Scalar(0, 0, 0, 0));
  draw_peak_marker(image, -1, -1, NAN, ChannelOrder::kRGBA, true);
  std::vector<cv::Mat> channels;
  cv::split(image, channels);
  EXPECT_GT(cv::countNonZero(channels[3](cv::Rect(0, 0, 160, 20))), 50);  // the label
  EXPECT_EQ(cv::countNonZero(channels[3](cv::Rect(0, 30, 160, 90))), 0);  // no ring
  // Nothing reads, but a part is hotter than the range: label and ring there.
  image.setTo(cv::Scalar::all(0));
  draw_peak_marker(image, 100, 80, NAN, ChannelOrder::kRGBA, false, 3500);
  cv::split(image, channels);
  EXPECT_GT(cv::countNonZero(channels[3](cv::Rect(0, 0, 160, 20))), 50);
  EXPECT_GT(cv::countNonZero(channels[3](cv::Rect(90, 70, 21, 21))), 10);
}

// Opaque overlay pixels replace the image's colour, transparent ones leave it, partial ones mix
// in proportion to alpha (rounded to nearest); a BGRx image gets the overlay's channels swapped,
// and its fourth byte is kept.
TEST(BlendOverlay, MixesByAlphaInEitherChannelOrder) {
  cv::Mat overlay(1, 3, CV_8UC4), image(1, 3, CV_8UC4, cv::Scalar(10, 20, 30, 77));
  overlay.at<cv::Vec4b>(0, 0) = {200, 100, 50, 255};
  overlay.at<cv::Vec4b>(0, 1) = {200, 100, 50, 0};
  overlay.at<cv::Vec4b>(0, 2) = {200, 100, 50, 128};
  cv::Mat rgba = image.clone(), bgra = image.clone();
  blend_overlay(overlay, ChannelOrder::kRGBA, rgba, ChannelOrder::kRGBA);
  EXPECT_EQ(rgba.at<cv::Vec4b>(0, 0), cv::Vec4b(200, 100, 50, 77));
  EXPECT_EQ(rgba.at<cv::Vec4b>(0, 1), cv::Vec4b(10, 20, 30, 77));
  // (200 * 128 + 10 * 127) / 255 = 105.38; (100 * 128 + 20 * 127) / 255 = 60.16;
  // (50 * 128 + 30 * 127) / 255 = 40.04
  EXPECT_EQ(rgba.at<cv::Vec4b>(0, 2), cv::Vec4b(105, 60, 40, 77));
  blend_overlay(overlay, ChannelOrder::kRGBA, bgra, ChannelOrder::kBGRA);
  EXPECT_EQ(bgra.at<cv::Vec4b>(0, 0), cv::Vec4b(50, 100, 200, 77));
  // (50 * 128 + 10 * 127) / 255 = 30.08; (200 * 128 + 30 * 127) / 255 = 115.34
  EXPECT_EQ(bgra.at<cv::Vec4b>(0, 2), cv::Vec4b(30, 60, 115, 77));
  cv::Mat small(1, 2, CV_8UC4);
  EXPECT_THROW(blend_overlay(overlay, ChannelOrder::kRGBA, small, ChannelOrder::kRGBA), InputError);
}

}  // namespace
}  // namespace pyrocam
