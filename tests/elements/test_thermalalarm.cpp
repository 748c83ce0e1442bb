// thermalalarm: frames pass unchanged; the pyrocam-alarm message on raise and clear with its
// fields; median against peak (a wild edge pixel raises nothing); region; bad settings.
#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>

#include "element_support.h"
#include "saturation_meta_support.h"

namespace pyrocam::test {
namespace {

std::uint16_t code_of(double t_c) {
  return static_cast<std::uint16_t>(std::lround((t_c + 273.15) * 10));
}

constexpr int kW = 16, kH = 12;

// A kW x kH frame at `background_c` (0 = no reading) with a 6x6 square at `hot_c` whose
// corner is (4, 3).
std::vector<std::uint16_t> frame(double background_c, double hot_c) {
  std::vector<std::uint16_t> v(kW * kH, background_c > 0 ? code_of(background_c) : 0);
  for (int y = 3; y < 9; ++y)
    for (int x = 4; x < 10; ++x) v[y * kW + x] = hot_c > 0 ? code_of(hot_c) : 0;
  return v;
}

class ThermalAlarm : public HarnessTest {
 protected:
  ThermalAlarm() : HarnessTest("thermalalarm") {}
  void start(const std::string& launch) {
    HarnessTest::start(launch, "video/x-raw,format=GRAY16_LE,width=" + std::to_string(kW) +
                                   ",height=" + std::to_string(kH) + ",framerate=30/1");
    attach_bus();
  }
  // Pushes one frame with pts n/30 s, checks it comes out unchanged, and returns the alarm
  // messages it caused.
  // `saturated`: a PyrocamSaturationMeta naming that rectangle of a mosaic `scale` times this
  // size (1: a colour camera; 5: a 5x5 one, one temperature per 5x5 macro-pixel).
  // `gap`: flagged GAP, a frame without an image (darksub capturing a dark).
  std::vector<GstStructure*> push(const std::vector<std::uint16_t>& codes,
                                  const cv::Rect& saturated = {}, int scale = 1,
                                  const std::vector<cv::Point>& spots = {}, bool gap = false) {
    const GstClockTime pts = gst_util_uint64_scale(n_++, GST_SECOND, 30);
    GstBuffer* in = with_pts(buffer_from(codes), pts);
    if (gap) GST_BUFFER_FLAG_SET(in, GST_BUFFER_FLAG_GAP);
    if (!above_.empty()) add_above_range_meta(in, above_.area(), above_, kW, kH, 2000);
    if (!saturated.empty())
      add_saturation_meta(in, static_cast<guint64>(saturated.area()),
                          cv::Rect(scale * saturated.x, scale * saturated.y,
                                   scale * saturated.width, scale * saturated.height),
                          scale * kW, scale * kH, spots);
    EXPECT_EQ(push_pull<std::uint16_t>(h, in), codes);
    std::vector<GstStructure*> out;
    while (GstMessage* m = gst_bus_pop(bus)) {
      const GstStructure* s = gst_message_get_structure(m);
      if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ELEMENT && gst_structure_has_name(s, "pyrocam-alarm"))
        out.push_back(gst_structure_copy(s));
      else if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_WARNING)
        warnings_.push_back(text_of(m));
      gst_message_unref(m);
    }
    return out;
  }
  // The states ("raised"/"cleared", "" for none) of pushing each frame.
  std::string states(const std::vector<std::vector<std::uint16_t>>& frames,
                     const cv::Rect& saturated = {}, int scale = 1,
                     const std::vector<cv::Point>& spots = {}) {
    std::string out;
    for (const auto& f : frames) {
      auto messages = push(f, saturated, scale, spots);
      EXPECT_LE(messages.size(), 1u);
      out += messages.empty() ? '.' : gst_structure_get_string(messages[0], "state")[0];
      for (GstStructure* s : messages) gst_structure_free(s);
    }
    return out;
  }
  static std::string text_of(GstMessage* m) {
    GError* err = nullptr;
    if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_ERROR)
      gst_message_parse_error(m, &err, nullptr);
    else
      gst_message_parse_warning(m, &err, nullptr);
    std::string text = err->message;
    g_error_free(err);
    return text;
  }
  // The first warning (seen by push or still on the bus) or error not yet taken ("" if none).
  std::string first_warning_or_error(GstMessageType type) {
    if (type == GST_MESSAGE_WARNING && !warnings_.empty()) {
      std::string text = warnings_.front();
      warnings_.erase(warnings_.begin());
      return text;
    }
    GstMessage* m = gst_bus_pop_filtered(bus, type);
    if (!m) return "";
    std::string text = text_of(m);
    gst_message_unref(m);
    return text;
  }
  std::vector<std::string> warnings_;
  // Sets a property of the element while it plays.
  template <typename T>
  void set(const char* property, T value) {
    GstElement* e = find_element(h, "thermalalarm");
    g_object_set(e, property, value, nullptr);
    gst_object_unref(e);
  }
  guint64 n_ = 0;
  cv::Rect above_;  // where push says pixels are hotter than a range ending at 2000 degC
};

