// darksub: caps of both raw media types, values against the library, saturation marks, dark
// capture, live property changes, flush/EOS, and bus errors for bad dark frames.
#include <cmath>
#include <cstdint>
#include <fstream>

#include "element_support.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/runtime/darksub.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

class DarkSub : public HarnessTest {
 protected:
  DarkSub() : HarnessTest("darksub") {}
};

// A 6x4 8-bit frame: a ramp with one saturated and one just-below pixel.
std::vector<std::uint8_t> frame6x4() {
  std::vector<std::uint8_t> v(24);
  for (int i = 0; i < 24; ++i) v[i] = static_cast<std::uint8_t>(60 + 5 * i);
  v[7] = 220;  // saturated at the default level 220 of 8 bit
  v[8] = 219;
  return v;
}

const char* kRggb6x4 = "video/x-bayer,format=rggb,width=6,height=4,framerate=30/1";

// Row-padded copy (GStreamer's 4-byte row alignment).
std::vector<std::uint8_t> padded(const std::vector<std::uint8_t>& v, int w, int h, int stride) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(stride * h), 0);
  for (int y = 0; y < h; ++y)
    std::copy(v.begin() + y * w, v.begin() + (y + 1) * w, out.begin() + y * stride);
  return out;
}

// The 6x4 frame as a buffer with GStreamer's row padding.
GstBuffer* padded6x4(const std::vector<std::uint8_t>& raw) {
  return buffer_from(padded(raw, 6, 4, 8));
}

std::vector<float> expected(const std::vector<std::uint8_t>& raw, int w, int h, double dark,
                            double saturation) {
  cv::Mat in(h, w, CV_8U, const_cast<std::uint8_t*>(raw.data())), out;
  subtract_dark(in, cv::Mat(h, w, CV_32F, cv::Scalar(dark)), saturation, out);
  return std::vector<float>(out.begin<float>(), out.end<float>());
}

TEST_F(DarkSub, bayer_caps_give_mosaic_caps_and_library_values) {
  start("darksub dark-level=50", "video/x-bayer,format=grbg,width=6,height=4,framerate=30/1");
  const auto raw = frame6x4();
  const auto v = push_pull<float>(h, padded6x4(raw));
  ASSERT_EQ(v.size(), 24u);
  EXPECT_EQ(v, expected(raw, 6, 4, 50, 220));
  EXPECT_EQ(v[7], kInf);
  EXPECT_EQ(v[8], 169.f);
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("video/x-pyrocam-mosaic"), std::string::npos) << caps;
  EXPECT_NE(caps.find("pattern=(string)grbg"), std::string::npos) << caps;
  EXPECT_NE(caps.find("bit-depth=(int)8"), std::string::npos) << caps;
  EXPECT_NE(caps.find("format=(string)F32LE"), std::string::npos) << caps;
  // Cameras that send rows without padding are read too.
  EXPECT_EQ(push_pull<float>(h, buffer_from(raw)), expected(raw, 6, 4, 50, 220));
}

// Each frame carries where it saturated (PyrocamSaturationMeta, found by the API's registered
// name: the test does not link the plugin).
TEST_F(DarkSub, frames_carry_their_saturated_samples) {
  start("darksub dark-level=50", kRggb6x4);
  for (const bool saturated : {true, false}) {
    auto raw = frame6x4();
    if (!saturated) raw[7] = 200;
    GstBuffer* out = gst_harness_push_and_pull(h, padded6x4(raw));
    ASSERT_NE(out, nullptr);
    const GType api = g_type_from_name("PyrocamSaturationMetaAPI");
    ASSERT_NE(api, G_TYPE_INVALID);
    const auto* m = reinterpret_cast<const PyrocamSaturationMeta*>(gst_buffer_get_meta(out, api));
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(m->samples, saturated ? 1u : 0u);
    EXPECT_EQ(m->x, saturated ? 1 : 0);  // sample 7 of a 6-wide frame
    EXPECT_EQ(m->y, saturated ? 1 : 0);
    EXPECT_EQ(m->width, saturated ? 1 : 0);
    EXPECT_EQ(m->height, saturated ? 1 : 0);
    EXPECT_EQ(m->frame_width, 6);
    EXPECT_EQ(m->frame_height, 4);
    gst_buffer_unref(out);
  }
}

