// ratiotemp's statistics: the message against region_stats of the frame, the peak (the hot
// spot, not a wild pixel), the region that tracks it and a peak window larger than the frame.
#include <algorithm>

#include "pyrocam/runtime/region_stats.h"
#include "pyrocam/runtime/uncertainty.h"
#include "ratiotemp_support.h"

namespace pyrocam::test {
namespace {

guint64 field_uint64(const GstStructure* s, const char* name) {
  guint64 v = 0;
  EXPECT_TRUE(gst_structure_get_uint64(s, name, &v)) << name;
  return v;
}

void expect_stats(const GstStructure* s, const std::string& prefix, const RegionStats& r) {
  SCOPED_TRACE(prefix);
  EXPECT_EQ(field_uint64(s, (prefix + "pixels").c_str()), r.pixels);
  EXPECT_EQ(field_uint64(s, (prefix + "valid").c_str()), r.valid);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "valid-fraction").c_str()), r.valid_fraction);
  if (r.valid == 0) {
    EXPECT_FALSE(gst_structure_has_field(s, (prefix + "median-c").c_str()));
    return;
  }
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "min-c").c_str()), r.min_c);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "max-c").c_str()), r.max_c);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "mean-c").c_str()), r.mean_c);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "median-c").c_str()), r.median_c);
}