TEST_F(ThermalAlarm, RaisesAfterFramesAboveAndClearsBelowTheHysteresis) {
  start("thermalalarm threshold-c=1500 frames=3 hysteresis-c=20 region=4,3,6,6");
  const auto cool = frame(900, 1400), hot = frame(900, 1600), band = frame(900, 1490),
             below = frame(900, 1470);
  EXPECT_EQ(states({cool, hot, hot, hot, hot, band, band, band, below, below, below}),
            "...r......c");
  // The fields of a raise.
  push(cool);
  push(hot);
  push(hot);
  auto m = push(hot);
  ASSERT_EQ(m.size(), 1u);
  const GstStructure* s = m[0];
  EXPECT_STREQ(gst_structure_get_string(s, "state"), "raised");
  gboolean active = FALSE;
  EXPECT_TRUE(gst_structure_get_boolean(s, "active", &active) && active);
  EXPECT_STREQ(gst_structure_get_string(s, "statistic"), "median");
  double v = 0, threshold = 0, clear = 0;
  EXPECT_TRUE(gst_structure_get_double(s, "value-c", &v));
  EXPECT_NEAR(v, 1600, 0.06);  // one code
  EXPECT_TRUE(gst_structure_get_double(s, "threshold-c", &threshold));
  EXPECT_EQ(threshold, 1500);
  EXPECT_TRUE(gst_structure_get_double(s, "clear-c", &clear));
  EXPECT_EQ(clear, 1480);
  guint frames = 0;
  EXPECT_TRUE(gst_structure_get_uint(s, "frames", &frames));
  EXPECT_EQ(frames, 3u);
  guint64 ts = 0;
  EXPECT_TRUE(gst_structure_get_uint64(s, "timestamp", &ts));
  EXPECT_EQ(ts, gst_util_uint64_scale(n_ - 1, GST_SECOND, 30));
  int x = -1, y = -1, w = -1, hh = -1;
  EXPECT_TRUE(gst_structure_get_int(s, "region-x", &x) &&
              gst_structure_get_int(s, "region-y", &y) &&
              gst_structure_get_int(s, "region-width", &w) &&
              gst_structure_get_int(s, "region-height", &hh));
  EXPECT_EQ(x, 4);
  EXPECT_EQ(y, 3);
  EXPECT_EQ(w, 6);
  EXPECT_EQ(hh, 6);
  for (GstStructure* st : m) gst_structure_free(st);
}

TEST_F(ThermalAlarm, TheWholeFrameMedianIsTheBackgroundSoOnlyARegionOrThePeakSeesTheSpot) {
  start("thermalalarm threshold-c=1500 frames=1");
  const auto hot = frame(900, 1600);  // 36 of 192 pixels hot: the median is the background
  EXPECT_EQ(states({hot, hot, hot}), "...");
  set("statistic", 1 /* peak */);
  EXPECT_EQ(states({hot}), "r");
}

TEST_F(ThermalAlarm, OneWildPixelDoesNotRaiseThePeakAlarm) {
  start("thermalalarm threshold-c=1500 frames=1 statistic=peak peak-window=5");
  auto wild = frame(900, 1000);
  wild[3 * kW + 4] = code_of(2900);  // a mixed pixel at the square's corner
  EXPECT_EQ(states({wild, wild}), "..");
}

TEST_F(ThermalAlarm, FramesWithoutAReadingDoNotClearARaisedAlarm) {
  start("thermalalarm threshold-c=1500 frames=2 region=4,3,6,6");
  const auto hot = frame(900, 1600), saturated = frame(900, 0), cool = frame(900, 1000);
  EXPECT_EQ(states({hot, hot, saturated, saturated, saturated, cool, cool}), ".r....c");
}