TEST_F(DarkSub, gray8_caps_use_the_pattern_property) {
  start("darksub dark-level=50 pattern=5x5",
        "video/x-raw,format=GRAY8,width=10,height=5,framerate=30/1");
  std::vector<std::uint8_t> raw(50);
  for (int i = 0; i < 50; ++i) raw[i] = static_cast<std::uint8_t>(50 + 4 * i);
  EXPECT_EQ(push_pull<float>(h, buffer_from(padded(raw, 10, 5, 12))),
            expected(raw, 10, 5, 50, 220));
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("pattern=(string)5x5"), std::string::npos) << caps;
}

TEST_F(DarkSub, gray16_caps_use_the_bit_depth_property) {
  start("darksub dark-level=100 pattern=bggr bit-depth=12",
        "video/x-raw,format=GRAY16_LE,width=4,height=2,framerate=30/1");
  const std::vector<std::uint16_t> raw = {100, 1000, 3532, 3533, 4095, 0, 200, 300};
  const auto v = push_pull<float>(h, buffer_from(raw));
  ASSERT_EQ(v.size(), 8u);
  EXPECT_EQ(v[0], 0.f);
  EXPECT_EQ(v[2], 3432.f);  // below round(220/255 * 4095) = 3533
  EXPECT_EQ(v[3], kInf);
  EXPECT_EQ(v[4], kInf);
  EXPECT_EQ(v[5], -100.f);
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("bit-depth=(int)12"), std::string::npos) << caps;
  EXPECT_NE(caps.find("pattern=(string)bggr"), std::string::npos) << caps;
}

TEST_F(DarkSub, dark_frame_from_a_file) {
  ScratchDir dir("darksub");
  cv::Mat dark(4, 6, CV_8U);
  for (int i = 0; i < 24; ++i) dark.data[i] = static_cast<std::uint8_t>(40 + i);
  write_raw_image(dir / "dark.pgm", dark);
  start("darksub location=" + (dir / "dark.pgm").string(),
        "video/x-bayer,format=rggb,width=6,height=4,framerate=30/1");
  const auto raw = frame6x4();
  const auto v = push_pull<float>(h, padded6x4(raw));
  ASSERT_EQ(v.size(), 24u);
  for (int i = 0; i < 24; ++i) {
    if (i != 7) {
      EXPECT_EQ(v[i], static_cast<float>(raw[i]) - (40 + i)) << i;
    }
  }
  EXPECT_EQ(v[7], kInf);
}

TEST_F(DarkSub, property_changes_apply_while_playing) {
  start("darksub dark-level=50", kRggb6x4);
  GstElement* e = find_element(h, "darksub");
  const auto raw = frame6x4();
  EXPECT_EQ(push_pull<float>(h, padded6x4(raw)), expected(raw, 6, 4, 50, 220));
  g_object_set(e, "saturation-level", 200.0, "dark-level", 60.0, nullptr);
  const auto v = push_pull<float>(h, padded6x4(raw));
  EXPECT_EQ(v, expected(raw, 6, 4, 60, 200));
  ASSERT_EQ(v.size(), 24u);
  EXPECT_EQ(v[8], kInf);  // 219 >= 200 now
  gst_object_unref(e);
}

