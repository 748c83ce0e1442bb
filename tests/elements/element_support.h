// Helpers for the element tests: GStreamer set-up, factory checks, pipelines run to the end
// with a time limit, and buffer <-> vector conversions.
#pragma once

#include <gst/check/gstharness.h>
#include <gst/gst.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace pyrocam::test {

// What darksub writes for a saturated pixel, and what follows from it downstream.
inline constexpr float kInf = std::numeric_limits<float>::infinity();

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
  int buffers = 0;                    // buffers that reached the sink named "sink", if any
  std::vector<std::string> warnings;  // the warning messages posted before the end
  int errors = 0;                     // error messages on the bus once the pipeline stopped
};
// `timeout` times PYROCAM_TEST_TIME_FACTOR where that is set above 1 (scripts/test-sanitized.sh:
// the sanitizers run pipelines several times slower).
GstClockTime scaled_timeout(GstClockTime timeout);

// Runs a gst-launch description to EOS or the first error, at most `timeout` (scaled); with
// `until_warning`, also to the first warning (a source without end, for a warning that comes
// when a thread of the element is ready).
BusResult run_pipeline(const std::string& description, GstClockTime timeout = 20 * GST_SECOND,
                       bool until_warning = false);

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

// Checks that a pipeline ended in an error of `domain` and `code` whose message holds every one
// of `parts`.
void expect_error(const BusResult& r, GQuark domain, int code,
                  std::initializer_list<std::string> parts);
// Checks that a pipeline ran to EOS with `buffers` buffers at the sink named "sink".
void expect_eos(const BusResult& r, int buffers);

// A buffer with a presentation time stamp.
GstBuffer* with_pts(GstBuffer* buffer, GstClockTime pts);
// Pushes `in`, which must flow, and returns the buffer that comes out (nullptr if none; unref it).
GstBuffer* push_pull_buffer(GstHarness* h, GstBuffer* in);
// The same, as the values of the output buffer (none if no buffer came out).
template <typename T>
std::vector<T> push_pull(GstHarness* h, GstBuffer* in) {
  GstBuffer* out = push_pull_buffer(h, in);
  if (!out) return {};
  std::vector<T> v = values_of<T>(out);
  gst_buffer_unref(out);
  return v;
}
// Pushes flush-start, flush-stop and a new time segment, as a flushing seek does.
void push_flush(GstHarness* h);
// Pushes EOS and says whether it came out of the element.
bool eos_passes(GstHarness* h);

// A test model of the build (PYROCAM_TEST_MODEL_DIR, else the working folder) by file name.
std::string test_model_path(const std::string& name);

// A double field of a structure (a message's), NaN and a test failure when it has none.
double field_double(const GstStructure* s, const char* name);

// Frees the structures and empties the vector.
void free_all(std::vector<GstStructure*>& v);

// How many values are not 0 (codes with a reading).
std::size_t count_nonzero(const std::vector<std::uint16_t>& v);

// The bytes of every buffer that reaches the fakesink named "sink" of a pipeline run to EOS
// (a test failure when it ends otherwise or not within `timeout`, scaled).
std::vector<std::vector<std::uint8_t>> sink_frames(const std::string& description,
                                                   GstClockTime timeout = 30 * GST_SECOND);

// The caps on a pad as a string ("" if none).
std::string current_caps(GstPad* pad);
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

// The fixture of an element's harness tests: fails them where the element is not registered, and
// tears down the harness `h` and the bus on it that the test made.
class HarnessTest : public ::testing::Test {
 protected:
  explicit HarnessTest(const char* element) : element_(element) {}
  void SetUp() override { REQUIRE_ELEMENT(element_); }
  // Also called between the cases of one test: everything is released and null again after.
  void TearDown() override;
  // The harness around a parsed launch line, fed caps `src_caps`, with a bus (attach_bus).
  void start(const std::string& launch, const std::string& src_caps);
  // A bus on the harnessed element, to see its messages (once: a second call keeps it).
  void attach_bus();

  GstHarness* h = nullptr;
  GstBus* bus = nullptr;

 private:
  const char* element_;
};

}  // namespace pyrocam::test