// The frame with the pixels within r of (cx, cy) without a reading: what a saturated sample
// leaves through the demosaicking kernels.
std::vector<std::uint16_t> with_hole(std::vector<std::uint16_t> v, int cx, int cy, int r) {
  for (int y = std::max(0, cy - r); y <= std::min(kH - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(kW - 1, cx + r); ++x) v[y * kW + x] = 0;
  return v;
}

// A frame without an image (GAP) tells nothing, whatever it carries: a saturation meta that
// would raise the alarm on a frame of the camera's does not, and the run of frames above the
// threshold goes on across it.
TEST_F(ThermalAlarm, FramesWithoutAnImageAreSkipped) {
  start("thermalalarm threshold-c=1500 frames=2 statistic=peak region=4,3,6,6");
  const auto hot = frame(900, 1600), cored = with_hole(frame(900, 1400), 6, 5, 2);
  const cv::Rect core(6, 5, 1, 1);
  for (int k = 0; k < 3; ++k) {
    auto m = push(cored, core, 1, {}, true);
    EXPECT_TRUE(m.empty()) << "a frame without an image changed the alarm";
    for (GstStructure* st : m) gst_structure_free(st);
  }
  EXPECT_EQ(states({hot}), ".");
  auto m = push(hot, {}, 1, {}, true);  // between two frames above the threshold
  EXPECT_TRUE(m.empty());
  for (GstStructure* st : m) gst_structure_free(st);
  EXPECT_EQ(states({hot}), "r");
}

// A saturated core reads nothing, and the rim's readings are below the object: frames whose
// meta puts saturated samples where the region has pixels without a reading (within the
// kernels' reach: 2 pixels, 1 macro-pixel of a 5x5 camera) count as above the threshold,
// unless saturated-raises is off. Saturation elsewhere, or saturation that left every pixel a
// reading (a 5x5 pixel read from its other bands), counts by the readings.
TEST_F(ThermalAlarm, SaturatedSamplesThatTookReadingsInTheRegionCountAsAboveTheThreshold) {
  start("thermalalarm threshold-c=1500 frames=2 statistic=peak region=4,3,6,6");
  gboolean raises = FALSE;
  GstElement* e = find_element(h, "thermalalarm");
  g_object_get(e, "saturated-raises", &raises, nullptr);
  gst_object_unref(e);
  EXPECT_TRUE(raises);
  const auto rim = frame(900, 1400);  // the rim reads below the threshold
  const auto cored = with_hole(rim, 6, 5, 2), far_hole = with_hole(rim, 14, 0, 2),
             near_hole = with_hole(rim, 11, 5, 2);
  const cv::Rect core(6, 5, 1, 1), far(14, 0, 1, 1), near(11, 5, 1, 1);
  EXPECT_EQ(states({far_hole, far_hole}, far), "..");
  EXPECT_EQ(states({rim, rim}, core), "..");  // nothing hidden
  EXPECT_EQ(states({cored, cored}, core), ".r");
  auto m = push(cored, core);  // no change, no message
  EXPECT_TRUE(m.empty());
  EXPECT_EQ(states({rim}), ".");  // one readable frame below does not clear
  m = push(rim);
  ASSERT_EQ(m.size(), 1u);
  gboolean saturated = TRUE;
  EXPECT_TRUE(gst_structure_get_boolean(m[0], "saturated", &saturated));
  EXPECT_FALSE(saturated);
  EXPECT_STREQ(gst_structure_get_string(m[0], "state"), "cleared");
  for (GstStructure* st : m) gst_structure_free(st);
  // A pixel beside the region: its hole reaches in.
  EXPECT_EQ(states({near_hole}, near), ".");
  m = push(near_hole, near);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_TRUE(gst_structure_get_boolean(m[0], "saturated", &saturated));
  EXPECT_TRUE(saturated);
  for (GstStructure* st : m) gst_structure_free(st);
  set("saturated-raises", FALSE);
  EXPECT_EQ(states({rim, rim, rim}), ".c.");  // by the readings: cleared after 2
  EXPECT_EQ(states({cored, cored, cored}, core), "...");
  // A 5x5 camera: the meta in mosaic pixels, scaled to macro-pixels; one of reach, so the hole
  // a macro-pixel beside the region stays outside.
  set("saturated-raises", TRUE);
  EXPECT_EQ(states({near_hole, near_hole}, near, 5), "..");
  EXPECT_EQ(states({cored, cored}, core, 5), ".r");
}

// A part hotter than the model's range has no reading; ratiotemp's meta says where. Its pixels
// count as hotter than any reading in the statistic: a core of them raises the median and the
// peak alarm (value-c then the range's end), a pixel of them at a corner does not move the peak,
// one outside the region is not watched, and a threshold above the range cannot be compared.
TEST_F(ThermalAlarm, PixelsHotterThanTheModelsRangeCountAsHotterThanAnyReading) {
  start("thermalalarm threshold-c=1900 frames=2 region=4,3,6,6");
  const auto rim = frame(900, 1400), cored = with_hole(rim, 6, 5, 2);
  EXPECT_EQ(states({cored, cored}), "..");    // no meta: a hole is no reading
  above_ = cv::Rect(5, 4, 5, 5);              // 25 of the region's 36 pixels
  const auto hole = with_hole(rim, 7, 6, 2);  // the same 5x5 without a reading
  EXPECT_EQ(states({hole}), ".");
  auto m = push(hole);
  ASSERT_EQ(m.size(), 1u);
  gboolean above = FALSE, saturated = TRUE;
  double v = 0;
  EXPECT_TRUE(gst_structure_get_boolean(m[0], "above-range", &above));
  EXPECT_TRUE(above);
  EXPECT_TRUE(gst_structure_get_boolean(m[0], "saturated", &saturated));
  EXPECT_FALSE(saturated);
  EXPECT_TRUE(gst_structure_get_double(m[0], "value-c", &v));
  EXPECT_EQ(v, 2000);
  for (GstStructure* st : m) gst_structure_free(st);
  above_ = {};
  EXPECT_EQ(states({hole, hole}), ".c");
  // A threshold above the range's end cannot be compared with them: no reading, and a warning.
  set("threshold-c", 2500.0);
  above_ = cv::Rect(5, 4, 5, 5);
  EXPECT_EQ(states({hole, hole}), "..");
  EXPECT_NE(first_warning_or_error(GST_MESSAGE_WARNING).find("lies above the model's range"),
            std::string::npos);
  EXPECT_EQ(first_warning_or_error(GST_MESSAGE_WARNING), "");  // once
  above_ = {};
  // The peak: one such pixel at the region's corner leaves every window's median a reading.
  set("statistic", "peak");
  set("threshold-c", 1900.0);
  above_ = cv::Rect(4, 3, 1, 1);
  EXPECT_EQ(states({with_hole(rim, 4, 3, 1), with_hole(rim, 4, 3, 1)}), "..");
  above_ = cv::Rect(5, 4, 5, 5);
  EXPECT_EQ(states({hole, hole}), ".r");
  above_ = {};
  EXPECT_EQ(states({rim, rim}), ".c");
  // Outside the region.
  above_ = cv::Rect(12, 0, 3, 3);
  EXPECT_EQ(states({with_hole(rim, 13, 1, 1), with_hole(rim, 13, 1, 1)}), "..");
}

// Two saturated spots in opposite corners: their rectangle spans the frame, but the meta's
// tiles say where they are, and the region's pixel without a reading between them is cold.
TEST_F(ThermalAlarm, SaturatedSpotsElsewhereDoNotRaiseThoughTheirRectangleSpansTheRegion) {
  start("thermalalarm threshold-c=1500 frames=2 statistic=peak region=4,3,6,6");
  const auto rim = frame(900, 1400);
  const auto cored = with_hole(rim, 6, 5, 2);
  const cv::Rect both(0, 0, kW, kH);
  const std::vector<cv::Point> corners = {{0, 0}, {kW - 1, kH - 1}};
  EXPECT_EQ(states({cored, cored}, both, 1, corners), "..");
  EXPECT_EQ(states({cored, cored}, both, 5, {{0, 0}, {5 * kW - 1, 5 * kH - 1}}), "..");
  // A spot at the hole: raised; where the tiles are not known, the rectangle decides.
  EXPECT_EQ(states({cored, cored}, both, 1, {{0, 0}, {6, 5}}), ".r");
  EXPECT_EQ(states({rim, rim}), ".c");
  EXPECT_EQ(states({cored, cored}, both), ".r");
}

TEST_F(ThermalAlarm, TurningTheThresholdOffClearsARaisedAlarm) {
  start("thermalalarm threshold-c=1500 frames=1 region=4,3,6,6");
  const auto hot = frame(900, 1600);
  EXPECT_EQ(states({hot}), "r");
  set("threshold-c", -273.15);
  auto m = push(hot);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_STREQ(gst_structure_get_string(m[0], "state"), "cleared");
  EXPECT_FALSE(gst_structure_has_field(m[0], "value-c"));
  // Off has no levels (they were NaN, which a structure's text cannot be read back from).
  EXPECT_FALSE(gst_structure_has_field(m[0], "threshold-c"));
  EXPECT_FALSE(gst_structure_has_field(m[0], "clear-c"));
  for (GstStructure* st : m) gst_structure_free(st);
  EXPECT_EQ(states({hot}), ".");
}

TEST_F(ThermalAlarm, ARegionOutsideTheFrameIsAnErrorAndAPartialOneAWarning) {
  start("thermalalarm threshold-c=1500 frames=1 region=12,8,10,10");
  EXPECT_EQ(states({frame(1600, 1600)}), "r");
  EXPECT_NE(first_warning_or_error(GST_MESSAGE_WARNING).find("watching 12,8,4,4"),
            std::string::npos);
  set("region", "40,40,2,2");
  EXPECT_EQ(gst_harness_push(h, buffer_from(frame(900, 1600))), GST_FLOW_ERROR);
  EXPECT_NE(first_warning_or_error(GST_MESSAGE_ERROR).find("lies outside the 16x12 frame"),
            std::string::npos);
}

TEST_F(ThermalAlarm, APeakWindowLargerThanTheRegionIsAnError) {
  start("thermalalarm threshold-c=1500 statistic=peak peak-window=7 region=0,0,6,6");
  EXPECT_EQ(gst_harness_push(h, buffer_from(frame(900, 1600))), GST_FLOW_ERROR);
  const std::string e = first_warning_or_error(GST_MESSAGE_ERROR);
  EXPECT_NE(e.find("peak-window 7"), std::string::npos) << e;
  EXPECT_NE(e.find("6x6"), std::string::npos) << e;
}

TEST_F(ThermalAlarm, MalformedSettingsAreRefusedWithAWarningAndTheOldOnesStay) {
  start("thermalalarm threshold-c=1500 region=4,3,6,6");
  set("region", "4,3,6");
  set("peak-window", 4u);
  GstElement* e = find_element(h, "thermalalarm");
  gchar* region = nullptr;
  guint window = 0;
  g_object_get(e, "region", &region, "peak-window", &window, nullptr);
  EXPECT_STREQ(region, "4,3,6,6");
  EXPECT_EQ(window, 5u);
  g_free(region);
  EXPECT_NE(first_warning_or_error(GST_MESSAGE_WARNING).find("'4,3,6' is not x,y,width,height"),
            std::string::npos);
  EXPECT_NE(first_warning_or_error(GST_MESSAGE_WARNING).find("peak-window 4 is not odd"),
            std::string::npos);
  gst_object_unref(e);
}

// Set in a launch line the element is not in a pipeline yet and a warning reaches no bus: the
// alarm watched the whole frame instead of a region it never parsed. Now it does not start.
TEST(ThermalAlarmLaunch, a_malformed_setting_in_a_launch_line_stops_the_pipeline_n) {
  REQUIRE_ELEMENT("thermalalarm");
  for (const char* setting : {"region=100,80,120", "peak-window=4"}) {
    SCOPED_TRACE(setting);
    const auto r = run_pipeline(
        "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY16_LE,width=32,height=24 ! "
        "thermalalarm threshold-c=1000 " +
        std::string(setting) + " ! fakesink");
    expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS,
                 {std::string(setting).substr(0, std::string(setting).find('='))});
    EXPECT_EQ(r.message.find("keeping"), std::string::npos) << r.message;  // it stops
  }
}