TEST_F(DarkSub, controlled_levels_follow_the_controller_by_buffer_time) {
  start("darksub dark-level=50", kRggb6x4);
  GstElement* e = find_element(h, "darksub");
  // dark-level 50 until 1 s, then 70; saturation-level 220 until 1 s, then 200.
  ASSERT_TRUE(control_property(e, "dark-level", {{0, 50.0}, {GST_SECOND, 70.0}}));
  ASSERT_TRUE(control_property(e, "saturation-level", {{0, 220.0}, {GST_SECOND, 200.0}}));
  const auto raw = frame6x4();
  auto push_pull_at = [&](GstClockTime pts) {
    return push_pull<float>(h, with_pts(padded6x4(raw), pts));
  };
  EXPECT_EQ(push_pull_at(GST_SECOND / 2), expected(raw, 6, 4, 50, 220));
  const auto later = push_pull_at(GST_SECOND + GST_SECOND / 2);
  EXPECT_EQ(later, expected(raw, 6, 4, 70, 200));
  EXPECT_EQ(later.at(8), kInf);  // 219 >= 200 from 1 s on
  double level = 0;
  g_object_get(e, "dark-level", &level, nullptr);
  EXPECT_EQ(level, 70.0);
  gst_object_unref(e);
}

TEST_F(DarkSub, capture_dark_averages_frames_and_outputs_nan_meanwhile) {
  start("darksub capture-frames=2 dark-level=0",
        "video/x-raw,format=GRAY8,width=4,height=2,framerate=30/1,pattern=rggb");
  GstElement* e = find_element(h, "darksub");
  g_signal_emit_by_name(e, "capture-dark");
  const std::vector<std::uint8_t> d1(8, 40), d2(8, 44), light(8, 100);
  for (const auto* frame : {&d1, &d2}) {
    ASSERT_EQ(gst_harness_push(h, buffer_from(*frame)), GST_FLOW_OK);
    GstBuffer* out = gst_harness_try_pull(h);
    ASSERT_NE(out, nullptr);
    for (float f : values_of<float>(out)) EXPECT_TRUE(std::isnan(f));
    gst_buffer_unref(out);
  }
  ASSERT_EQ(gst_harness_push(h, buffer_from(light)), GST_FLOW_OK);
  GstBuffer* out = gst_harness_try_pull(h);
  ASSERT_NE(out, nullptr);
  for (float f : values_of<float>(out)) EXPECT_EQ(f, 58.f);
  gst_buffer_unref(out);
  gst_object_unref(e);
}

// A captured dark that no longer fits the stream (its size changed) is dropped, and said on the
// bus with what is subtracted instead (it was only a debug line).
// dark-level is controllable: one above the full scale, set while playing, would leave no
// reading anywhere and say nothing; it is refused with a warning once. bit-depth and pattern
// cannot change while running: they keep their value, with a warning.
TEST_F(DarkSub, settings_refused_while_playing_keep_the_last_good_value_and_say_so_n) {
  start("darksub dark-level=50", kRggb6x4);
  GstElement* e = find_element(h, "darksub");
  const auto raw = frame6x4();
  g_object_set(e, "dark-level", 65535.0, "bit-depth", 16, "pattern", 0 /* rggb */, nullptr);
  EXPECT_EQ(push_pull<float>(h, padded6x4(raw)), expected(raw, 6, 4, 50, 220));
  EXPECT_EQ(push_pull<float>(h, padded6x4(raw)), expected(raw, 6, 4, 50, 220));
  gint bits = -1;
  g_object_get(e, "bit-depth", &bits, nullptr);
  EXPECT_EQ(bits, 0);
  g_object_set(e, "dark-level", 60.0, nullptr);
  EXPECT_EQ(push_pull<float>(h, padded6x4(raw)), expected(raw, 6, 4, 60, 220));
  gst_object_unref(e);
  std::vector<std::string> warnings;
  while (GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_WARNING)) {
    GError* err = nullptr;
    gst_message_parse_warning(m, &err, nullptr);
    warnings.emplace_back(err->message);
    g_error_free(err);
    gst_message_unref(m);
  }
  const auto count = [&](const std::string& part) {
    return std::count_if(warnings.begin(), warnings.end(),
                         [&](const std::string& w) { return w.find(part) != std::string::npos; });
  };
  EXPECT_EQ(count("dark-level 65535 is above the 8-bit full scale (255 DN): refused, 50 DN stays "
                  "subtracted"),
            1);
  EXPECT_EQ(count("bit-depth can change only in the NULL or READY state"), 1);
  EXPECT_EQ(count("pattern can change only in the NULL or READY state"), 1);
}

