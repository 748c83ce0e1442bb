#include "element_support.h"

#include <gst/controller/gstdirectcontrolbinding.h>
#include <gst/controller/gstinterpolationcontrolsource.h>

#include <algorithm>
#include <cmath>

namespace pyrocam::test {

GstClockTime scaled_timeout(GstClockTime timeout) {
  const char* factor = g_getenv("PYROCAM_TEST_TIME_FACTOR");
  const double f = factor ? g_ascii_strtod(factor, nullptr) : 1.0;
  return f > 1 && f < 1000 ? static_cast<GstClockTime>(static_cast<double>(timeout) * f) : timeout;
}

bool have_element(const char* name) {
  GstElementFactory* f = gst_element_factory_find(name);
  if (!f) return false;
  gst_object_unref(f);
  return true;
}

BusResult run_pipeline(const std::string& description, GstClockTime timeout, bool until_warning) {
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
  // Warnings are collected on the way to the end.
  const GstClockTime deadline = gst_util_get_timestamp() + scaled_timeout(timeout);
  GstMessage* msg = nullptr;
  for (;;) {
    const GstClockTime now = gst_util_get_timestamp();
    msg = gst_bus_timed_pop_filtered(
        bus, now < deadline ? deadline - now : 0,
        static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR | GST_MESSAGE_WARNING));
    if (!msg || GST_MESSAGE_TYPE(msg) != GST_MESSAGE_WARNING) break;
    GError* warning = nullptr;
    gst_message_parse_warning(msg, &warning, nullptr);
    r.warnings.push_back(warning->message);
    g_error_free(warning);
    gst_message_unref(msg);
    msg = nullptr;
    if (until_warning) break;
  }
  if (until_warning && !r.warnings.empty()) {
    gst_element_set_state(pipeline, GST_STATE_NULL);
    if (sink) gst_object_unref(sink);
    gst_object_unref(bus);
    gst_object_unref(pipeline);
    return r;
  }
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
  // READY stops the streaming threads; NULL would flush what they posted before.
  gst_element_set_state(pipeline, GST_STATE_READY);
  r.errors = r.error ? 1 : 0;
  while (GstMessage* more = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
    ++r.errors;
    gst_message_unref(more);
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  if (sink) gst_object_unref(sink);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
  return r;
}

void expect_error(const BusResult& r, GQuark domain, int code,
                  std::initializer_list<std::string> parts) {
  ASSERT_TRUE(r.error) << "no error; eos " << r.eos << ", timed out " << r.timed_out;
  EXPECT_EQ(r.domain, domain) << g_quark_to_string(r.domain) << ": " << r.message;
  EXPECT_EQ(r.code, code) << r.message;
  for (const std::string& part : parts)
    EXPECT_NE(r.message.find(part), std::string::npos) << part << " in " << r.message;
}

void expect_eos(const BusResult& r, int buffers) {
  EXPECT_TRUE(r.eos) << r.message << " " << r.debug;
  EXPECT_EQ(r.buffers, buffers);
}

GstBuffer* with_pts(GstBuffer* buffer, GstClockTime pts) {
  GST_BUFFER_PTS(buffer) = pts;
  return buffer;
}

GstBuffer* push_pull_buffer(GstHarness* h, GstBuffer* in) {
  EXPECT_EQ(gst_harness_push(h, in), GST_FLOW_OK);
  return gst_harness_try_pull(h);
}

void push_flush(GstHarness* h) {
  EXPECT_TRUE(gst_harness_push_event(h, gst_event_new_flush_start()));
  EXPECT_TRUE(gst_harness_push_event(h, gst_event_new_flush_stop(TRUE)));
  GstSegment segment;
  gst_segment_init(&segment, GST_FORMAT_TIME);
  EXPECT_TRUE(gst_harness_push_event(h, gst_event_new_segment(&segment)));
}

bool eos_passes(GstHarness* h) {
  EXPECT_TRUE(gst_harness_push_event(h, gst_event_new_eos()));
  bool eos = false;
  while (GstEvent* ev = gst_harness_try_pull_event(h)) {
    eos |= GST_EVENT_TYPE(ev) == GST_EVENT_EOS;
    gst_event_unref(ev);
  }
  return eos;
}

std::string current_caps(GstPad* pad) {
  GstCaps* caps = gst_pad_get_current_caps(pad);
  if (!caps) return "";
  gchar* s = gst_caps_to_string(caps);
  std::string out = s;
  g_free(s);
  gst_caps_unref(caps);
  return out;
}

std::string sink_caps(GstHarness* h) { return current_caps(h->sinkpad); }

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

void HarnessTest::TearDown() {
  if (bus) {
    gst_element_set_bus(h->element, nullptr);
    gst_object_unref(bus);
    bus = nullptr;
  }
  if (h) gst_harness_teardown(h);
  h = nullptr;
}

std::string test_model_path(const std::string& name) {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(dir ? dir : ".") + "/" + name;
}

double field_double(const GstStructure* s, const char* name) {
  double v = NAN;
  EXPECT_TRUE(gst_structure_get_double(s, name, &v)) << name;
  return v;
}

void free_all(std::vector<GstStructure*>& v) {
  for (GstStructure* s : v) gst_structure_free(s);
  v.clear();
}

std::size_t count_nonzero(const std::vector<std::uint16_t>& v) {
  return static_cast<std::size_t>(std::count_if(v.begin(), v.end(), [](auto c) { return c; }));
}

// The bytes of every buffer that reaches the fakesink named "sink" of a pipeline run to EOS.
std::vector<std::vector<std::uint8_t>> sink_frames(const std::string& description,
                                                   GstClockTime timeout) {
  std::vector<std::vector<std::uint8_t>> frames;
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  EXPECT_TRUE(pipeline && !error) << (error ? error->message : "");
  if (error) g_error_free(error);
  if (!pipeline) return frames;
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "sink");
  g_object_set(sink, "signal-handoffs", TRUE, nullptr);
  g_signal_connect(sink, "handoff",
                   G_CALLBACK(+[](GstElement*, GstBuffer* b, GstPad*, gpointer out) {
                     static_cast<std::vector<std::vector<std::uint8_t>>*>(out)->push_back(
                         values_of<std::uint8_t>(b));
                   }),
                   &frames);
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstMessage* msg =
      gst_bus_timed_pop_filtered(bus, scaled_timeout(timeout),
                                 static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR));
  EXPECT_TRUE(msg && GST_MESSAGE_TYPE(msg) == GST_MESSAGE_EOS) << description;
  if (msg) gst_message_unref(msg);
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  return frames;
}

void HarnessTest::start(const std::string& launch, const std::string& src_caps) {
  h = gst_harness_new_parse(launch.c_str());
  // Before the caps: an error set_caps posts is posted once (not again on the first buffer).
  attach_bus();
  gst_harness_set_src_caps_str(h, src_caps.c_str());
}

void HarnessTest::attach_bus() {
  if (bus) return;
  bus = gst_bus_new();
  gst_element_set_bus(h->element, bus);
}

}  // namespace pyrocam::test

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
