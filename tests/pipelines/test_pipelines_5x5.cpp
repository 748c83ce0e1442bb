// The scripts in pipelines/ with the 5x5 camera (PROFILE=nir5x5-reference), the default model
// calibrated on first use, the live view on a (virtual) display with the default sink, and the
// overlay on the first frame of a live view.
#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "element_support.h"
#include "pipeline_support.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;

// 160x120 sensor pixels: 32x24 macro-pixels, one temperature each.
constexpr int kWidth = 160, kHeight = 120, kCell = 5;
constexpr int kTempWidth = kWidth / kCell, kTempHeight = kHeight / kCell;
const std::string kCaps = "video/x-raw,width=160,height=120,framerate=30/1";
// A plate: the melt pool is a few macro-pixels across at this size, with hardly a reading.
const std::string kScene = "pyrocamsrc profile=nir5x5-reference scene=plate seed=7";
const std::string kProfile = "nir5x5-reference";
constexpr milliseconds kRunLimit(90000);

std::string nir_model() { return test_model("test-model-nir5x5.json"); }

std::string temperature_chain(int frames) {
  return kScene + " num-buffers=" + std::to_string(frames) + " ! " + kCaps +
         " ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=\"" + nir_model() + "\"";
}
Video reference_temperatures(int frames) {
  return pull_frames(temperature_chain(frames) + " ! appsink name=out");
}
// The raw mosaic (GRAY8, one byte per sensor pixel).
Video reference_mosaic(int frames) {
  return pull_frames(kScene + " num-buffers=" + std::to_string(frames) + " ! " + kCaps +
                     " ! appsink name=out");
}
// The overlay as the scripts draw it: the temperatures at the sensor's size, then colour-mapped.
Video reference_overlay(int frames) {
  return pull_frames(temperature_chain(frames) +
                     " ! videoscale method=nearest-neighbour ! video/x-raw,width=160,height=120 "
                     "! thermalcolormap scale-bar=true ! video/x-raw,format=RGBA ! appsink "
                     "name=out");
}

// What the view must show, computed here: each macro-pixel's centre cell, as gray, over its
// whole 5x5 block.
Bytes expected_view(const Bytes& mosaic) {
  Bytes rgba(static_cast<std::size_t>(kWidth * kHeight * 4));
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const int cy = y / kCell * kCell + 2, cx = x / kCell * kCell + 2;
      const std::uint8_t v = mosaic[static_cast<std::size_t>(cy * kWidth + cx)];
      std::uint8_t* p = &rgba[static_cast<std::size_t>((y * kWidth + x) * 4)];
      p[0] = p[1] = p[2] = v;
      p[3] = 255;
    }
  return rgba;
}

class Pipelines5x5 : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp", "thermalcolormap"})
      REQUIRE_ELEMENT(e);
    ASSERT_TRUE(fs::exists(nir_model())) << nir_model();
  }
  Env settings(int frames) const {
    return {{"PROFILE", kProfile},
            {"MODEL", nir_model()},
            {"SOURCE", kScene},
            {"CAPS", kCaps},
            {"NUM_BUFFERS", std::to_string(frames)},
            // Not a test of the watchdog: a source that is not live is held back by the slowest
            // branch, for seconds on a loaded machine.
            {"WATCHDOG_MS", "30000"}};
  }
  ScratchDir dir{"pipeline-5x5"};
  std::string log(const std::string& name) const { return (dir / (name + ".log")).string(); }
};

// ---------------------------------------------------------------------------------------------

