// pyrocamsrc: caps per profile, negotiated sizes, timestamps, determinism, live property
// changes, bus errors, and the smoke pipeline through darksub and demosaic25.
#include "element_support.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

class PyrocamSrc : public HarnessTest {
 protected:
  PyrocamSrc() : HarnessTest("pyrocamsrc") {}
};

// The mean of the central 8x4 pixels of a 40x20 frame.
double centre_mean(const std::vector<std::uint8_t>& v) {
  double sum = 0;
  for (int y = 8; y < 12; ++y)
    for (int x = 16; x < 24; ++x) sum += v[y * 40 + x];
  return sum / 32;
}

TEST_F(PyrocamSrc, colour_profile_gives_bayer_frames_with_timestamps) {
  h = gst_harness_new_parse("pyrocamsrc scene=plate temperature=1100");
  gst_harness_play(h);
  for (guint64 i = 0; i < 3; ++i) {
    GstBuffer* b = gst_harness_pull(h);
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(gst_buffer_get_size(b), 320u * 240u);
    EXPECT_EQ(GST_BUFFER_PTS(b), gst_util_uint64_scale(i, GST_SECOND, 30));
    EXPECT_EQ(GST_BUFFER_DURATION(b), gst_util_uint64_scale(i + 1, GST_SECOND, 30) -
                                          gst_util_uint64_scale(i, GST_SECOND, 30));
    EXPECT_EQ(GST_BUFFER_OFFSET(b), i);
    if (i == 0) {
      // The plate (central 60 %) glows: its mean is well above the dark level of 50 DN.
      const auto v = values_of<std::uint8_t>(b);
      double centre = 0;
      for (int x = 140; x < 180; ++x) centre += v[120 * 320 + x];
      EXPECT_GT(centre / 40, 80);
      EXPECT_LT(v[0], 60);  // the cold corner shows the dark level
    }
    gst_buffer_unref(b);
  }
  const std::string caps = sink_caps(h);
  for (const char* part : {"video/x-bayer", "format=(string)rggb", "width=(int)320",
                           "height=(int)240", "framerate=(fraction)30/1"})
    EXPECT_NE(caps.find(part), std::string::npos) << part << " in " << caps;
}

TEST_F(PyrocamSrc, snapshot_profile_gives_gray8_of_the_negotiated_size) {
  h = gst_harness_new_parse("pyrocamsrc profile=nir5x5-reference scene=filament");
  gst_harness_set_sink_caps_str(h, "video/x-raw,width=100,height=50,framerate=10/1");
  gst_harness_play(h);
  GstBuffer* b = gst_harness_pull(h);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(gst_buffer_get_size(b), 100u * 50u);
  gst_buffer_unref(b);
  b = gst_harness_pull(h);
  ASSERT_NE(b, nullptr);
  EXPECT_EQ(GST_BUFFER_PTS(b), GST_SECOND / 10);
  gst_buffer_unref(b);
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("format=(string)GRAY8"), std::string::npos) << caps;
}

std::vector<std::uint8_t> first_frame(const char* launch) {
  GstHarness* h = gst_harness_new_parse(launch);
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20");
  gst_harness_play(h);
  GstBuffer* b = gst_harness_pull(h);
  std::vector<std::uint8_t> v = b ? values_of<std::uint8_t>(b) : std::vector<std::uint8_t>{};
  if (b) gst_buffer_unref(b);
  gst_harness_teardown(h);
  return v;
}

TEST_F(PyrocamSrc, equal_seeds_give_equal_frames) {
  const auto a = first_frame("pyrocamsrc seed=5");
  EXPECT_EQ(a.size(), 40u * 20u);
  EXPECT_EQ(a, first_frame("pyrocamsrc seed=5"));
  EXPECT_NE(a, first_frame("pyrocamsrc seed=6"));
}

