#include "pipeline_support.h"

#include <fcntl.h>
#include <gst/app/gstappsink.h>
#include <gst/gst.h>
#include <gst/video/video.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <thread>

extern char** environ;

namespace pyrocam::test {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? v : fallback;
}

int decode_status(int raw) {
  if (WIFEXITED(raw)) return WEXITSTATUS(raw);
  if (WIFSIGNALED(raw)) return 128 + WTERMSIG(raw);
  return -1;
}

}  // namespace

std::string pipeline_script(const std::string& name) {
  return (fs::path(env_or("PYROCAM_PIPELINES_DIR", "pipelines")) / name).string();
}

std::string test_model(const std::string& name) {
  return (fs::path(env_or("PYROCAM_TEST_MODEL_DIR", ".")) / name).string();
}

// ---------------------------------------------------------------------------------------------
// Process

Process::Process(const std::vector<std::string>& argv, const Env& extra_env,
                 const std::string& log_path)
    : log_path_(log_path) {
  // Everything is prepared before the spawn: the test binary has threads (GStreamer's).
  std::map<std::string, std::string> env;
  for (char** e = environ; *e; ++e) {
    const std::string kv = *e;
    const auto eq = kv.find('=');
    if (eq != std::string::npos) env[kv.substr(0, eq)] = kv.substr(eq + 1);
  }
  for (const auto& [k, v] : extra_env) env[k] = v;
  std::vector<std::string> env_strings;
  for (const auto& [k, v] : env) env_strings.push_back(k + "=" + v);
  std::vector<char*> envp, args;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::vector<std::string> argv_copy = argv;
  for (auto& s : argv_copy) args.push_back(s.data());
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setpgroup(&attr, 0);
  // The test runner may ignore or block signals; the child starts with the defaults.
  sigset_t none, all;
  sigemptyset(&none);
  sigfillset(&all);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &all);
  posix_spawnattr_setflags(&attr,
                           POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);
  const int rc = posix_spawnp(&pid_, args[0], &actions, &attr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) {
    pid_ = -1;
    status_ = 127;
    std::ofstream(log_path, std::ios::app) << "cannot start " << argv[0] << ": " << rc << "\n";
  }
}

Process::~Process() {
  if (pid_ <= 0) return;
  // The group outlives its leader when the leader has exited but a child of it has not.
  ::kill(-pid_, SIGKILL);
  if (!status_) {
    int raw = 0;
    waitpid(pid_, &raw, 0);
  }
}

bool Process::running() {
  if (status_ || pid_ <= 0) return false;
  int raw = 0;
  const pid_t r = waitpid(pid_, &raw, WNOHANG);
  if (r == pid_) {
    status_ = decode_status(raw);
    return false;
  }
  return r == 0;
}

std::optional<int> Process::wait_for(milliseconds timeout) {
  wait_until([this] { return !running(); }, timeout);
  return status_;
}

void Process::signal(int sig) {
  if (running()) ::kill(pid_, sig);
}

void Process::signal_group(int sig) {
  if (pid_ > 0) ::kill(-pid_, sig);
}