TEST_F(RatioTemp, stats_message_matches_region_stats_of_the_frame) {
  start("ratiotemp stats-interval=1000000000 region=4,2,10,10 model=" + rgb_model_path(),
        bands_caps(3, "bayer", 7, 5));
  auto planes = graybody_planes(*rgb_model(), 7, 5, 900, 1700);
  for (int b = 0; b < 3; ++b) {  // two pixels without a reading, whatever the method
    planes[b * 35 + 0] = kInf;
    planes[b * 35 + 33] = NAN;
  }
  std::vector<float> dark(planes.size(), 1.0f);  // every band dim: no reading anywhere
  // Frames at 0, 0.5, 1.0 and 1.2 s: the first and the third post.
  run(planes, 7, 5, 0);
  run(planes, 7, 5, GST_SECOND / 2);
  run(planes, 7, 5, GST_SECOND);
  run(dark, 7, 5, GST_SECOND + GST_SECOND / 5);
  auto s = stats();
  ASSERT_EQ(s.size(), 2u);
  const cv::Mat t = library(rgb_model(), rgb_auto_method(), planes, 7, 5).t;
  const cv::Rect region(4, 2, 3, 3);  // clipped to the 7x5 frame
  for (std::size_t k = 0; k < 2; ++k) {
    const GstStructure* m = s[k];
    EXPECT_EQ(field_uint64(m, "timestamp"), k * GST_SECOND);
    EXPECT_EQ(field_uint64(m, "running-time"), k * GST_SECOND);
    EXPECT_EQ(field_uint64(m, "stream-time"), k * GST_SECOND);
    EXPECT_EQ(gst_structure_get_string(m, "method"), method_name(rgb_auto_method()));
    int v = 0;
    EXPECT_TRUE(gst_structure_get_int(m, "width", &v) && v == 7);
    EXPECT_TRUE(gst_structure_get_int(m, "height", &v) && v == 5);
    EXPECT_TRUE(gst_structure_get_int(m, "region-x", &v) && v == 4);
    EXPECT_TRUE(gst_structure_get_int(m, "region-y", &v) && v == 2);
    EXPECT_TRUE(gst_structure_get_int(m, "region-width", &v) && v == 3);
    EXPECT_TRUE(gst_structure_get_int(m, "region-height", &v) && v == 3);
    const RegionStats frame = region_stats(t);
    EXPECT_EQ(frame.valid, 33u);
    expect_stats(m, "", frame);
    const RegionStats reg = region_stats(t(region));
    EXPECT_EQ(reg.pixels, 9u);
    EXPECT_EQ(reg.valid, 8u);
    expect_stats(m, "region-", reg);
    // The median is reported apart from the mean.
    EXPECT_NE(field_double(m, "median-c"), field_double(m, "mean-c"));
    // Of the two pixels without a reading, (0, 0) saturated (+INF); (5, 4)'s NaN lies more than
    // 2 pixels from any saturated pixel (a mixed pixel's mark, not light that saturated).
    EXPECT_EQ(field_uint64(m, "saturated"), 1u);
    EXPECT_EQ(field_uint64(m, "region-saturated"), 0u);  // (0, 0) is outside
  }
  free_all(s);
  // A frame without any reading: counts, fraction 0, no temperatures.
  g_object_set(element, "stats-interval", G_GUINT64_CONSTANT(1), nullptr);
  run(dark, 7, 5, 3 * GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  expect_stats(s[0], "", region_stats(cv::Mat(5, 7, CV_32F, cv::Scalar(NAN))));
  EXPECT_EQ(field_uint64(s[0], "pixels"), 35u);
  EXPECT_FALSE(gst_structure_has_field(s[0], "min-c"));
  EXPECT_EQ(field_uint64(s[0], "saturated"), 0u);  // dim, not saturated
  free_all(s);
}

// A saturated sample through darksub and demosaic25: the statistics count the pixels it left
// without a reading (its kernels' reach: 3x3 bilinear, 5x5 matched, which ratiotemp demosaics
// itself), not the dim corner's; a warning says so once, and again after a frame without.
class SaturatedStats : public RatioTemp {
 protected:
  void check(const std::string& demosaic, int radius) {
    for (const char* e : {"darksub", "demosaic25"}) REQUIRE_ELEMENT(e);
    start_on_raw_frames("ratiotemp stats-interval=1 model=" + rgb_model_path(), demosaic);
    const auto plain = raw_bayer_frame(*rgb_model(), 1300);
    auto raw = plain;
    raw[4 * 8 + 4] = 255;  // an R pixel, saturated
    const auto out = run(raw, 8, 8, 0);
    ASSERT_EQ(out.size(), 64u);
    std::size_t near = 0, none = 0;
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x) {
        none += out[y * 8 + x] == 0;
        near += out[y * 8 + x] == 0 && std::abs(x - 4) <= radius && std::abs(y - 4) <= radius;
      }
    EXPECT_EQ(out[4 * 8 + 4], 0);
    EXPECT_GT(none, near);  // the dim corner too
    auto s = stats();
    ASSERT_EQ(s.size(), 1u);
    EXPECT_EQ(field_uint64(s[0], "saturated"), near);
    free_all(s);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("saturated"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("lower bound"), std::string::npos) << warnings[0];
    run(raw, 8, 8, GST_SECOND);  // still saturated: no second warning
    run(plain, 8, 8, 2 * GST_SECOND);
    s = stats();
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(field_uint64(s[1], "saturated"), 0u);
    free_all(s);
    EXPECT_EQ(warnings.size(), 1u);
    run(raw, 8, 8, 3 * GST_SECOND);  // saturated again: warned again
    s = stats();
    free_all(s);
    EXPECT_EQ(warnings.size(), 2u);
  }
};

TEST_F(SaturatedStats, bilinear_planes) { check("demosaic25 method=bilinear", 1); }
TEST_F(SaturatedStats, matched_on_the_fused_path) { check("demosaic25", 2); }