TEST_F(Pipelines5x5, live_view_band_and_overlay_line_up_pixel_for_pixel) {
  constexpr int kFrames = 6;
  Env env = settings(kFrames);
  env["SINK"] = raw_sink(dir, "view-");
  const ScriptRun run = run_script("live-view.sh", {}, env, log("live-view"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;
  const auto frames = frames_in_files(dir.path().string(), "view-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));

  // The overlay at the sensor's size keeps each macro-pixel's code over its 5x5 block.
  const Video temps = reference_temperatures(kFrames);
  ASSERT_EQ(temps.frames.size(), static_cast<std::size_t>(kFrames)) << temps.error;
  ASSERT_EQ(temps.width, kTempWidth);
  ASSERT_EQ(temps.height, kTempHeight);
  const Video scaled = pull_frames(temperature_chain(1) +
                                   " ! videoscale method=nearest-neighbour ! "
                                   "video/x-raw,width=160,height=120 ! appsink name=out");
  ASSERT_EQ(scaled.frames.size(), 1u) << scaled.error;
  int readings = 0;
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) {
      const std::size_t big = static_cast<std::size_t>(y * kWidth + x) * 2;
      const std::size_t small = static_cast<std::size_t>(y / kCell * kTempWidth + x / kCell) * 2;
      ASSERT_EQ(scaled.frames[0][big], temps.frames[0][small]) << x << "," << y;
      ASSERT_EQ(scaled.frames[0][big + 1], temps.frames[0][small + 1]) << x << "," << y;
      readings += (temps.frames[0][small] | temps.frames[0][small + 1]) != 0;
    }
  EXPECT_GT(readings, 100) << "the plate must give readings for the check to mean much";

  const Video mosaic = reference_mosaic(kFrames), overlay = reference_overlay(kFrames);
  ASSERT_EQ(mosaic.frames.size(), static_cast<std::size_t>(kFrames)) << mosaic.error;
  ASSERT_EQ(overlay.frames.size(), static_cast<std::size_t>(kFrames)) << overlay.error;
  int opaque = 0;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_EQ(frames[i].size(), static_cast<std::size_t>(kWidth * kHeight * 4)) << "frame " << i;
    const CompositeCheck c =
        check_composite(frames[i], expected_view(mosaic.frames[i]), overlay.frames[i]);
    EXPECT_EQ(c.wrong, 0) << "frame " << i << ": " << c.opaque << " opaque, " << c.transparent
                          << " transparent, " << c.blended << " blended overlay pixels";
    EXPECT_GT(c.transparent, 1000) << "frame " << i << ": no camera view to see";
    opaque += c.opaque;
  }
  EXPECT_GT(opaque, kFrames * 100) << "no overlay drawn";
}

TEST_F(Pipelines5x5, record_then_playback) {
  constexpr int kFrames = 15;
  Env env = settings(kFrames);
  env["OUT"] = (dir / "rec").string();
  env["SEGMENT_SECONDS"] = "0.25";
  env["SNAPSHOT_RATE"] = "30";
  const ScriptRun run = run_script("record.sh", {}, env, log("record"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;

  const Video reference = reference_temperatures(kFrames);
  ASSERT_EQ(reference.frames.size(), static_cast<std::size_t>(kFrames)) << reference.error;
  const Video joined =
      pull_frames("splitmuxsrc location=\"" + (dir / "rec" / "temperature-*.mkv").string() +
                  "\" ! avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! appsink name=out");
  ASSERT_EQ(joined.frames.size(), static_cast<std::size_t>(kFrames)) << joined.error;
  EXPECT_EQ(joined.width, kTempWidth);
  EXPECT_EQ(joined.height, kTempHeight);
  EXPECT_TRUE(joined.frames == reference.frames) << "recorded temperatures differ";

  const Video snapshot =
      pull_frames("filesrc location=\"" + (dir / "rec" / "view.png").string() +
                  "\" ! pngdec ! videoconvert ! video/x-raw,format=RGBA ! appsink name=out");
  ASSERT_EQ(snapshot.frames.size(), 1u) << snapshot.error;
  EXPECT_EQ(snapshot.width, kWidth);
  EXPECT_EQ(snapshot.height, kHeight);

  // Playback with the 5x5 profile: the view scaled up by nearest neighbour.
  const ScriptRun played = run_script("playback.sh", {(dir / "rec").string()},
                                      {{"PROFILE", kProfile}, {"SINK", raw_sink(dir, "play-")}},
                                      log("playback"), kRunLimit);
  ASSERT_EQ(played.status, 0) << played.log;
  const auto frames = frames_in_files(dir.path().string(), "play-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));
  for (const Bytes& f : frames) EXPECT_EQ(f.size(), static_cast<std::size_t>(320 * 240 * 4));

  // With the peak marker, its windows are scaled with the view: 5 x 5 recorded pixels, not one
  // (24 rows shown in 240: 10 view pixels a recorded one, 50 made odd).
  const ScriptRun marked = run_script("playback.sh", {(dir / "rec").string()},
                                      {{"PROFILE", kProfile},
                                       {"COLORMAP", "scale-bar=true peak-marker=true"},
                                       {"SINK", raw_sink(dir, "peak-")}},
                                      log("playback-peak"), kRunLimit);
  ASSERT_EQ(marked.status, 0) << marked.log;
  EXPECT_NE(marked.log.find("peak-window=51"), std::string::npos) << marked.log;
  EXPECT_EQ(frames_in_files(dir.path().string(), "peak-").size(),
            static_cast<std::size_t>(kFrames));
}

TEST_F(Pipelines5x5, stream_received_by_watch_stream) {
  constexpr int kFrames = 15;
  const int port = free_udp_port();
  ASSERT_GT(port, 0);
  Process screen(
      {pipeline_script("watch-stream.sh")},
      {{"ADDRESS", "127.0.0.1"}, {"PORT", std::to_string(port)}, {"SINK", raw_sink(dir, "rx-")}},
      log("watch-stream"));
  ASSERT_TRUE(
      wait_until([&] { return udp_port_bound(port) || !screen.running(); }, milliseconds(10000)))
      << screen.log();
  Env env = settings(kFrames);
  env["HOST"] = "127.0.0.1";
  env["PORT"] = std::to_string(port);
  const ScriptRun sent = run_script("stream.sh", {}, env, log("stream"), kRunLimit);
  ASSERT_EQ(sent.status, 0) << sent.log;
  const auto received = [&] { return files_in(dir.path().string(), "rx-", ".rgba").size(); };
  wait_until([&] { return received() >= static_cast<std::size_t>(kFrames); }, milliseconds(5000));
  ASSERT_TRUE(screen.running()) << screen.log();
  screen.signal_group(SIGINT);
  const auto status = screen.wait_for(milliseconds(10000));
  ASSERT_TRUE(status.has_value()) << screen.log();
  const auto frames = frames_in_files(dir.path().string(), "rx-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames)) << screen.log();
  for (const Bytes& f : frames) EXPECT_EQ(f.size(), static_cast<std::size_t>(kWidth * kHeight * 4));
}

TEST_F(Pipelines5x5, genicam_live_refuses_caps_without_a_size_n) {
  // The 5x5 view needs the sensor's size; checked before any camera is opened.
  const ScriptRun run = run_script("genicam-live.sh", {},
                                   {{"PROFILE", kProfile},
                                    {"MODEL", nir_model()},
                                    {"DARK", "dark-level=0"},
                                    {"SINK", "fakesink"},
                                    {"NUM_BUFFERS", "3"}},
                                   log("genicam"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 2) << run.log;
  EXPECT_NE(run.log.find("multiples of 5"), std::string::npos) << run.log;
}

TEST_F(Pipelines5x5, rejects_an_unknown_profile_and_a_missing_model_n) {
  Env env = settings(3);
  env["SINK"] = "fakesink";
  env["PROFILE"] = "nir4x4";
  ScriptRun run = run_script("live-view.sh", {}, env, log("profile"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 2) << run.log;
  EXPECT_NE(run.log.find("nir4x4"), std::string::npos) << run.log;

  // A model the user named is never replaced by a calibration.
  env["PROFILE"] = kProfile;
  env["MODEL"] = (dir / "no-such-model.json").string();
  env["PYROCAM_CALIB"] = "/bin/false";
  run = run_script("live-view.sh", {}, env, log("model"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 1) << run.log;
  EXPECT_NE(run.log.find("no-such-model.json"), std::string::npos) << run.log;
}

// The default model is calibrated on first use, as scripts/main-job.sh calibrates the colour
// one: a stand-in for pyrocam-calib records what it is asked and writes the test model.
TEST_F(Pipelines5x5, default_model_is_calibrated_on_first_use) {
  const fs::path work = dir / "work", calls = dir / "calls.txt", stub = dir / "fake-calib.sh";
  fs::create_directories(work);
  write_text(stub,
             "#!/usr/bin/env bash\n"
             "echo \"$*\" >> '" +
                 calls.string() +
                 "'\n"
                 "cmd=$1 out=''\n"
                 "while (($#)); do [[ $1 == --out ]] && out=$2; shift; done\n"
                 "case $cmd in\n"
                 "  simulate) mkdir -p \"$out\" ;;\n"
                 "  calibrate) cp '" +
                 nir_model() +
                 "' \"$out\" ;;\n"
                 "esac\n");
  fs::permissions(stub, fs::perms::owner_all);
  Env env = settings(3);
  env.erase("MODEL");
  env["SINK"] = "fakesink";
  env["PYROCAM_CALIB"] = stub.string();
  const std::string script = pipeline_script("live-view.sh");
  std::vector<std::string> argv = {"bash", "-c",
                                   "cd '" + work.string() + "' && exec '" + script + "'"};
  Process p(argv, env, log("first-use"));
  const auto status = p.wait_for(kRunLimit);
  ASSERT_TRUE(status.has_value()) << "hung: " << p.log();
  ASSERT_EQ(*status, 0) << p.log();
  EXPECT_TRUE(fs::exists(work / "out" / "model-nir5x5.json")) << p.log();
  std::ifstream in(calls);
  std::string simulate, calibrate;
  std::getline(in, simulate);
  std::getline(in, calibrate);
  EXPECT_NE(simulate.find("simulate campaign --profile nir5x5-reference --unit typical"),
            std::string::npos)
      << simulate;
  EXPECT_NE(calibrate.find("calibrate --dataset out/furnace-nir5x5 --profile nir5x5-reference"),
            std::string::npos)
      << calibrate;
  // No partial model left behind.
  for (const auto& e : fs::directory_iterator(work / "out"))
    EXPECT_EQ(e.path().filename().string().find("partial"), std::string::npos) << e.path();
}

// ---------------------------------------------------------------------------------------------

// An X server of its own (Xvfb picks a free display and writes its number when it is ready).
class VirtualDisplay {
 public:
  explicit VirtualDisplay(const std::string& log_path) : log_(log_path) {
    // -noreset: by default the server resets when its last client leaves, and a view that
    // connects meanwhile fails ("Could not initialise X output", seen once in CI).
    process_.emplace(std::vector<std::string>{"Xvfb", "-displayfd", "1", "-noreset", "-screen", "0",
                                              "640x480x24", "-nolisten", "tcp"},
                     Env{}, log_path);
    wait_until(
        [&] {
          std::ifstream in(log_);
          std::string line;
          while (std::getline(in, line))
            if (!line.empty() && line.find_first_not_of("0123456789") == std::string::npos) {
              display_ = ":" + line;
              return true;
            }
          return !process_->running();
        },
        milliseconds(30000));
  }
  const std::string& display() const { return display_; }
  std::string log() const { return process_->log(); }

 private:
  std::string log_, display_;
  std::optional<Process> process_;
};

bool have_program(const std::string& name) {
  return std::system(("command -v " + name + " >/dev/null 2>&1").c_str()) == 0;
}

TEST_F(Pipelines5x5, live_views_show_on_a_display_with_the_default_sink) {
  ASSERT_TRUE(have_program("Xvfb")) << "Xvfb is missing: scripts/install-deps.sh --tests";
  VirtualDisplay x(log("xvfb"));
  ASSERT_FALSE(x.display().empty()) << "Xvfb did not start: " << x.log();
  for (const std::string& profile : std::vector<std::string>{"rgb-reference", kProfile}) {
    Env env = settings(10);
    env["PROFILE"] = profile;
    env["MODEL"] = profile == kProfile ? nir_model() : test_model("test-model-rgb.json");
    env["SOURCE"] = "pyrocamsrc is-live=true scene=plate profile=" + profile;
    env["DISPLAY"] = x.display();
    env.erase("CAPS");
    const ScriptRun run = run_script("live-view.sh", {}, env, log("x-" + profile), kRunLimit);
    ASSERT_TRUE(run.status.has_value()) << profile << " hung: " << run.log;
    EXPECT_EQ(*run.status, 0) << profile << ": " << run.log;
  }
}

// --help prints a script's header (its settings) and starts nothing; an argument a script does not
// take is refused rather than ignored (`record.sh --help` used to calibrate and record).
TEST(Files, help_prints_the_settings_and_stray_arguments_are_refused_n) {
  ScratchDir dir("files-help");
  for (const char* script : {"live-view.sh", "record.sh", "playback.sh", "stream.sh",
                             "watch-stream.sh", "genicam-live.sh"}) {
    const ScriptRun help =
        run_script(script, {"--help"}, {}, (dir / "help.log").string(), milliseconds(20000));
    ASSERT_TRUE(help.status.has_value()) << script << " hung";
    EXPECT_EQ(*help.status, 0) << script << ": " << help.log;
    EXPECT_NE(help.log.find("Settings (environment variables"), std::string::npos)
        << script << ": " << help.log;
  }
  const ScriptRun stray =
      run_script("record.sh", {"out/x"}, {}, (dir / "stray.log").string(), milliseconds(20000));
  ASSERT_TRUE(stray.status.has_value()) << "hung";
  EXPECT_EQ(*stray.status, 2) << stray.log;
  EXPECT_NE(stray.log.find("no arguments are taken"), std::string::npos) << stray.log;
}

TEST_F(Pipelines5x5, no_display_is_a_clear_error_not_a_crash_n) {
  for (const std::string script : {"live-view.sh", "playback.sh", "watch-stream.sh"}) {
    Env env = settings(3);
    env["DISPLAY"] = "";
    env["WAYLAND_DISPLAY"] = "";
    const ScriptRun run = run_script(script, {}, env, log("nodisplay"), kRunLimit);
    ASSERT_TRUE(run.status.has_value()) << script << " hung";
    EXPECT_EQ(*run.status, 1) << script << ": " << run.log;
    EXPECT_NE(run.log.find("no display"), std::string::npos) << script << ": " << run.log;
  }
  // autovideosink at the end of a SINK that scales first (docs/live-view.md's example).
  Env env = settings(3);
  env["DISPLAY"] = "";
  env["WAYLAND_DISPLAY"] = "";
  env["SINK"] = "videoscale ! video/x-raw,width=640,height=480 ! autovideosink";
  const ScriptRun run = run_script("live-view.sh", {}, env, log("nodisplay-scaled"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 1) << run.log;
  EXPECT_NE(run.log.find("no display"), std::string::npos) << run.log;
}

// ---------------------------------------------------------------------------------------------

// A live view shows every camera frame under its own overlay, from the first frame, however late
// the temperatures come (LATENCY_MS=0: a sink that counted frames late would drop them, this one
// does not sync): thermaloverlay waits for each frame's own overlay. Neither an earlier frame's
// overlay (the melt pool moves: temperatures beside it that look right) nor none at all.
TEST(LiveOverlay, every_frame_under_its_own_overlay_from_the_first) {
  for (const char* e :
       {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp", "thermalcolormap", "thermaloverlay"})
    REQUIRE_ELEMENT(e);
  ScratchDir dir("live-overlay");
  const std::string model = test_model("test-model-rgb.json");
  const std::string scene = "pyrocamsrc scene=melt-pool seed=7";
  const std::string caps = "video/x-bayer,width=160,height=120,framerate=30/1";
  constexpr int kFrames = 30, kW = 160, kH = 120;
  const ScriptRun run = run_script("live-view.sh", {},
                                   {{"MODEL", model},
                                    {"SOURCE", scene + " is-live=true"},
                                    {"CAPS", caps},
                                    {"LATENCY_MS", "0"},
                                    {"WATCHDOG_MS", "30000"},
                                    {"NUM_BUFFERS", std::to_string(kFrames)},
                                    {"SINK", raw_sink(dir, "view-")}},
                                   (dir / "live-view.log").string(), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;
  const auto frames = frames_in_files(dir.path().string(), "view-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));
  // The same seeded frames as the live camera's (pyrocamsrc draws them by frame index).
  const std::string chain = scene + " num-buffers=" + std::to_string(kFrames) + " ! " + caps;
  const Video camera =
      pull_frames(chain + " ! bayer2rgb ! video/x-raw,format=RGBA ! appsink name=out");
  const Video overlay = pull_frames(chain + " ! darksub dark-level=50 ! demosaic25 ! ratiotemp " +
                                    "model=\"" + model +
                                    "\" ! thermalcolormap scale-bar=true ! "
                                    "video/x-raw,format=RGBA ! appsink name=out");
  ASSERT_EQ(camera.frames.size(), static_cast<std::size_t>(kFrames)) << camera.error;
  ASSERT_EQ(overlay.frames.size(), static_cast<std::size_t>(kFrames)) << overlay.error;
  for (int k = 0; k < kFrames; ++k) {
    ASSERT_EQ(frames[k].size(), static_cast<std::size_t>(kW * kH * 4));
    const CompositeCheck c = check_composite(frames[k], camera.frames[k], overlay.frames[k]);
    EXPECT_EQ(c.wrong, 0) << "frame " << k << " is not camera frame " << k
                          << " under its own overlay";
    // Every frame has readings to show (the pool and the scale bar), so a bare frame would fail.
    EXPECT_GT(c.opaque, 0) << "frame " << k;
    EXPECT_NE(frames[k], camera.frames[k]) << "frame " << k << " is shown bare";
  }
}

}  // namespace
}  // namespace pyrocam::test
