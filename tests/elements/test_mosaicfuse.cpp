// mosaicfuse and pyrocamsrc's bracket: each fused mosaic is, sample by sample, the number of the
// most exposed of the last `frames` frames that has one, scaled to the most exposed frame held,
// whose exposure the buffer then carries; frames without an exposure pass unchanged with a
// warning.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam-meta.h"

namespace pyrocam::test {
namespace {

struct Frame {
  std::vector<float> samples;
  double exposure_us = -1;
};

void on_frame(GstElement*, GstBuffer* buffer, GstPad*, gpointer data) {
  // By the API's registered name: the plugin registered it, the test does not link it.
  const GType api = g_type_from_name("PyrocamExposureMetaAPI");
  const auto* meta =
      api ? reinterpret_cast<const PyrocamExposureMeta*>(gst_buffer_get_meta(buffer, api))
          : nullptr;
  static_cast<std::vector<Frame>*>(data)->push_back(
      {values_of<float>(buffer), meta ? meta->exposure_us : -1});
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
  return "pyrocamsrc scene=melt-pool bracket=1,0.333,0.111 num-buffers=9 ! "
         "video/x-bayer,width=64,height=48 ! darksub dark-level=50 ! " +
         fuse + " ! fakesink name=sink";
}

TEST(MosaicFuse, EachSampleFromTheMostExposedOfTheLastFramesScaledToIt) {
  REQUIRE_ELEMENT("mosaicfuse");
  const FuseRun plain = run(chain("mosaicfuse frames=1")),
                fused = run(chain("mosaicfuse frames=3"));
  ASSERT_TRUE(plain.eos && fused.eos);
  ASSERT_EQ(plain.frames.size(), 9u);
  ASSERT_EQ(fused.frames.size(), 9u);
  std::size_t from_earlier = 0, plain_numbers = 0, fused_numbers = 0;
  for (std::size_t k = 0; k < 9; ++k) {
    const std::size_t first = k >= 2 ? k - 2 : 0;
    // The reference: the most exposed frame held (the latest of equals).
    double reference = 0;
    for (std::size_t j = first; j <= k; ++j)
      reference = std::max(reference, plain.frames[j].exposure_us);
    EXPECT_EQ(fused.frames[k].exposure_us, reference) << "frame " << k;
    const std::size_t n = plain.frames[k].samples.size();
    ASSERT_EQ(fused.frames[k].samples.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      // The expected sample: the most exposed of k-2..k with a number, the latest on ties.
      float want = std::numeric_limits<float>::infinity();
      double best = 0;
      for (std::size_t j = first; j <= k; ++j) {
        const float v = plain.frames[j].samples[i];
        if (std::isfinite(v) && plain.frames[j].exposure_us >= best) {
          best = plain.frames[j].exposure_us;
          want = v * static_cast<float>(reference / best);
        }
      }
      ASSERT_EQ(fused.frames[k].samples[i], want) << "frame " << k << " sample " << i;
      from_earlier += want != plain.frames[k].samples[i];
      plain_numbers += std::isfinite(plain.frames[k].samples[i]);
      fused_numbers += std::isfinite(want);
    }
  }
  // The bracket matters here: samples came from other frames, and more of them are numbers.
  EXPECT_GT(from_earlier, 0u);
  EXPECT_GT(fused_numbers, plain_numbers);
  EXPECT_TRUE(plain.warnings.empty() && fused.warnings.empty());
}

TEST(MosaicFuse, FramesWithoutAnExposurePassUnchangedWithOneWarning) {
  REQUIRE_ELEMENT("mosaicfuse");
  const std::string source =
      "videotestsrc num-buffers=3 ! video/x-raw,format=GRAY8,width=8,height=4 ! "
      "darksub pattern=rggb dark-level=0 ! ";
  const FuseRun r = run(source + "mosaicfuse frames=3 ! fakesink name=sink"),
                same = run(source + "fakesink name=sink");
  ASSERT_TRUE(r.eos);
  ASSERT_EQ(r.frames.size(), 3u);
  ASSERT_EQ(same.frames.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) EXPECT_EQ(r.frames[k].samples, same.frames[k].samples);
  ASSERT_EQ(r.warnings.size(), 1u);
  EXPECT_NE(r.warnings[0].find("without its exposure"), std::string::npos) << r.warnings[0];
}

}  // namespace
}  // namespace pyrocam::test
