// Helpers for the pipeline tests: the scripts in pipelines/ run as child processes (each in its
// own process group, killed with everything it started when the test ends), frames pulled from
// files or reference pipelines through appsink, free UDP ports, and the fake GigE Vision camera.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "element_support.h"
#include "test_support.h"

namespace pyrocam::test {

using Bytes = std::vector<std::uint8_t>;
using Env = std::map<std::string, std::string>;
using std::chrono::milliseconds;

// A pipelines/ script by file name ($PYROCAM_PIPELINES_DIR, set by meson).
std::string pipeline_script(const std::string& name);
// A model made at build time by tests/data (test-model-rgb.json, test-model-nir5x5.json).
std::string test_model(const std::string& name);

// A child process in a new process group, its stdout and stderr to `log_path`. The destructor
// kills the whole group (the script, gst-launch, anything they started) if it still runs.
class Process {
 public:
  Process(const std::vector<std::string>& argv, const Env& extra_env, const std::string& log_path);
  ~Process();
  Process(const Process&) = delete;
  Process& operator=(const Process&) = delete;

  pid_t pid() const { return pid_; }
  bool running();
  // The exit status (the exit code, or 128 + the signal that ended it), or nothing when it still
  // runs after `timeout`.
  std::optional<int> wait_for(milliseconds timeout);
  // A signal to the leader alone, or to the whole group as a terminal's Ctrl-C does.
  void signal(int sig);
  void signal_group(int sig);
  std::string log() const;

 private:
  pid_t pid_ = -1;
  std::optional<int> status_;
  std::string log_path_;
};

// Runs a script to its end: its exit status, or nothing if it ran past `timeout` (then killed).
struct ScriptRun {
  std::optional<int> status;
  std::string log;
  double seconds = 0;
};
ScriptRun run_script(const std::string& name, const std::vector<std::string>& args, const Env& env,
                     const std::string& log_path, milliseconds timeout);

// Raw frames with the caps they came with.
struct Video {
  std::string media, format;  // media type (video/x-raw, video/x-ffv, ...) and format field
  int width = 0, height = 0, fps_n = 0, fps_d = 0;
  std::vector<Bytes> frames;
  std::string error;  // non-empty when the pipeline failed or timed out
};
// Runs a gst-launch description ending in "appsink name=out" to EOS and returns what reached it.
Video pull_frames(const std::string& description, milliseconds timeout = milliseconds(60000));

// Files in `dir` whose names start with `prefix` and end with `suffix`, sorted by name.
std::vector<std::string> files_in(const std::string& dir, const std::string& prefix,
                                  const std::string& suffix);
Bytes read_bytes(const std::string& path);

// Polls `condition` every 20 ms until it holds or `timeout` passes.
bool wait_until(const std::function<bool()>& condition, milliseconds timeout);

// A UDP port that nothing on this machine is bound to at the time of the call.
int free_udp_port();
// Whether anything is bound to UDP `port` (on any address), from /proc/net/udp.
bool udp_port_bound(int port);

// Peak signal-to-noise ratio in dB of two byte images of equal size (infinity if equal).
double psnr(const Bytes& a, const Bytes& b);

// How far a composited RGBA frame is from the camera's colour image under the temperature
// overlay: pixels where the overlay is opaque must be the overlay's colour, where it is
// transparent the camera's, exactly; in between (anti-aliased edges) the blend within 2 steps.
struct CompositeCheck {
  int opaque = 0, transparent = 0, blended = 0;  // pixels of each kind in the overlay
  int wrong = 0;                                 // pixels that break the rule above
};
CompositeCheck check_composite(const Bytes& composite_rgba, const Bytes& camera_rgba,
                               const Bytes& overlay_rgba);
// The overlay drawn over the camera's image ("over" with the overlay's alpha), opaque RGBA.
Bytes blend_over(const Bytes& camera_rgba, const Bytes& overlay_rgba);

// The networked fake GigE Vision camera of Aravis (arv-fake-gv-camera-0.8 -i 127.0.0.1). GigE
// Vision control uses the fixed UDP port 3956, so one such camera can run on the machine at a
// time: construction takes a machine-wide lock, waits for the port to be free, starts the camera
// and waits until it listens. The destructor kills it and releases the lock.
class FakeGigECamera {
 public:
  explicit FakeGigECamera(const std::string& log_path);
  ~FakeGigECamera();
  FakeGigECamera(const FakeGigECamera&) = delete;
  FakeGigECamera& operator=(const FakeGigECamera&) = delete;

  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  void kill_now();  // SIGKILL: the camera vanishes as if unplugged
  void freeze();    // SIGSTOP: the camera stops sending but keeps its sockets
  void thaw();      // SIGCONT

 private:
  int lock_fd_ = -1;
  std::optional<Process> process_;
  std::string error_;
};

// The temperature frames (GRAY16_LE) of a recorded segment (Matroska, FFV1).
Video decode_segment(const std::string& path);
// The colour test model (tests/data), which the pipeline tests run their scripts with.
std::string rgb_model();
// Raw RGBA frames written one per file by multifilesink (raw_sink), in order.
std::vector<Bytes> frames_in_files(const std::string& dir, const std::string& prefix);
// A sink description writing RGBA frames as `prefix`NNNNN.rgba files in `dir`.
std::string raw_sink(const ScratchDir& dir, const std::string& prefix);

// A script test: the elements the scripts need and the colour model, and a scratch folder for
// their outputs and logs.
class PipelineTest : public ::testing::Test {
 protected:
  void SetUp() override;
  ScratchDir dir{"pipeline"};
  std::string log(const std::string& name) const { return (dir / (name + ".log")).string(); }
};

}  // namespace pyrocam::test