// Buffers too short for their frame: GstVideoFilter warned "please file a bug" and dropped them,
// and the alarm never looked at the stream. They are a STREAM FORMAT error, as in
// thermalcolormap.
TEST(ThermalAlarmLaunch, a_buffer_too_short_for_its_frame_is_an_error_naming_both_sizes_n) {
  REQUIRE_ELEMENT("thermalalarm");
  const auto r = run_pipeline(
      "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY16_LE,width=40,height=30 ! "
      "capssetter join=false caps=video/x-raw,format=GRAY16_LE,width=40,height=40 ! "
      "thermalalarm threshold-c=100 frames=1 ! fakesink");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT, {"2400 bytes", "40x40"});
}

// ratiotemp output=uncertainty gives expanded uncertainties in the codes' steps: compared with a
// threshold as temperatures, 53 K read as -220 degC and a real threshold never raised.
TEST(ThermalAlarmLaunch, an_uncertainty_stream_is_refused_by_its_tags_n) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp", "thermalalarm"})
    REQUIRE_ELEMENT(e);
  const auto r = run_pipeline(
      "pyrocamsrc scene=plate temperature=1500 num-buffers=3 ! video/x-bayer,width=40,height=20 "
      "! darksub dark-level=50 ! demosaic25 ! ratiotemp output=uncertainty model=" +
      test_model_path("test-model-rgb.json") + " ! thermalalarm threshold-c=2000 ! fakesink");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT,
               {"the stream holds expanded-uncertainty (its tags say so), not temperatures"});
}

}  // namespace
}  // namespace pyrocam::test
