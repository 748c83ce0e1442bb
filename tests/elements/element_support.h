// Helpers for the element tests: GStreamer set-up, factory checks, pipelines run to the end
// with a time limit, and buffer <-> vector conversions.
#pragma once

#include <gst/check/gstharness.h>
#include <gst/gst.h>
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace pyrocam::test {

bool have_element(const char* name);

// Fails the test and returns from it when an element is not registered: gst_harness_new on an
// unknown element would abort the whole binary.
#define REQUIRE_ELEMENT(name)                                                            \
  do {                                                                                   \
    if (!::pyrocam::test::have_element(name)) {                                          \
      FAIL() << "element " << name << " is not registered (GST_PLUGIN_PATH="             \
             << (g_getenv("GST_PLUGIN_PATH") ? g_getenv("GST_PLUGIN_PATH") : "") << ")"; \
    }                                                                                    \
  } while (0)

// How a pipeline ended.
struct BusResult {
  bool eos = false;
  bool error = false;
  bool timed_out = false;
  GQuark domain = 0;
  int code = 0;
  std::string message, debug, source;
  int buffers = 0;  // buffers that reached the sink named "sink", if any
};
// Runs a gst-launch description to EOS or the first error, at most `timeout`.
BusResult run_pipeline(const std::string& description, GstClockTime timeout = 20 * GST_SECOND);

template <typename T>
GstBuffer* buffer_from(const std::vector<T>& values) {
  GstBuffer* b = gst_buffer_new_allocate(nullptr, values.size() * sizeof(T), nullptr);
  gst_buffer_fill(b, 0, values.data(), values.size() * sizeof(T));
  return b;
}

template <typename T>
std::vector<T> values_of(GstBuffer* buffer) {
  std::vector<T> v(gst_buffer_get_size(buffer) / sizeof(T));
  gst_buffer_extract(buffer, 0, v.data(), v.size() * sizeof(T));
  return v;
}

// The caps on the harness's sink pad as a string ("" if none).
std::string sink_caps(GstHarness* h);

// An element of the harness by factory name (a new reference; unref it).
GstElement* find_element(GstHarness* h, const char* factory);

// Drives a numeric property by a controller: an interpolation control source in step mode
// (each value holds until the next point) with an absolute direct binding, so that the property
// takes value v from stream time t for each (t, v). Returns false if the element refused the
// binding (a property that is not GST_PARAM_CONTROLLABLE).
bool control_property(GstElement* element, const char* property,
                      const std::vector<std::pair<GstClockTime, double>>& points);

}  // namespace pyrocam::test