TEST_F(DarkSub, a_captured_dark_dropped_on_a_size_change_is_said) {
  start("darksub capture-frames=1 dark-level=10",
        "video/x-raw,format=GRAY8,width=4,height=2,framerate=30/1,pattern=rggb");
  attach_bus();
  GstElement* e = find_element(h, "darksub");
  g_signal_emit_by_name(e, "capture-dark");
  gst_object_unref(e);
  ASSERT_EQ(gst_harness_push(h, buffer_from(std::vector<std::uint8_t>(8, 40))), GST_FLOW_OK);
  gst_buffer_unref(gst_harness_pull(h));
  EXPECT_EQ(push_pull<float>(h, buffer_from(std::vector<std::uint8_t>(8, 100))),
            std::vector<float>(8, 60.f));
  gst_harness_set_src_caps_str(
      h, "video/x-raw,format=GRAY8,width=4,height=4,framerate=30/1,pattern=rggb");
  EXPECT_EQ(push_pull<float>(h, buffer_from(std::vector<std::uint8_t>(16, 100))),
            std::vector<float>(16, 90.f));
  std::string warning;
  while (GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_WARNING)) {
    GError* err = nullptr;
    gst_message_parse_warning(m, &err, nullptr);
    warning += err->message;
    g_error_free(err);
    gst_message_unref(m);
  }
  EXPECT_NE(warning.find("captured 4x2 dark does not fit the stream, now 4x4"), std::string::npos)
      << warning;
  EXPECT_NE(warning.find("dark-level 10"), std::string::npos) << warning;
}

TEST_F(DarkSub, survives_flush_and_eos) {
  start("darksub dark-level=50", kRggb6x4);
  const auto raw = frame6x4();
  ASSERT_EQ(gst_harness_push(h, padded6x4(raw)), GST_FLOW_OK);
  gst_buffer_unref(gst_harness_pull(h));
  push_flush(h);
  EXPECT_EQ(push_pull<float>(h, padded6x4(raw)), expected(raw, 6, 4, 50, 220));
  EXPECT_TRUE(eos_passes(h));
  // And it starts again after a state change.
  gst_harness_set(h, "darksub", "dark-level", 10.0, nullptr);
  ASSERT_EQ(gst_element_set_state(h->element, GST_STATE_READY), GST_STATE_CHANGE_SUCCESS);
  ASSERT_EQ(gst_element_set_state(h->element, GST_STATE_PLAYING), GST_STATE_CHANGE_SUCCESS);
}

// Runs a darksub (its launch words) on two 16x8 GRAY8 frames that say rggb.
BusResult run_on_gray8(const std::string& darksub) {
  return run_pipeline(
      "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY8,width=16,height=8,pattern=rggb ! " +
      darksub + " ! fakesink");
}
// The same with a dark frame from a file.
BusResult run_on_gray8_with_dark(const std::filesystem::path& dark) {
  return run_on_gray8("darksub location=" + dark.string());
}

TEST(DarkSubErrors, rejects_a_missing_dark_file) {
  REQUIRE_ELEMENT("darksub");
  const auto r = run_on_gray8("darksub location=/nonexistent/dark.pgm");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND, {"/nonexistent/dark.pgm"});
}

TEST(DarkSubErrors, rejects_a_dark_of_the_wrong_size) {
  REQUIRE_ELEMENT("darksub");
  ScratchDir dir("darksub-size");
  write_raw_image(dir / "dark.png", cv::Mat(6, 12, CV_8U, cv::Scalar(50)));
  const auto r = run_on_gray8_with_dark(dir / "dark.png");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT, {"12x6", "16x8"});
}

TEST(DarkSubErrors, rejects_a_corrupt_dark_file) {
  REQUIRE_ELEMENT("darksub");
  ScratchDir dir("darksub-corrupt");
  write_text(dir / "dark.pgm", "P5\n16 8\n255\nshort");
  const auto r = run_on_gray8_with_dark(dir / "dark.pgm");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_READ, {"dark.pgm"});
}

