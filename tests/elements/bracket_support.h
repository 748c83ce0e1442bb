// Runs a pipeline ending in `fakesink name=sink` and keeps each buffer's values and the
// exposure of its PyrocamExposureMeta (and its PyrocamSaturationMeta's samples), with the warnings
// on the bus: for the bracket fusions' tests (thermalfuse, mosaicfuse).
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam-meta.h"

namespace pyrocam::test {

template <typename T>
struct BracketFrame {
  std::vector<T> values;
  double exposure_us = -1;   // -1: no exposure metadata
  long long saturated = -1;  // PyrocamSaturationMeta's samples; -1: no saturation metadata
};

template <typename T>
struct BracketRun {
  std::vector<BracketFrame<T>> frames;
  std::vector<std::string> warnings;
  bool eos = false;
};

template <typename T>
void on_bracket_frame(GstElement*, GstBuffer* buffer, GstPad*, gpointer data) {
  // By the API's registered name: the plugin registered it, the test does not link it.
  const GType api = g_type_from_name("PyrocamExposureMetaAPI");
  const auto* meta =
      api ? reinterpret_cast<const PyrocamExposureMeta*>(gst_buffer_get_meta(buffer, api))
          : nullptr;
  const GType saturation_api = g_type_from_name("PyrocamSaturationMetaAPI");
  const auto* saturation = saturation_api ? reinterpret_cast<const PyrocamSaturationMeta*>(
                                                gst_buffer_get_meta(buffer, saturation_api))
                                          : nullptr;
  static_cast<std::vector<BracketFrame<T>>*>(data)->push_back(
      {values_of<T>(buffer), meta ? meta->exposure_us : -1,
       saturation ? static_cast<long long>(saturation->samples) : -1});
}

// Gives the nth buffer (from 1) into an element a time two frames before its own: frames out
// of time order.
struct FrameBackInTime {
  int nth;
  int seen = 0;
  void probe(GstElement* pipeline, const char* element) {
    GstElement* e = gst_bin_get_by_name(GST_BIN(pipeline), element);
    GstPad* pad = gst_element_get_static_pad(e, "sink");
    gst_pad_add_probe(pad, GST_PAD_PROBE_TYPE_BUFFER, on_buffer, this, nullptr);
    gst_object_unref(pad);
    gst_object_unref(e);
  }
  static GstPadProbeReturn on_buffer(GstPad*, GstPadProbeInfo* info, gpointer data) {
    auto* self = static_cast<FrameBackInTime*>(data);
    if (++self->seen == self->nth) {
      GstBuffer* b = gst_buffer_make_writable(GST_PAD_PROBE_INFO_BUFFER(info));
      GST_BUFFER_PTS(b) -= 2 * GST_BUFFER_DURATION(b);
      GST_PAD_PROBE_INFO_DATA(info) = b;
    }
    return GST_PAD_PROBE_OK;
  }
};

// Makes the nth buffer into `element` a frame without an image, as ratiotemp passes on
// darksub's while it captures a dark: no reading anywhere (16-bit codes 0), flagged GAP.
struct GapFrame {
  int nth;
  int seen = 0;
  void probe(GstElement* pipeline, const char* element) {
    GstElement* e = gst_bin_get_by_name(GST_BIN(pipeline), element);
    GstPad* pad = gst_element_get_static_pad(e, "sink");
    gst_pad_add_probe(pad, GST_PAD_PROBE_TYPE_BUFFER, on_buffer, this, nullptr);
    gst_object_unref(pad);
    gst_object_unref(e);
  }
  static GstPadProbeReturn on_buffer(GstPad*, GstPadProbeInfo* info, gpointer data) {
    auto* self = static_cast<GapFrame*>(data);
    if (++self->seen == self->nth) {
      GstBuffer* b = gst_buffer_make_writable(GST_PAD_PROBE_INFO_BUFFER(info));
      gst_buffer_memset(b, 0, 0, gst_buffer_get_size(b));
      GST_BUFFER_FLAG_SET(b, GST_BUFFER_FLAG_GAP);
      GST_PAD_PROBE_INFO_DATA(info) = b;
    }
    return GST_PAD_PROBE_OK;
  }
};

// `prepare`, where given, sees the pipeline before it plays (to add probes).
template <typename T>
BracketRun<T> run_bracket(const std::string& launch,
                          const std::function<void(GstElement*)>& prepare = {}) {
  BracketRun<T> r;
  GstElement* pipeline = gst_parse_launch(launch.c_str(), nullptr);
  if (pipeline == nullptr) return r;
  if (prepare) prepare(pipeline);
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_object_set(sink, "signal-handoffs", TRUE, nullptr);
  g_signal_connect(sink, "handoff", G_CALLBACK(on_bracket_frame<T>), &r.frames);
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

}  // namespace pyrocam::test