// While darksub captures a dark its frames have no image (NaN, flagged GAP): ratiotemp gives them
// no reading and no statistics, and does not call them saturated (it did: every pixel, with
// advice to shorten the exposure); its output keeps the GAP flag (it dropped it: a recording or
// thermalfuse took the empty frame for one without readings). The frames after the capture are
// measured as usual.
class DarkCaptureStats : public RatioTemp {
 protected:
  void check(const std::string& demosaic) {
    for (const char* e : {"darksub", "demosaic25"}) REQUIRE_ELEMENT(e);
    start_on_raw_frames("ratiotemp stats-interval=1 model=" + rgb_model_path(), demosaic);
    GstElement* darksub = find_element(h, "darksub");
    g_object_set(darksub, "capture-frames", 2, nullptr);
    g_signal_emit_by_name(darksub, "capture-dark");
    gst_object_unref(darksub);
    const std::vector<std::uint8_t> capped(64, 50);
    for (int k = 0; k < 2; ++k) {
      const auto out = run(capped, 8, 8, k * GST_SECOND);
      ASSERT_EQ(out.size(), 64u);
      EXPECT_EQ(std::count(out.begin(), out.end(), 0), 64) << "a capture frame read";
      EXPECT_TRUE(last_gap) << "a capture frame lost its GAP flag";
    }
    auto s = stats();
    EXPECT_TRUE(s.empty()) << "statistics of a capture frame";
    free_all(s);
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    run(raw_bayer_frame(*rgb_model(), 1300), 8, 8, 2 * GST_SECOND);
    EXPECT_FALSE(last_gap);
    s = stats();
    ASSERT_EQ(s.size(), 1u);
    EXPECT_EQ(field_uint64(s[0], "saturated"), 0u);
    EXPECT_GT(field_uint64(s[0], "valid"), 0u);
    free_all(s);
  }
};

TEST_F(DarkCaptureStats, bilinear_planes) { check("demosaic25 method=bilinear"); }
TEST_F(DarkCaptureStats, matched_on_the_fused_path) { check("demosaic25"); }

// A part hotter than the model's range (3500 degC) has no reading, like a cold one; the
// statistics count it (the 6x6 square at 3800 degC, less its corners, whose 3x3 neighbourhoods
// hold only 4 of its pixels), a warning says so once per appearance, and every output frame
// carries the count in its PyrocamAboveRangeMeta, 0 without any. On every method.
class AboveRangeStats : public RatioTemp {
 protected:
  static constexpr int kW = 12, kH = 10;
  // A 6x6 square at hot_c whose corner is (3, 2), 1500 degC around it.
  static std::vector<float> planes_of(double hot_c) {
    const ThermalModel& m = *rgb_model();
    std::vector<float> v(3 * kW * kH);
    for (int y = 0; y < kH; ++y)
      for (int x = 0; x < kW; ++x) {
        const bool hot = x >= 3 && x < 9 && y >= 2 && y < 8;
        const Eigen::VectorXd r = m.camera.rates(hot ? hot_c : 1500);
        for (int b = 0; b < 3; ++b) v[(b * kH + y) * kW + x] = 150 * r[b] / r.maxCoeff();
      }
    return v;
  }
  void check(const std::string& method) {
    start(
        "ratiotemp stats-interval=1 region=0,0,5,5 method=" + method + " model=" + rgb_model_path(),
        bands_caps(3, "bayer", kW, kH));
    const auto out = run(planes_of(3800), kW, kH, 0);
    ASSERT_EQ(out.size(), static_cast<std::size_t>(kW * kH));
    EXPECT_EQ(std::count(out.begin(), out.end(), 0), 36);  // the square: no reading
    EXPECT_EQ(last_above_range, 32u);
    auto s = stats();
    ASSERT_EQ(s.size(), 1u);
    EXPECT_EQ(field_uint64(s[0], "above-range"), 32u);
    // (4, 2), (3, 3), (4, 3), (3, 4), (4, 4): the square's corner (3, 2) is not one
    EXPECT_EQ(field_uint64(s[0], "region-above-range"), 5u);
    free_all(s);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("hotter than the model's range (up to 3500 degC)"),
              std::string::npos)
        << warnings[0];
    run(planes_of(3800), kW, kH, 1);  // still there: no second warning
    run(planes_of(2000), kW, kH, 2);
    EXPECT_EQ(last_above_range, 0u);
    s = stats();
    ASSERT_EQ(s.size(), 2u);
    EXPECT_EQ(field_uint64(s[1], "above-range"), 0u);
    free_all(s);
    EXPECT_EQ(warnings.size(), 1u);
    run(planes_of(3800), kW, kH, 3);  // back: warned again
    s = stats();
    free_all(s);
    EXPECT_EQ(warnings.size(), 2u);
  }
};