TEST(DarkSubErrors, rejects_a_16_bit_dark_on_an_8_bit_stream) {
  REQUIRE_ELEMENT("darksub");
  ScratchDir dir("darksub-depth");
  write_raw_image(dir / "dark16.pgm", cv::Mat(8, 16, CV_16U, cv::Scalar(50)));
  const auto r = run_on_gray8_with_dark(dir / "dark16.pgm");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT,
               {"dark16.pgm", "has 16-bit samples", "GRAY8"});
}

// A dark that cannot be this camera's frame is refused from its header: the PNG below declares
// 10000x10000 (within the readers' limits) and holds no pixels, so decoding it first would fail
// with "could not read" (and, were the pixels there, take 100 MB) instead of naming the sizes.
TEST(DarkSubErrors, rejects_a_dark_of_another_size_from_its_header_n) {
  REQUIRE_ELEMENT("darksub");
  ScratchDir dir("darksub-huge");
  std::ofstream(dir / "huge.png", std::ios::binary) << test::png_header(10000, 10000, 8);
  const auto r = run_on_gray8_with_dark(dir / "huge.png");
  ASSERT_TRUE(r.error);
  EXPECT_EQ(r.domain, GST_STREAM_ERROR);
  EXPECT_NE(r.message.find("huge.png is 10000x10000 but the camera frames are"), std::string::npos)
      << r.message;
}

// GstBaseTransform tries set_caps again with the caps it refused: the message is posted once.
TEST(DarkSubErrors, posts_a_refused_dark_once) {
  REQUIRE_ELEMENT("darksub");
  ScratchDir dir("darksub-once");
  write_raw_image(dir / "dark.pgm", cv::Mat(10, 10, CV_8U, cv::Scalar(50)));
  const auto r =
      run_pipeline("pyrocamsrc num-buffers=5 ! darksub location=" + (dir / "dark.pgm").string() +
                   " ! demosaic25 ! fakesink");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT, {"dark.pgm is 10x10"});
  EXPECT_EQ(r.errors, 1);
}

TEST(DarkSubErrors, rejects_an_8_bit_dark_on_a_16_bit_stream) {
  REQUIRE_ELEMENT("darksub");
  ScratchDir dir("darksub-depth8");
  write_raw_image(dir / "dark8.png", cv::Mat(8, 16, CV_8U, cv::Scalar(50)));
  const auto r = run_pipeline(
      "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY16_LE,width=16,height=8,pattern=rggb ! "
      "darksub location=" +
      (dir / "dark8.png").string() + " ! fakesink");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT,
               {"dark8.png has 8-bit samples", "GRAY16_LE"});
}

TEST(DarkSubErrors, rejects_a_bit_depth_that_gray8_cannot_carry) {
  REQUIRE_ELEMENT("darksub");
  const auto r = run_on_gray8("darksub dark-level=5 bit-depth=12");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"bit-depth 12", "GRAY8"});
}

