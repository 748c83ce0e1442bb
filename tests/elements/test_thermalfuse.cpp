// thermalfuse and pyrocamsrc's bracket: the frames cycle through the bracket's exposures, each
// carrying its own; each fused frame is, pixel by pixel, the reading of the most exposed of the
// last `frames` frames that has one; frames without an exposure pass unchanged with a warning.
#include <cstdint>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam-meta.h"

namespace pyrocam::test {
namespace {

struct Frame {
  std::vector<std::uint16_t> codes;
  double exposure_us = -1;
};

void on_frame(GstElement*, GstBuffer* buffer, GstPad*, gpointer data) {
  // By the API's registered name: the plugin registered it, the test does not link it.
  const GType api = g_type_from_name("PyrocamExposureMetaAPI");
  const auto* meta =
      api ? reinterpret_cast<const PyrocamExposureMeta*>(gst_buffer_get_meta(buffer, api))
          : nullptr;
  static_cast<std::vector<Frame>*>(data)->push_back(
      {values_of<std::uint16_t>(buffer), meta ? meta->exposure_us : -1});
}

struct FuseRun {
  std::vector<Frame> frames;
  std::vector<std::string> warnings;
  bool eos = false;
};

FuseRun run(const std::string& launch) {
  FuseRun r;
  GstElement* pipeline = gst_parse_launch(launch.c_str(), nullptr);
  if (pipeline == nullptr) return r;
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_object_set(sink, "signal-handoffs", TRUE, nullptr);
  g_signal_connect(sink, "handoff", G_CALLBACK(on_frame), &r.frames);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstBus* bus = gst_element_get_bus(pipeline);
  for (;;) {
    GstMessage* m = gst_bus_timed_pop_filtered(
        bus, 60 * GST_SECOND,
        static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR | GST_MESSAGE_WARNING));
    if (m == nullptr) break;
    const GstMessageType type = GST_MESSAGE_TYPE(m);
    if (type == GST_MESSAGE_WARNING) {
      GError* e = nullptr;
      gst_message_parse_warning(m, &e, nullptr);
      r.warnings.push_back(e->message);
      g_error_free(e);
    }
    r.eos = type == GST_MESSAGE_EOS;
    gst_message_unref(m);
    if (type != GST_MESSAGE_WARNING) break;
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  return r;
}

std::string chain(const std::string& fuse) {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(
             "pyrocamsrc scene=melt-pool bracket=1,0.333,0.111 num-buffers=9 ! "
             "video/x-bayer,width=64,height=48 ! darksub dark-level=50 ! demosaic25 ! "
             "ratiotemp method=likelihood model=") +
         (dir ? dir : ".") + "/test-model-rgb.json ! " + fuse + " ! fakesink name=sink";
}

TEST(ThermalFuse, EachPixelFromTheMostExposedOfTheLastFramesThatReadsIt) {
  REQUIRE_ELEMENT("thermalfuse");
  const FuseRun plain = run(chain("thermalfuse frames=1")),
                fused = run(chain("thermalfuse frames=3"));
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(plain.frames.size(), 9u);
  ASSERT_EQ(fused.frames.size(), 9u);
  // The bracket: the automatic exposure, a third and a ninth of it, again and again.
  const double e0 = plain.frames[0].exposure_us;
  ASSERT_GT(e0, 0);
  for (std::size_t k = 0; k < 9; ++k) {
    const double factor[] = {1, 0.333, 0.111};
    EXPECT_NEAR(plain.frames[k].exposure_us, e0 * factor[k % 3], 1e-9 * e0);
    EXPECT_EQ(fused.frames[k].exposure_us, plain.frames[k].exposure_us);
  }
  std::size_t from_earlier = 0, plain_readings = 0, fused_readings = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    const std::size_t n = plain.frames[k].codes.size();
    ASSERT_EQ(fused.frames[k].codes.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      // The expected pixel: the most exposed frame of k-2..k that reads it, the latest on ties.
      std::uint16_t want = 0;
      double best = 0;
      for (std::size_t j = k >= 2 ? k - 2 : 0; j <= k; ++j) {
        const std::uint16_t c = plain.frames[j].codes[i];
        if (c != 0 && plain.frames[j].exposure_us >= best) {
          want = c;
          best = plain.frames[j].exposure_us;
        }
      }
      ASSERT_EQ(fused.frames[k].codes[i], want) << "frame " << k << " pixel " << i;
      from_earlier += want != plain.frames[k].codes[i];
      plain_readings += plain.frames[k].codes[i] != 0;
      fused_readings += want != 0;
    }
  }
  // The bracket matters here: the fusion took readings from earlier frames and read more.
  EXPECT_GT(from_earlier, 0u);
  EXPECT_GT(fused_readings, plain_readings);
  EXPECT_TRUE(plain.warnings.empty() && fused.warnings.empty());
}

TEST(ThermalFuse, FramesWithoutAnExposurePassUnchangedWithOneWarning) {
  REQUIRE_ELEMENT("thermalfuse");
  const FuseRun r =
      run("videotestsrc num-buffers=3 ! video/x-raw,format=GRAY16_LE,width=8,height=4 ! "
          "thermalfuse ! fakesink name=sink");
  ASSERT_TRUE(r.eos);
  ASSERT_EQ(r.frames.size(), 3u);
  const FuseRun same =
      run("videotestsrc num-buffers=3 ! video/x-raw,format=GRAY16_LE,width=8,height=4 ! "
          "fakesink name=sink");
  ASSERT_EQ(same.frames.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(r.frames[k].codes, same.frames[k].codes);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("without its exposure"), std::string::npos) << r.warnings[0];
}

TEST(ThermalFuse, ABadBracketStopsTheCameraWithAClearError) {
  REQUIRE_ELEMENT("pyrocamsrc");
  const BusResult r = run_pipeline("pyrocamsrc bracket=1,zero num-buffers=2 ! fakesink name=sink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"bracket", "zero"});
}

}  // namespace
}  // namespace pyrocam::test
