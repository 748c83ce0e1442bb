// autoexposure: settles on the simulated camera after a 10x step of brightness and then stays;
// frames pass unchanged; a camera without an exposure property gets a warning and the stream
// runs on; clamping to the range is a warning.
#include <algorithm>
#include <cmath>
#include <mutex>

#include "element_support.h"
#include "pyrocam-meta.h"

namespace pyrocam::test {
namespace {

// The 50th brightest value of each frame that reached the fakesink named "sink".
struct Levels {
  std::mutex lock;
  std::vector<int> levels;
};

void on_handoff(GstElement*, GstBuffer* buffer, GstPad*, gpointer data) {
  auto* out = static_cast<Levels*>(data);
  std::vector<std::uint8_t> v = values_of<std::uint8_t>(buffer);
  std::nth_element(v.begin(), v.begin() + 49, v.end(), std::greater<>());
  std::lock_guard<std::mutex> guard(out->lock);
  out->levels.push_back(v[49]);
}

struct RunResult {
  std::vector<int> levels;
  std::vector<std::string> warnings;
  int exposure_messages_after = 0;  // after frame `quiet_from`
  bool eos = false;
};

// Runs `description` (its sink a fakesink named "sink"), with pyrocamsrc's temperature stepped
// from `from_c` to `to_c` at 1 s (frame 30) when the source is named "camera".
RunResult run(const std::string& description, double from_c, double to_c, GstClockTime quiet_from) {
  RunResult r;
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  EXPECT_EQ(error, nullptr);
  if (!pipeline) return r;
  Levels levels;
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_object_set(sink, "signal-handoffs", TRUE, nullptr);
  g_signal_connect(sink, "handoff", G_CALLBACK(on_handoff), &levels);
  if (GstElement* camera = gst_bin_get_by_name(GST_BIN(pipeline), "camera")) {
    EXPECT_TRUE(control_property(camera, "temperature", {{0, from_c}, {GST_SECOND, to_c}}));
    gst_object_unref(camera);
  }
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  for (;;) {
    GstMessage* m = gst_bus_timed_pop(bus, 30 * GST_SECOND);
    if (!m) break;
    const GstMessageType type = GST_MESSAGE_TYPE(m);
    if (type == GST_MESSAGE_WARNING) {
      GError* err = nullptr;
      gst_message_parse_warning(m, &err, nullptr);
      r.warnings.push_back(err->message);
      g_error_free(err);
    } else if (type == GST_MESSAGE_ELEMENT &&
               gst_structure_has_name(gst_message_get_structure(m), "pyrocam-exposure")) {
      guint64 ts = 0;
      gst_structure_get_uint64(gst_message_get_structure(m), "timestamp", &ts);
      if (ts >= quiet_from) ++r.exposure_messages_after;
    }
    const bool end = type == GST_MESSAGE_EOS || type == GST_MESSAGE_ERROR;
    r.eos = type == GST_MESSAGE_EOS;
    gst_message_unref(m);
    if (end) break;
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  r.levels = levels.levels;
  return r;
}

constexpr double kDark = 50.5, kSaturation = 220;  // darksub's default for 8-bit Bayer
const double kTarget = kDark + 0.7 * (kSaturation - kDark);

// Whether a frame's level is within 15 % of the target's signal (the element's tolerance is
// 10 %; the frame-to-frame scatter of the 50th brightest of 76 800 noisy pixels is a few DN).
bool near_target(int level) { return std::abs(level - kTarget) <= 0.15 * (kTarget - kDark); }

TEST(AutoExposure, SettlesWithinTenFramesOfATenfoldStepAndStaysWithoutOscillating) {
  REQUIRE_ELEMENT("autoexposure");
  // A 1400 degC plate, 10x too bright at the start (and saturating), then at frame 30 a step to
  // 1800 degC: about 11x the red band's signal at the same exposure.
  const RunResult r =
      run("pyrocamsrc name=camera scene=plate exposure=20 num-buffers=60 ! "
          "video/x-bayer,width=320,height=240,framerate=30/1 ! autoexposure dark-level=50 ! "
          "fakesink name=sink sync=false",
          1400, 1800, gst_util_uint64_scale(41, GST_SECOND, 30));
  ASSERT_TRUE(r.eos);
  ASSERT_EQ(r.levels.size(), 60u);
  EXPECT_FALSE(near_target(r.levels[0]));   // really a step: saturated at the start
  EXPECT_FALSE(near_target(r.levels[30]));  // and after the scene's step
  for (int i = 10; i < 30; ++i)
    EXPECT_TRUE(near_target(r.levels[i])) << "frame " << i << ": " << r.levels[i];
  for (int i = 40; i < 60; ++i)
    EXPECT_TRUE(near_target(r.levels[i])) << "frame " << i << ": " << r.levels[i];
  EXPECT_EQ(r.exposure_messages_after, 0);  // settled: no more changes
  EXPECT_TRUE(r.warnings.empty());
}

TEST(AutoExposure, ACameraWithoutExposureGetsAWarningAndTheStreamRunsOn) {
  REQUIRE_ELEMENT("autoexposure");
  const RunResult r =
      run("videotestsrc num-buffers=5 ! video/x-raw,format=GRAY8,width=64,height=48 ! "
          "autoexposure ! fakesink name=sink",
          0, 0, 0);
  EXPECT_TRUE(r.eos);
  EXPECT_EQ(r.levels.size(), 5u);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("has no exposure property"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("videotestsrc0"), std::string::npos) << r.warnings[0];
}

TEST(AutoExposure, AnExposureOutsideTheRangeIsClampedWithAWarning) {
  REQUIRE_ELEMENT("autoexposure");
  // 2500 degC with at least 5 us: always saturated, so it wants shorter than it may.
  const RunResult r =
      run("pyrocamsrc name=camera scene=plate exposure=20 num-buffers=10 ! "
          "video/x-bayer,width=320,height=240,framerate=30/1 ! "
          "autoexposure dark-level=50 min-exposure=5 ! fakesink name=sink sync=false",
          2500, 2500, 0);
  EXPECT_TRUE(r.eos);
  EXPECT_EQ(r.levels.back(), 255);
  ASSERT_EQ(r.warnings.size(), 1u);  // once, not every frame
  EXPECT_NE(r.warnings[0].find("outside the camera's range 5.."), std::string::npos)
      << r.warnings[0];
}

// The exposure each frame was taken with reaches the temperatures: the meta passes darksub,
// demosaic25 and ratiotemp.
void on_temperature(GstElement*, GstBuffer* buffer, GstPad*, gpointer data) {
  // By the API's registered name: the plugin registered it, the test does not link it.
  const GType api = g_type_from_name("PyrocamExposureMetaAPI");
  const auto* meta =
      api ? reinterpret_cast<const PyrocamExposureMeta*>(gst_buffer_get_meta(buffer, api))
          : nullptr;
  static_cast<std::vector<double>*>(data)->push_back(meta ? meta->exposure_us : -1);
}

TEST(AutoExposure, EachFramesExposureTravelsThroughTheChainAsAMeta) {
  REQUIRE_ELEMENT("autoexposure");
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  ASSERT_NE(dir, nullptr);
  const std::string launch = std::string(
                                 "pyrocamsrc scene=plate temperature=1400 exposure=20 "
                                 "num-buffers=4 ! video/x-bayer,width=40,height=30 ! "
                                 "autoexposure dark-level=50 ! darksub dark-level=50 ! "
                                 "demosaic25 ! ratiotemp method=likelihood model=") +
                             dir + "/test-model-rgb.json ! fakesink name=sink";
  GstElement* pipeline = gst_parse_launch(launch.c_str(), nullptr);
  ASSERT_NE(pipeline, nullptr);
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  std::vector<double> exposures;
  g_object_set(sink, "signal-handoffs", TRUE, nullptr);
  g_signal_connect(sink, "handoff", G_CALLBACK(on_temperature), &exposures);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstBus* bus = gst_element_get_bus(pipeline);
  GstMessage* m = gst_bus_timed_pop_filtered(
      bus, 60 * GST_SECOND, static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(GST_MESSAGE_TYPE(m), GST_MESSAGE_EOS);
  gst_message_unref(m);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  ASSERT_EQ(exposures.size(), 4u);
  EXPECT_EQ(exposures[0], 20);        // as set
  EXPECT_EQ(exposures[1], 20 / 8.0);  // saturated: one max-step down
  EXPECT_GT(exposures[2], 0);
}

}  // namespace
}  // namespace pyrocam::test