TEST(DarkSubErrors, rejects_gray_input_that_says_no_pattern) {
  REQUIRE_ELEMENT("darksub");
  const auto r = run_pipeline(
      "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY8,width=16,height=8 ! "
      "darksub dark-level=5 ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"GRAY8", "pattern"});
}

// A snapshot sensor's frame is larger than its mosaic (2048x1088 around 2045x1085): the error
// says how to crop it, and the crop it names runs.
TEST(DarkSubErrors, a_frame_beyond_whole_periods_is_refused_with_the_crop_to_make_n) {
  REQUIRE_ELEMENT("darksub");
  const std::string source =
      "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY8,width=2048,height=1088 ! ";
  const auto r = run_pipeline(source + "darksub dark-level=5 pattern=5x5 ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"2048x1088", "2045x1085", "videocrop right=3 bottom=3"});
  if (!have_element("videocrop")) GTEST_SKIP() << "videocrop (gst-plugins-good) missing";
  expect_eos(run_pipeline(source + "videocrop right=3 bottom=3 ! darksub dark-level=5 "
                                   "pattern=5x5 ! fakesink name=sink"),
             2);
}

TEST(DarkSubErrors, a_frame_smaller_than_one_period_is_refused_as_such_n) {
  REQUIRE_ELEMENT("darksub");
  const auto r = run_pipeline(
      "videotestsrc num-buffers=2 ! video/x-raw,format=GRAY8,width=1,height=1 ! "
      "darksub dark-level=5 pattern=rggb ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"1x1 frames are smaller than one rggb period (2x2)"});
}

// A constant dark above the full scale leaves no signal anywhere: refused, not run dark.
TEST(DarkSubErrors, rejects_a_dark_level_above_the_full_scale_n) {
  REQUIRE_ELEMENT("darksub");
  const auto r = run_on_gray8("darksub dark-level=300 pattern=rggb");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS,
               {"dark-level 300", "8-bit full scale (255 DN)"});
}

// A saturation level at or below the dark level marks every pixel saturated, and ratiotemp
// then asks for a shorter exposure: refused, naming both (the default 220 too).
TEST(DarkSubErrors, rejects_a_saturation_level_not_above_the_dark_level_n) {
  REQUIRE_ELEMENT("darksub");
  expect_error(run_on_gray8("darksub dark-level=50 saturation-level=40 pattern=rggb"),
               GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS,
               {"saturation-level 40 DN is at or below dark-level 50 DN"});
  expect_error(run_on_gray8("darksub dark-level=230 pattern=rggb"), GST_RESOURCE_ERROR,
               GST_RESOURCE_ERROR_SETTINGS,
               {"saturation-level 220 DN is at or below dark-level 230 DN"});
  const auto fine = run_on_gray8("darksub dark-level=50 saturation-level=51 pattern=rggb");
  EXPECT_FALSE(fine.error) << fine.message;
  EXPECT_TRUE(fine.eos);
}

// 8-bit samples scaled to 16 bits (videoconvert) with bit-depth 8 still in the caps: every
// pixel would read as saturated; an error names the samples and the bit depth. 16 bits: fine.
TEST(DarkSubErrors, rejects_samples_above_the_stated_bit_depth_n) {
  REQUIRE_ELEMENT("darksub");
  const std::string source =
      "videotestsrc pattern=white num-buffers=1 ! "
      "video/x-raw,format=GRAY16_LE,width=8,height=4 ! ";
  expect_error(run_pipeline(source + "darksub pattern=rggb bit-depth=8 dark-level=0 ! fakesink"),
               GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT,
               {"in a stream whose caps say bit-depth 8"});
  EXPECT_TRUE(
      run_pipeline(source + "darksub pattern=rggb bit-depth=16 dark-level=0 ! fakesink").eos);
}

TEST(DarkSubErrors, rejects_a_pattern_that_differs_from_the_caps) {
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=1 profile=nir5x5-reference ! video/x-raw,width=20,height=10 ! "
      "darksub dark-level=5 pattern=rggb ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"pattern=rggb", "5x5 mosaic"});
}

TEST(DarkSubErrors, rejects_a_pattern_that_differs_from_the_bayer_format) {
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=1 ! video/x-bayer,format=rggb,width=20,height=10 ! "
      "darksub dark-level=5 pattern=5x5 ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"pattern=5x5", "rggb mosaic"});
}

TEST(DarkSubPipeline, takes_the_pattern_and_saturation_level_from_pyrocamsrc) {
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=1 profile=nir5x5-reference ! video/x-raw,width=20,height=10 ! "
      "darksub dark-level=5 ! "
      "video/x-pyrocam-mosaic,pattern=5x5,bit-depth=8 ! fakesink name=sink");
  expect_eos(r, 1);
}

TEST(DarkSubErrors, rejects_running_without_a_dark) {
  REQUIRE_ELEMENT("darksub");
  const auto r = run_on_gray8("darksub");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"dark-level"});
}