std::string Process::log() const {
  std::ifstream in(log_path_);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

ScriptRun run_script(const std::string& name, const std::vector<std::string>& args, const Env& env,
                     const std::string& log_path, milliseconds timeout) {
  std::vector<std::string> argv = {pipeline_script(name)};
  argv.insert(argv.end(), args.begin(), args.end());
  const auto start = Clock::now();
  Process p(argv, env, log_path);
  ScriptRun run;
  run.status = p.wait_for(timeout);
  run.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  run.log = p.log();
  return run;
}

// ---------------------------------------------------------------------------------------------
// Frames

Video pull_frames(const std::string& description, milliseconds timeout) {
  Video video;
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  if (!pipeline || error) {
    video.error = std::string("cannot build the pipeline: ") + (error ? error->message : "?");
    if (error) g_error_free(error);
    if (pipeline) gst_object_unref(pipeline);
    return video;
  }
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "out");
  if (!sink) {
    gst_object_unref(pipeline);
    video.error = "no appsink named out";
    return video;
  }
  g_object_set(sink, "sync", FALSE, nullptr);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  GstBus* bus = gst_element_get_bus(pipeline);
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (Clock::now() > deadline) {
      video.error = "timed out after " + std::to_string(timeout.count()) + " ms";
      break;
    }
    GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
    if (msg) {
      GError* err = nullptr;
      gchar* dbg = nullptr;
      gst_message_parse_error(msg, &err, &dbg);
      video.error = std::string(GST_OBJECT_NAME(GST_MESSAGE_SRC(msg))) + ": " + err->message +
                    " (" + (dbg ? dbg : "") + ")";
      g_error_free(err);
      g_free(dbg);
      gst_message_unref(msg);
      break;
    }
    GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 50 * GST_MSECOND);
    if (!sample) {
      if (gst_app_sink_is_eos(GST_APP_SINK(sink))) break;
      continue;
    }
    if (video.frames.empty()) {
      const GstStructure* s = gst_caps_get_structure(gst_sample_get_caps(sample), 0);
      video.media = gst_structure_get_name(s);
      const char* format = gst_structure_get_string(s, "format");
      video.format = format ? format : "";
      gst_structure_get_int(s, "width", &video.width);
      gst_structure_get_int(s, "height", &video.height);
      gst_structure_get_fraction(s, "framerate", &video.fps_n, &video.fps_d);
    }
    GstBuffer* buffer = gst_sample_get_buffer(sample);
    Bytes frame(gst_buffer_get_size(buffer));
    gst_buffer_extract(buffer, 0, frame.data(), frame.size());
    video.frames.push_back(std::move(frame));
    gst_sample_unref(sample);
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  return video;
}

std::vector<std::string> files_in(const std::string& dir, const std::string& prefix,
                                  const std::string& suffix) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.size() >= prefix.size() + suffix.size() && name.rfind(prefix, 0) == 0 &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      out.push_back(entry.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

Bytes read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes(std::istreambuf_iterator<char>(in), {});
}

bool wait_until(const std::function<bool()>& condition, milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  for (;;) {
    if (condition()) return true;
    if (Clock::now() > deadline) return false;
    std::this_thread::sleep_for(milliseconds(20));
  }
}

// ---------------------------------------------------------------------------------------------
// Network

int free_udp_port() {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return -1;
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  addr.sin_port = 0;
  socklen_t len = sizeof addr;
  int port = -1;
  if (bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) == 0)
    port = ntohs(addr.sin_port);
  close(fd);
  return port;
}

bool udp_port_bound(int port) {
  // Lines read "  sl  local_address rem_address ...", local_address as HEXIP:HEXPORT.
  std::ifstream in("/proc/net/udp");
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string slot, local;
    fields >> slot >> local;
    const auto colon = local.find(':');
    if (colon != std::string::npos &&
        std::strtol(local.c_str() + colon + 1, nullptr, 16) == static_cast<long>(port))
      return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Images

double psnr(const Bytes& a, const Bytes& b) {
  if (a.size() != b.size() || a.empty()) return 0;
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
    sum += d * d;
  }
  if (sum == 0) return INFINITY;
  return 10 * std::log10(255.0 * 255.0 / (sum / static_cast<double>(a.size())));
}

CompositeCheck check_composite(const Bytes& composite, const Bytes& camera, const Bytes& overlay) {
  CompositeCheck c;
  if (composite.size() != camera.size() || composite.size() != overlay.size()) {
    c.wrong = -1;
    return c;
  }
  for (std::size_t p = 0; p + 3 < composite.size(); p += 4) {
    const int alpha = overlay[p + 3];
    bool ok = true;
    for (int ch = 0; ch < 3; ++ch) {
      const int got = composite[p + ch];
      if (alpha == 255) {
        ok = ok && got == overlay[p + ch];
      } else if (alpha == 0) {
        ok = ok && got == camera[p + ch];
      } else {
        const double want = (overlay[p + ch] * alpha + camera[p + ch] * (255 - alpha)) / 255.0;
        ok = ok && std::abs(got - want) <= 2.0;
      }
    }
    (alpha == 255 ? c.opaque : alpha == 0 ? c.transparent : c.blended)++;
    if (!ok) ++c.wrong;
  }
  return c;
}