TEST_F(AboveRangeStats, auto_method) { check("auto"); }
TEST_F(AboveRangeStats, likelihood) { check("likelihood"); }
TEST_F(AboveRangeStats, mlp) { check("mlp"); }

// The model, output and table-cache can change only in NULL or READY: set while playing, the
// change is refused on the bus (it was only in the debug log, and an application never learnt
// it) and readings go on with the model in use.
TEST_F(RatioTemp, a_model_set_while_playing_is_refused_on_the_bus) {
  start("ratiotemp model=" + rgb_model_path(), bands_caps(3, "bayer", 4, 4));
  const auto planes = graybody_planes(*rgb_model(), 4, 4, 1000, 1400);
  const auto expected = library_codes(rgb_model(), rgb_auto_method(), planes, 4, 4);
  EXPECT_EQ(run(planes, 4, 4, 0), expected);
  g_object_set(element, "model", nir_model_path().c_str(), nullptr);
  auto collected = stats();  // collects the warnings
  free_all(collected);
  ASSERT_EQ(warnings.size(), 1u);
  for (const char* part : {"model", "NULL or READY", "ignored"})
    EXPECT_NE(warnings[0].find(part), std::string::npos) << warnings[0];
  gchar* model = nullptr;
  g_object_get(element, "model", &model, nullptr);
  EXPECT_EQ(std::string(model), rgb_model_path());
  g_free(model);
  EXPECT_EQ(run(planes, 4, 4, GST_SECOND), expected);
}

// An even peak-window set while playing is refused on the bus, the value in use staying (it was
// only in the debug log); region-tracks-peak without a region is said once.
TEST_F(RatioTemp, values_refused_while_playing_are_said_on_the_bus) {
  start("ratiotemp model=" + rgb_model_path(), bands_caps(3, "bayer", 4, 4));
  const auto planes = graybody_planes(*rgb_model(), 4, 4, 1000, 1400);
  const auto expected = library_codes(rgb_model(), rgb_auto_method(), planes, 4, 4);
  EXPECT_EQ(run(planes, 4, 4, 0), expected);
  g_object_set(element, "peak-window", 4u, "region-tracks-peak", TRUE, nullptr);
  EXPECT_EQ(run(planes, 4, 4, GST_SECOND), expected);
  auto collected = stats();  // collects the warnings
  free_all(collected);
  guint window = 0;
  g_object_get(element, "peak-window", &window, nullptr);
  EXPECT_EQ(window, 5u);
  const auto count = [&](const std::string& part) {
    return std::count_if(warnings.begin(), warnings.end(),
                         [&](const std::string& w) { return w.find(part) != std::string::npos; });
  };
  EXPECT_EQ(count("peak-window 4 is even (a window needs a centre pixel); the value in use "
                  "stays 5"),
            1);
  EXPECT_EQ(count("region-tracks-peak needs a region"), 1);
  EXPECT_EQ(warnings.size(), 2u);
}

TEST_F(RatioTemp, survives_flush_and_eos) {
  start("ratiotemp model=" + rgb_model_path(), bands_caps(3, "bayer", 4, 4));
  const auto planes = graybody_planes(*rgb_model(), 4, 4, 1000, 1400);
  const auto expected = library_codes(rgb_model(), rgb_auto_method(), planes, 4, 4);
  EXPECT_EQ(run(planes, 4, 4, 0), expected);
  EXPECT_EQ(run(planes, 4, 4, GST_SECOND / 10), expected);
  auto s = stats();
  EXPECT_EQ(s.size(), 1u);  // the second frame is within the 1 s default interval
  free_all(s);
  push_flush(h);
  EXPECT_EQ(run(planes, 4, 4, GST_SECOND / 5), expected);
  s = stats();
  EXPECT_EQ(s.size(), 1u);  // after a flush the next frame posts
  free_all(s);
  EXPECT_TRUE(eos_passes(h));
  // And it starts again after a state change.
  ASSERT_EQ(gst_element_set_state(h->element, GST_STATE_READY), GST_STATE_CHANGE_SUCCESS);
  ASSERT_EQ(gst_element_set_state(h->element, GST_STATE_PLAYING), GST_STATE_CHANGE_SUCCESS);
}

