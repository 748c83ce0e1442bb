#include "element_support.h"

#include <gst/controller/gstdirectcontrolbinding.h>
#include <gst/controller/gstinterpolationcontrolsource.h>

namespace pyrocam::test {

bool have_element(const char* name) {
  GstElementFactory* f = gst_element_factory_find(name);
  if (!f) return false;
  gst_object_unref(f);
  return true;
}

BusResult run_pipeline(const std::string& description, GstClockTime timeout) {
  BusResult r;
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  if (!pipeline || error) {
    r.error = true;
    r.message = error ? error->message : "gst_parse_launch failed";
    if (error) g_error_free(error);
    if (pipeline) gst_object_unref(pipeline);
    return r;
  }
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  if (sink) {
    g_object_set(sink, "signal-handoffs", TRUE, nullptr);
    g_signal_connect(sink, "handoff",
                     G_CALLBACK(+[](GstElement*, GstBuffer*, GstPad*, gpointer count) {
                       g_atomic_int_inc(static_cast<int*>(count));
                     }),
                     &r.buffers);
  }
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstMessage* msg = gst_bus_timed_pop_filtered(
      bus, timeout, static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  if (!msg) {
    r.timed_out = true;
  } else if (GST_MESSAGE_TYPE(msg) == GST_MESSAGE_EOS) {
    r.eos = true;
  } else {
    GError* err = nullptr;
    gchar* dbg = nullptr;
    gst_message_parse_error(msg, &err, &dbg);
    r.error = true;
    r.domain = err->domain;
    r.code = err->code;
    r.message = err->message;
    r.debug = dbg ? dbg : "";
    r.source = GST_OBJECT_NAME(GST_MESSAGE_SRC(msg));
    g_error_free(err);
    g_free(dbg);
  }
  if (msg) gst_message_unref(msg);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  if (sink) gst_object_unref(sink);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
  return r;
}

std::string sink_caps(GstHarness* h) {
  GstCaps* caps = gst_pad_get_current_caps(h->sinkpad);
  if (!caps) return "";
  gchar* s = gst_caps_to_string(caps);
  std::string out = s;
  g_free(s);
  gst_caps_unref(caps);
  return out;
}

GstElement* find_element(GstHarness* h, const char* factory) {
  return gst_harness_find_element(h, factory);
}

bool control_property(GstElement* element, const char* property,
                      const std::vector<std::pair<GstClockTime, double>>& points) {
  GstControlSource* source = gst_interpolation_control_source_new();
  g_object_set(source, "mode", GST_INTERPOLATION_MODE_NONE, nullptr);
  for (const auto& [time, value] : points)
    gst_timed_value_control_source_set(GST_TIMED_VALUE_CONTROL_SOURCE(source), time, value);
  const gboolean added = gst_object_add_control_binding(
      GST_OBJECT(element),
      gst_direct_control_binding_new_absolute(GST_OBJECT(element), property, source));
  gst_object_unref(source);
  return added;
}

}  // namespace pyrocam::test

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
