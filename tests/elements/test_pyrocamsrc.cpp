// pyrocamsrc: caps per profile, negotiated sizes, timestamps, determinism, live property
// changes, gain, bus errors, and the smoke pipeline through darksub and demosaic25.
#include <cmath>
#include <cstdio>
#include <string>

#include "element_support.h"
#include "pyrocam-meta.h"
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

// The red pixels of the 1100 degC plate's central 24x12 over `frames` frames of 40x20: their mean
// signal above the 50 DN dark level, and the temporal noise variance (from frame-to-frame
// differences, free of the fixed patterns), DN^2; and the last frame's meta gain.
struct PlateNoise {
  double mean = 0, variance = 0, gain_db = -1;
};
PlateNoise plate_noise(const std::string& properties, int frames) {
  GstHarness* h = gst_harness_new_parse(
      ("pyrocamsrc scene=plate temperature=1100 unit=datasheet " + properties).c_str());
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20");
  gst_harness_play(h);
  PlateNoise n;
  std::vector<std::uint8_t> previous;
  double sum = 0, squares = 0;
  int count = 0, pairs = 0;
  for (int f = 0; f < frames; ++f) {
    GstBuffer* b = gst_harness_pull(h);
    if (!b) break;
    const auto v = values_of<std::uint8_t>(b);
    const GType api = g_type_from_name("PyrocamExposureMetaAPI");
    const auto* meta =
        api ? reinterpret_cast<const PyrocamExposureMeta*>(gst_buffer_get_meta(b, api)) : nullptr;
    n.gain_db = meta ? meta->gain_db : -1;
    gst_buffer_unref(b);
    // Red pixels only (one band: one noise level; the brightest, 140 DN), even x and y in RGGB.
    for (int y = 4; y < 16; y += 2)
      for (int x = 8; x < 32; x += 2) {
        const int i = y * 40 + x;
        sum += v[i] - 50;
        ++count;
        if (!previous.empty()) {
          const double d = static_cast<double>(v[i]) - previous[i];
          squares += d * d;
          ++pairs;
        }
      }
    previous = v;
  }
  gst_harness_teardown(h);
  n.mean = count ? sum / count : 0;
  n.variance = pairs ? squares / pairs / 2 : 0;
  return n;
}

TEST_F(PyrocamSrc, gain_multiplies_the_signal_and_its_shot_noise) {
  // 12 dB (x3.98) with a quarter of the exposure: about the same signal; the shot noise in DN^2
  // per DN of signal 3.98 times as large, the read noise (0.2 DN) the same.
  const Simulator camera(load_profile_by_name("rgb-reference"),
                         UnitPerturbation::parse("datasheet", 1));
  const double exposure = camera.exposure_for(1100, 140, kSceneDefaults.plate_emissivity);
  const PlateNoise plain = plate_noise("exposure=" + std::to_string(exposure), 24);
  const PlateNoise gained = plate_noise("gain=12 exposure=" + std::to_string(exposure / 4), 24);
  const double factor = std::pow(10.0, 12.0 / 20);
  std::printf("[ figures  ] 0 dB: %.1f DN, %.2f DN^2; 12 dB, exposure / 4: %.1f DN, %.2f DN^2\n",
              plain.mean, plain.variance, gained.mean, gained.variance);
  EXPECT_EQ(plain.gain_db, 0);
  EXPECT_EQ(gained.gain_db, 12);
  // 72 pixels x 24 frames: the mean's scatter is well below 1 DN; 3.98 / 4 = 0.995 of the signal.
  EXPECT_NEAR(gained.mean, plain.mean * factor / 4, 0.03 * plain.mean);
  // Variance estimates from 1656 differences scatter by about 3.5 %, their ratio by 5 %: about
  // 3.9 expected (3.98, a little less with the floor of read noise and quantisation, 0.1 DN^2
  // against 4 DN^2 of shot noise at 0 dB); the bounds are 3 sigma and more away.
  EXPECT_GT(gained.variance / plain.variance, 2.8);
  EXPECT_LT(gained.variance / plain.variance, 4.8);
}

// A cold plate's automatic exposure (7500 s at 300 degC) is held to the property's 10 s: frames
// at the black level with noise, not all zero, and meta saying 10 s.
TEST_F(PyrocamSrc, automatic_exposure_of_a_cold_scene_stays_in_range) {
  h = gst_harness_new_parse("pyrocamsrc scene=plate temperature=300");
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20");
  gst_harness_play(h);
  GstBuffer* b = gst_harness_pull(h);
  ASSERT_NE(b, nullptr);
  const GType api = g_type_from_name("PyrocamExposureMetaAPI");  // the plugin's, loaded
  const auto* meta =
      api ? reinterpret_cast<const PyrocamExposureMeta*>(gst_buffer_get_meta(b, api)) : nullptr;
  ASSERT_NE(meta, nullptr);
  EXPECT_EQ(meta->exposure_us, 1e7);
  const double mean = centre_mean(values_of<std::uint8_t>(b));
  EXPECT_GT(mean, 45);  // the profiles' 50 DN black level, a plate barely glowing on it
  EXPECT_LT(mean, 60);
  gst_buffer_unref(b);
}