// A Bayer mosaic labelled as shifted by one column (grbg, as a crop of the left column leaves
// rggb) or one row (gbrg) reads temperatures that look right and are not: darksub warns. The
// labels that are true, and a shift by both (bggr: red and blue traded, not seen), say nothing.
// A dark level 20 DN off leaves the cold background at +-20 DN in every band: said once; the
// camera's own (pyrocamsrc's clamped black level, 50 DN) is not.
TEST(DarkSubPipeline, warns_when_the_dark_level_is_not_the_cameras) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto warnings_with = [](const std::string& source, const std::string& darksub) {
    const BusResult r = run_pipeline(source + " scene=plate temperature=1500 num-buffers=6 ! " +
                                     darksub + " ! fakesink");
    EXPECT_TRUE(r.eos) << r.message;
    std::string dark;
    for (const std::string& w : r.warnings)
      if (w.find("cold background reads 0") != std::string::npos) dark += w + "\n";
    return dark;
  };
  const std::string colour = "pyrocamsrc", snapshot = "pyrocamsrc profile=nir5x5-reference";
  EXPECT_EQ(warnings_with(colour, "darksub dark-level=50"), "");
  EXPECT_EQ(warnings_with(snapshot, "darksub pattern=5x5 dark-level=50"), "");
  const std::string low = warnings_with(colour, "darksub dark-level=30");
  EXPECT_NE(low.find("after the dark (dark-level 30 DN) the frame's darkest parts read +20 DN"),
            std::string::npos)
      << low;
  EXPECT_NE(low.find("the dark is about 20 DN too low"), std::string::npos) << low;
  EXPECT_EQ(std::count(low.begin(), low.end(), '\n'), 1) << low;  // once
  EXPECT_NE(warnings_with(snapshot, "darksub pattern=5x5 dark-level=70").find("20 DN too high"),
            std::string::npos);
}

TEST(DarkSubPipeline, warns_when_the_greens_are_not_where_the_pattern_says) {
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("pyrocamsrc");
  if (!have_element("capssetter")) GTEST_SKIP() << "capssetter (gst-plugins-good) missing";
  for (const char* label : {"rggb", "grbg", "gbrg", "bggr"}) {
    SCOPED_TRACE(label);
    const auto r = run_pipeline(
        "pyrocamsrc num-buffers=10 scene=plate temperature=1500 ! "
        "video/x-bayer,format=rggb,width=160,height=120 ! capssetter caps=video/x-bayer,format=" +
        std::string(label) + " ! darksub dark-level=50 ! fakesink name=sink");
    expect_eos(r, 10);  // every 16th row of cells: the lit ones of a few frames
    const bool shifted = std::string(label) == "grbg" || std::string(label) == "gbrg";
    ASSERT_EQ(r.warnings.size(), shifted ? 1u : 0u);
    if (shifted) {
      for (const char* part : {label, "other diagonal", "crop"})
        EXPECT_NE(r.warnings[0].find(part), std::string::npos) << r.warnings[0];
    }
  }
}

// A snapshot camera's frames labelled as a Bayer mosaic (aravissrc gives GRAY8 without a
// pattern, and the user says rggb): every place of the 2x2 cell averages all 25 filters, so the
// greens look in place on average, but the two of each cell differ: darksub says this is no
// Bayer mosaic. (A 5x5 mosaic's cells lie inside a body in one row of its period only: the rows
// looked at move on each frame, or 16 rows apart they would miss it.)
TEST(DarkSubPipeline, warns_when_a_snapshot_mosaic_is_labelled_bayer) {
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("pyrocamsrc");
  if (!have_element("capssetter")) GTEST_SKIP() << "capssetter (gst-plugins-good) missing";
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=30 profile=nir5x5-reference scene=plate temperature=1500 ! "
      "video/x-raw,width=320,height=240 ! capssetter caps=video/x-raw,pattern=rggb ! "
      "darksub dark-level=50 ! fakesink name=sink");
  expect_eos(r, 30);
  ASSERT_EQ(r.warnings.size(), 1u);
  for (const char* part : {"rggb", "no Bayer mosaic", "12 %"})
    EXPECT_NE(r.warnings[0].find(part), std::string::npos) << r.warnings[0];
}

}  // namespace
}  // namespace pyrocam::test