TEST_F(PyrocamSrc, exposure_change_while_playing_brightens_frames) {
  h = gst_harness_new_parse("pyrocamsrc scene=plate exposure=20 unit=datasheet");
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20");
  gst_harness_set_blocking_push_mode(h);  // the source waits for each pull
  gst_harness_play(h);
  auto next_centre_mean = [&] {
    GstBuffer* b = gst_harness_pull(h);
    const auto v = b ? values_of<std::uint8_t>(b) : std::vector<std::uint8_t>(40 * 20, 0);
    if (b) gst_buffer_unref(b);
    return centre_mean(v);
  };
  const double dim = next_centre_mean();
  gst_harness_set(h, "pyrocamsrc", "exposure", 200.0, nullptr);
  // Frames rendered before the change may still be queued in the harness.
  double bright = 0;
  for (int i = 0; i < 5 && bright < dim + 20; ++i) bright = next_centre_mean();
  EXPECT_GT(bright, dim + 20);
}

TEST_F(PyrocamSrc, controlled_temperature_follows_the_controller_by_frame_time) {
  // A fixed exposure that puts a 1100 degC plate's brightest band at 140 DN: 900 degC is then
  // an order of magnitude dimmer.
  const Simulator camera(load_profile_by_name("rgb-reference"),
                         UnitPerturbation::parse("datasheet", 1));
  const double exposure = camera.exposure_for(1100, 140, kSceneDefaults.plate_emissivity);
  h = gst_harness_new_parse(
      ("pyrocamsrc scene=plate unit=datasheet temperature=900 exposure=" + std::to_string(exposure))
          .c_str());
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20,framerate=10/1");
  GstElement* e = find_element(h, "pyrocamsrc");
  // 900 degC for the first two frames (0 and 0.1 s), 1100 degC from 0.2 s on.
  ASSERT_TRUE(control_property(e, "temperature", {{0, 900.0}, {GST_SECOND / 5, 1100.0}}));
  gst_object_unref(e);
  gst_harness_play(h);
  std::vector<double> means;
  for (int i = 0; i < 4; ++i) {
    GstBuffer* b = gst_harness_pull(h);
    ASSERT_NE(b, nullptr);
    means.push_back(centre_mean(values_of<std::uint8_t>(b)));
    gst_buffer_unref(b);
  }
  EXPECT_NEAR(means[1], means[0], 5);
  EXPECT_GT(means[2], means[1] + 20);  // the hotter plate
  EXPECT_NEAR(means[3], means[2], 5);
}

TEST(PyrocamSrcPipeline, smoke_runs_through_darksub_and_demosaic25_to_eos) {
  REQUIRE_ELEMENT("pyrocamsrc");
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("demosaic25");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=5 ! darksub dark-level=50 ! demosaic25 ! fakesink name=sink");
  expect_eos(r, 5);
}

TEST(PyrocamSrcPipeline, live_snapshot_camera_through_the_chain) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(
      "pyrocamsrc is-live=true num-buffers=3 profile=nir5x5-reference ! "
      "video/x-raw,framerate=50/1 ! darksub dark-level=50 pattern=5x5 ! demosaic25 ! "
      "fakesink name=sink sync=true");
  expect_eos(r, 3);
}

TEST(PyrocamSrcErrors, rejects_a_missing_profile) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline("pyrocamsrc profile=/nonexistent/camera.json ! fakesink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND, {"/nonexistent/camera.json"});
}

TEST(PyrocamSrcErrors, rejects_a_corrupt_profile) {
  REQUIRE_ELEMENT("pyrocamsrc");
  ScratchDir dir("pyrocamsrc-profile");
  write_text(dir / "camera.json", "{ \"format\": \"pyrocam-camera-profile\", ");
  const auto r =
      run_pipeline("pyrocamsrc profile=" + (dir / "camera.json").string() + " ! fakesink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_READ, {"camera.json"});
}

TEST(PyrocamSrcErrors, rejects_a_size_that_is_not_whole_macro_pixels) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(
      "pyrocamsrc profile=nir5x5-reference num-buffers=1 ! video/x-raw,width=64,height=48 ! "
      "fakesink");
  ASSERT_TRUE(r.error);
  EXPECT_NE(r.message.find("64x48"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace pyrocam::test