// A plate at 1000 degC with a 7x7 hot spot at 1400 centred on (12, 7) and one wild pixel at
// 1750 (a mixed pixel at an edge), as band planes of the colour model.
std::vector<float> plate_with_spot_and_outlier(int w, int h) {
  const ThermalModel& m = *rgb_model();
  const auto plate = graybody_planes(m, w, h, 1000, 1000),
             spot = graybody_planes(m, w, h, 1400, 1400),
             wild = graybody_planes(m, w, h, 1750, 1750);
  std::vector<float> v = plate;
  const int n = w * h;
  for (int b = 0; b < m.profile().band_count(); ++b)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(b * n + y * w + x);
        if (std::abs(x - 12) <= 3 && std::abs(y - 7) <= 3) v[i] = spot[i];
        if (x == 3 && y == 12) v[i] = wild[i];
      }
  return v;
}

TEST_F(RatioTemp, stats_peak_is_the_hot_spot_not_a_wild_pixel) {
  const int w = 24, h = 16;
  start("ratiotemp stats-interval=1 region=8,2,12,12 model=" + rgb_model_path(),
        bands_caps(3, "bayer", w, h));
  guint window = 0;
  g_object_get(element, "peak-window", &window, nullptr);
  EXPECT_EQ(window, 5u);
  const auto planes = plate_with_spot_and_outlier(w, h);
  run(planes, w, h, 0);
  auto s = stats();
  ASSERT_EQ(s.size(), 1u);
  const cv::Mat t = library(rgb_model(), rgb_auto_method(), planes, w, h).t;
  EXPECT_NEAR(field_double(s[0], "max-c"), 1750, 30);  // the wild pixel
  const RegionPeak want = region_peak(t, 5);
  EXPECT_DOUBLE_EQ(field_double(s[0], "peak-c"), want.c);
  EXPECT_NEAR(field_double(s[0], "peak-c"), 1400, 30);
  int x = -1, y = -1;
  EXPECT_TRUE(gst_structure_get_int(s[0], "peak-x", &x));
  EXPECT_TRUE(gst_structure_get_int(s[0], "peak-y", &y));
  EXPECT_LE(std::abs(x - 12), 1);
  EXPECT_LE(std::abs(y - 7), 1);
  // The region's peak: windows inside it, the position in frame pixels.
  const RegionPeak in_region = region_peak(t(cv::Rect(8, 2, 12, 12)), 5);
  EXPECT_DOUBLE_EQ(field_double(s[0], "region-peak-c"), in_region.c);
  EXPECT_TRUE(gst_structure_get_int(s[0], "region-peak-x", &x));
  EXPECT_TRUE(gst_structure_get_int(s[0], "region-peak-y", &y));
  EXPECT_EQ(x, in_region.x + 8);
  EXPECT_EQ(y, in_region.y + 2);
  // Each peak with the expanded systematic uncertainty of a reading there, which every output
  // frame carries as a table (PyrocamUncertaintyMeta).
  const auto estimator = make_estimator(rgb_model(), rgb_auto_method());
  const SystematicUncertaintyTable table = systematic_uncertainty_table(*estimator);
  EXPECT_DOUBLE_EQ(field_double(s[0], "peak-u-sys-c"), table.at(want.c));
  EXPECT_DOUBLE_EQ(field_double(s[0], "region-peak-u-sys-c"), table.at(in_region.c));
  EXPECT_GT(table.at(want.c), 0);
  EXPECT_EQ(last_u_temperature_c, table.temperature_c);
  EXPECT_EQ(last_u_expanded_c, table.expanded_u_c);
  free_all(s);
  // peak-window 0: no peak; even values are refused.
  g_object_set(element, "peak-window", 4u, nullptr);
  g_object_get(element, "peak-window", &window, nullptr);
  EXPECT_EQ(window, 5u);
  g_object_set(element, "peak-window", 0u, nullptr);
  run(planes, w, h, GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_FALSE(gst_structure_has_field(s[0], "peak-c"));
  EXPECT_FALSE(gst_structure_has_field(s[0], "region-peak-c"));
  EXPECT_TRUE(gst_structure_has_field(s[0], "max-c"));
  free_all(s);
  ASSERT_EQ(warnings.size(), 1u);  // the refused window
  EXPECT_NE(warnings[0].find("peak-window 4 is even"), std::string::npos) << warnings[0];
}

// region-tracks-peak: the region (its size from region) is centred on the frame's peak, moved
// to stay in the frame, so its statistics are the hot spot's; off, it stays where region says.
TEST_F(RatioTemp, region_tracks_the_peak) {
  const int w = 24, h = 16;
  start(
      "ratiotemp stats-interval=1 region=0,0,5,5 region-tracks-peak=true model=" + rgb_model_path(),
      bands_caps(3, "bayer", w, h));
  const auto planes = plate_with_spot_and_outlier(w, h);  // the 7x7 spot centred at (12, 7)
  run(planes, w, h, 0);
  auto s = stats();
  ASSERT_EQ(s.size(), 1u);
  int px = -1, py = -1, rx = -1, ry = -1, rw = 0, rh = 0;
  gboolean tracking = FALSE;
  ASSERT_TRUE(gst_structure_get_int(s[0], "peak-x", &px));
  ASSERT_TRUE(gst_structure_get_int(s[0], "peak-y", &py));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-x", &rx));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-y", &ry));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-width", &rw));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-height", &rh));
  ASSERT_TRUE(gst_structure_get_boolean(s[0], "region-tracks-peak", &tracking));
  EXPECT_TRUE(tracking);
  EXPECT_EQ(rw, 5);
  EXPECT_EQ(rh, 5);
  EXPECT_EQ(rx, px - 2);
  EXPECT_EQ(ry, py - 2);
  // The region lies in the spot: its median is the spot's, 1400 degC, not the plate's.
  EXPECT_NEAR(field_double(s[0], "region-median-c"), 1400, 30);
  free_all(s);
  g_object_set(element, "region-tracks-peak", FALSE, nullptr);
  run(planes, w, h, GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-x", &rx));
  ASSERT_TRUE(gst_structure_get_boolean(s[0], "region-tracks-peak", &tracking));
  EXPECT_EQ(rx, 0);
  EXPECT_FALSE(tracking);
  EXPECT_NEAR(field_double(s[0], "region-median-c"), 1000, 30);
  free_all(s);
  EXPECT_TRUE(warnings.empty());
}

TEST_F(RatioTemp, peak_window_larger_than_the_frame_warns_once_and_gives_no_peak) {
  const int w = 24, h = 16;
  start("ratiotemp name=rt0 stats-interval=1 peak-window=17 model=" + rgb_model_path(),
        bands_caps(3, "bayer", w, h));
  const auto planes = plate_with_spot_and_outlier(w, h);
  run(planes, w, h, 0);
  run(planes, w, h, GST_SECOND);
  auto s = stats();
  ASSERT_EQ(s.size(), 2u);
  for (const GstStructure* m : s) {
    EXPECT_FALSE(gst_structure_has_field(m, "peak-c"));
    EXPECT_TRUE(gst_structure_has_field(m, "median-c"));
  }
  free_all(s);
  ASSERT_EQ(warnings.size(), 1u);  // once, not per message
  EXPECT_NE(warnings[0].find("rt0"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("peak-window 17"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("24x16"), std::string::npos) << warnings[0];
  // A window that fits again: the peak is back.
  g_object_set(element, "peak-window", 15u, nullptr);
  run(planes, w, h, 2 * GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_TRUE(gst_structure_has_field(s[0], "peak-c"));
  free_all(s);
}

}  // namespace
}  // namespace pyrocam::test