Bytes blend_over(const Bytes& camera, const Bytes& overlay) {
  Bytes out(camera.size());
  for (std::size_t p = 0; p + 3 < camera.size() && p + 3 < overlay.size(); p += 4) {
    const int alpha = overlay[p + 3];
    for (int ch = 0; ch < 3; ++ch)
      out[p + ch] = static_cast<std::uint8_t>(
          std::lround((overlay[p + ch] * alpha + camera[p + ch] * (255 - alpha)) / 255.0));
    out[p + 3] = 255;
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// The fake GigE Vision camera

namespace {
constexpr int kGvcpPort = 3956;
}

FakeGigECamera::FakeGigECamera(const std::string& log_path) {
  // One lock for every checkout on this machine: the control port is fixed.
  const std::string lock_path =
      (fs::temp_directory_path() / "pyrocam-fake-gv-camera.lock").string();
  lock_fd_ = open(lock_path.c_str(), O_RDONLY | O_CREAT, 0666);
  const bool locked =
      lock_fd_ >= 0 &&
      wait_until([this] { return flock(lock_fd_, LOCK_EX | LOCK_NB) == 0; }, milliseconds(60000));
  if (!locked) {
    error_ = "could not lock " + lock_path + " within 60 s (another fake camera test runs)";
    return;
  }
  if (!wait_until([] { return !udp_port_bound(kGvcpPort); }, milliseconds(20000))) {
    error_ = "UDP port 3956 (GigE Vision control) stays taken by another program";
    return;
  }
  process_.emplace(std::vector<std::string>{"arv-fake-gv-camera-0.8", "-i", "127.0.0.1"}, Env{},
                   log_path);
  if (!wait_until([] { return udp_port_bound(kGvcpPort); }, milliseconds(10000)))
    error_ = "arv-fake-gv-camera-0.8 did not start listening on 127.0.0.1:3956: " + process_->log();
}

FakeGigECamera::~FakeGigECamera() {
  process_.reset();
  if (lock_fd_ >= 0) close(lock_fd_);  // releases the lock
}

void FakeGigECamera::kill_now() {
  if (process_) {
    process_->signal_group(SIGKILL);
    process_->wait_for(milliseconds(5000));
  }
}

void FakeGigECamera::freeze() {
  if (process_) process_->signal_group(SIGSTOP);
}

void FakeGigECamera::thaw() {
  if (process_) process_->signal_group(SIGCONT);
}

Video decode_segment(const std::string& path) {
  return pull_frames("filesrc location=\"" + path +
                     "\" ! matroskademux ! avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! "
                     "appsink name=out");
}

std::string rgb_model() { return test_model("test-model-rgb.json"); }

std::vector<Bytes> frames_in_files(const std::string& dir, const std::string& prefix) {
  std::vector<Bytes> out;
  for (const auto& f : files_in(dir, prefix, ".rgba")) out.push_back(read_bytes(f));
  return out;
}

std::string raw_sink(const ScratchDir& dir, const std::string& prefix) {
  return "video/x-raw,format=RGBA ! multifilesink sync=false location=\"" +
         (dir / (prefix + "%05d.rgba")).string() + "\"";
}

void PipelineTest::SetUp() {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp", "thermalcolormap"})
    REQUIRE_ELEMENT(e);
  ASSERT_TRUE(std::filesystem::exists(rgb_model())) << rgb_model();
}

}  // namespace pyrocam::test