// A bracket that does not parse, set while playing, is refused on the bus; the bracket in use
// stays, and reads back (it read back the refused text, and a restart then used the old one
// silently).
TEST_F(PyrocamSrc, a_bad_bracket_set_while_playing_is_refused_on_the_bus_n) {
  h = gst_harness_new_parse("pyrocamsrc scene=plate temperature=1500 bracket=1,0.5");
  attach_bus();
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20");
  gst_harness_play(h);
  gst_buffer_unref(gst_harness_pull(h));
  GstElement* src = find_element(h, "pyrocamsrc");
  g_object_set(src, "bracket", "abc", nullptr);
  gchar* bracket = nullptr;
  g_object_get(src, "bracket", &bracket, nullptr);
  EXPECT_STREQ(bracket, "1,0.5");
  g_free(bracket);
  gst_object_unref(src);
  GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_WARNING);
  ASSERT_NE(m, nullptr);
  GError* err = nullptr;
  gst_message_parse_warning(m, &err, nullptr);
  EXPECT_NE(std::string(err->message).find("bracket 'abc' refused"), std::string::npos)
      << err->message;
  EXPECT_NE(std::string(err->message).find("the bracket stays '1,0.5'"), std::string::npos)
      << err->message;
  g_error_free(err);
  gst_message_unref(m);
}

// is-live set while playing: basesrc waited for a PLAYING that had come, and no frame came
// again. It is refused with a warning, and the frames go on.
TEST_F(PyrocamSrc, is_live_set_while_playing_is_refused_and_the_frames_go_on_n) {
  h = gst_harness_new_parse("pyrocamsrc scene=plate temperature=1500");
  attach_bus();
  gst_harness_set_sink_caps_str(h, "video/x-bayer,width=40,height=20");
  gst_harness_play(h);
  gst_buffer_unref(gst_harness_pull(h));
  GstElement* src = find_element(h, "pyrocamsrc");
  g_object_set(src, "is-live", TRUE, nullptr);
  gboolean live = TRUE;
  g_object_get(src, "is-live", &live, nullptr);
  EXPECT_FALSE(live);
  gst_object_unref(src);
  for (int i = 0; i < 3; ++i) {
    GstBuffer* b = gst_harness_pull(h);  // blocked for ever before
    ASSERT_NE(b, nullptr);
    gst_buffer_unref(b);
  }
  GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_WARNING);
  ASSERT_NE(m, nullptr);
  GError* err = nullptr;
  gst_message_parse_warning(m, &err, nullptr);
  EXPECT_NE(std::string(err->message).find("is-live"), std::string::npos) << err->message;
  g_error_free(err);
  gst_message_unref(m);
}

TEST(PyrocamSrcPipeline, smoke_runs_through_darksub_and_demosaic25_to_eos) {
  REQUIRE_ELEMENT("pyrocamsrc");
  REQUIRE_ELEMENT("darksub");
  REQUIRE_ELEMENT("demosaic25");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=5 ! darksub dark-level=50 ! demosaic25 ! fakesink name=sink");
  expect_eos(r, 5);
}

// Bayer frames carried as GRAY8 (capssetter) into an element that proposes a buffer pool for
// its own caps: the frames go into pyrocamsrc's own pool ("output buffer too small" before).
TEST(PyrocamSrcPipeline, frames_fill_their_own_pool_whatever_downstream_proposes) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=5 ! video/x-bayer,width=320,height=240,framerate=30/1 ! "
      "capssetter join=false caps=video/x-raw,format=GRAY8,width=320,height=240,"
      "framerate=30/1 ! videoflip video-direction=horiz ! fakesink name=sink");
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

// A path to a file that is no .json was looked up as a shipped profile's name ("/etc/passwd.json:
// camera profile not found").
TEST(PyrocamSrcErrors, names_a_path_that_is_no_profile_n) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline("pyrocamsrc profile=/etc/passwd ! fakesink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_READ,
               {"/etc/passwd: not a camera profile"});
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

TEST(PyrocamSrcErrors, names_a_variable_frame_rate_n) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline("pyrocamsrc num-buffers=1 ! video/x-bayer,framerate=0/1 ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"framerate 0/1"});
}

// GstBaseSrc alone says "Internal data stream error ... not-negotiated".
TEST(PyrocamSrcErrors, names_a_mosaic_downstream_does_not_take_n) {
  REQUIRE_ELEMENT("pyrocamsrc");
  auto r = run_pipeline("pyrocamsrc num-buffers=1 ! video/x-bayer,format=bggr ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"profile rgb-reference gives video/x-bayer, format=(string)rggb",
                "downstream does not take", "format=(string)bggr"});
  r = run_pipeline("pyrocamsrc profile=nir5x5-reference num-buffers=1 ! video/x-bayer ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"profile nir5x5-reference gives video/x-raw, format=(string)GRAY8"});
  EXPECT_EQ(r.message.find("band-map"), std::string::npos) << r.message;
}

}  // namespace
}  // namespace pyrocam::test
