// thermaloverlay: each camera frame goes out under the overlay with its own timestamp, waiting
// for it; older overlays are dropped; a frame whose overlay cannot come goes out bare; latency;
// sizes that differ are an error.
#include <gst/check/gstharness.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "element_support.h"

namespace pyrocam::test {
namespace {

constexpr int kW = 4, kH = 2;
const char* const kCaps = "video/x-raw,format=RGBA,width=4,height=2,framerate=30/1";

GstClockTime frame_time(int n) { return gst_util_uint64_scale(n, GST_SECOND, 30); }

// A camera frame of one grey level, opaque.
GstBuffer* camera_frame(int n, std::uint8_t level) {
  return with_pts(buffer_from(std::vector<std::uint8_t>(kW * kH * 4, level)), frame_time(n));
}

// An overlay whose first pixel is opaque `red` and the others transparent.
GstBuffer* overlay_frame(int n, std::uint8_t red) {
  std::vector<std::uint8_t> v(kW * kH * 4, 0);
  v[0] = red;
  v[3] = 255;
  return with_pts(buffer_from(v), frame_time(n));
}

class ThermalOverlay : public ::testing::Test {
 protected:
  void SetUp() override {
    REQUIRE_ELEMENT("thermaloverlay");
    video = gst_harness_new_with_padnames("thermaloverlay", "video_sink", "src");
    overlay = gst_harness_new_with_element(video->element, "overlay_sink", nullptr);
    gst_harness_set_src_caps_str(video, kCaps);
    gst_harness_set_src_caps_str(overlay, kCaps);
  }
  void TearDown() override {
    if (overlay != nullptr) gst_harness_teardown(overlay);
    if (video != nullptr) gst_harness_teardown(video);
  }
  // The first pixel's red byte of the next output frame, and whether it kept its timestamp n.
  int next_red(int n) {
    GstBuffer* out = gst_harness_try_pull(video);
    if (out == nullptr) return -1;
    EXPECT_EQ(GST_BUFFER_PTS(out), frame_time(n));
    const int red = values_of<std::uint8_t>(out)[0];
    gst_buffer_unref(out);
    return red;
  }

  GstHarness* video = nullptr;
  GstHarness* overlay = nullptr;
};

TEST_F(ThermalOverlay, PairsEachFrameWithTheOverlayOfItsTimestamp) {
  // Overlays 0 and 1 come before the frames; overlay 0 has no frame (dropped).
  ASSERT_EQ(gst_harness_push(overlay, overlay_frame(0, 200)), GST_FLOW_OK);
  ASSERT_EQ(gst_harness_push(overlay, overlay_frame(1, 201)), GST_FLOW_OK);
  ASSERT_EQ(gst_harness_push(overlay, overlay_frame(3, 203)), GST_FLOW_OK);
  ASSERT_EQ(gst_harness_push(video, camera_frame(1, 10)), GST_FLOW_OK);
  EXPECT_EQ(next_red(1), 201);
  // Frame 2's overlay never came (the next one is frame 3's): bare.
  ASSERT_EQ(gst_harness_push(video, camera_frame(2, 10)), GST_FLOW_OK);
  EXPECT_EQ(next_red(2), 10);
  ASSERT_EQ(gst_harness_push(video, camera_frame(3, 10)), GST_FLOW_OK);
  EXPECT_EQ(next_red(3), 203);
  // The transparent pixels keep the camera's colour.
  ASSERT_EQ(gst_harness_push(overlay, overlay_frame(4, 204)), GST_FLOW_OK);
  ASSERT_EQ(gst_harness_push(video, camera_frame(4, 10)), GST_FLOW_OK);
  GstBuffer* out = gst_harness_pull(video);
  const auto bytes = values_of<std::uint8_t>(out);
  gst_buffer_unref(out);
  EXPECT_EQ(bytes[0], 204);
  EXPECT_EQ(bytes[4], 10);
  EXPECT_EQ(bytes[kW * kH * 4 - 2], 10);
}

TEST_F(ThermalOverlay, AFrameWaitsForItsOverlayHoweverLate) {
  std::atomic<bool> pushing{false}, pushed{false};
  std::thread camera([&] {
    pushing = true;
    EXPECT_EQ(gst_harness_push(video, camera_frame(0, 10)), GST_FLOW_OK);
    pushed = true;
  });
  while (!pushing) std::this_thread::yield();
  // Nothing goes out while the overlay is not there (here 300 ms; the wait has no limit).
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_FALSE(pushed) << "the camera's frame did not wait for its overlay";
  EXPECT_EQ(gst_harness_buffers_received(video), 0u);
  ASSERT_EQ(gst_harness_push(overlay, overlay_frame(0, 222)), GST_FLOW_OK);
  camera.join();
  EXPECT_EQ(next_red(0), 222);
}

TEST_F(ThermalOverlay, FramesGoBareOnceTheOverlaysEnded) {
  ASSERT_TRUE(gst_harness_push_event(overlay, gst_event_new_eos()));
  ASSERT_EQ(gst_harness_push(video, camera_frame(0, 10)), GST_FLOW_OK);
  EXPECT_EQ(next_red(0), 10);
}

TEST_F(ThermalOverlay, ReportsItsLatencyDownstream) {
  g_object_set(video->element, "latency", guint64{250 * GST_MSECOND}, nullptr);
  GstQuery* q = gst_query_new_latency();
  ASSERT_TRUE(gst_pad_peer_query(video->sinkpad, q));
  GstClockTime min = 0, max = 0;
  gboolean live = FALSE;
  gst_query_parse_latency(q, &live, &min, &max);
  gst_query_unref(q);
  EXPECT_EQ(min, 250 * GST_MSECOND);
}

TEST(ThermalOverlayPipeline, AnOverlayOfAnotherSizeIsAnError) {
  REQUIRE_ELEMENT("thermaloverlay");
  const BusResult r = run_pipeline(
      "videotestsrc num-buffers=3 ! video/x-raw,format=RGBA,width=16,height=16 ! "
      "mix.video_sink videotestsrc num-buffers=3 ! video/x-raw,format=RGBA,width=8,height=8 ! "
      "mix.overlay_sink thermaloverlay name=mix ! fakesink name=sink");
  expect_error(r, GST_STREAM_ERROR, GST_STREAM_ERROR_FORMAT, {"8x8", "16x16"});
}

// Nothing linked to overlay_sink: each frame waited for an overlay that could not come, and the
// pipeline prerolled for ever without a word. Frames go out bare, with a warning.
TEST(ThermalOverlayPipeline, WithoutAnOverlayLinkedFramesGoOutBareWithAWarning) {
  REQUIRE_ELEMENT("thermaloverlay");
  const BusResult r = run_pipeline(
      "videotestsrc num-buffers=5 ! video/x-raw,format=RGBA,width=16,height=16 ! "
      "mix.video_sink thermaloverlay name=mix ! fakesink name=sink");
  expect_eos(r, 5);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("nothing is linked to overlay_sink"), std::string::npos)
      << r.warnings[0];
}

TEST(ThermalOverlayPipeline, RunsToTheEndWithEveryFrame) {
  REQUIRE_ELEMENT("thermaloverlay");
  const BusResult r = run_pipeline(
      "videotestsrc num-buffers=5 ! video/x-raw,format=BGRx,width=16,height=16 ! "
      "mix.video_sink videotestsrc num-buffers=5 pattern=ball ! "
      "video/x-raw,format=RGBA,width=16,height=16 ! mix.overlay_sink "
      "thermaloverlay name=mix ! fakesink name=sink");
  expect_eos(r, 5);
}

}  // namespace
}  // namespace pyrocam::test
