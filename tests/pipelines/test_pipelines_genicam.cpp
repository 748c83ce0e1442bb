// genicam-live.sh with the fake GigE Vision camera (arv-fake-gv-camera-0.8 on loopback): the
// full chain, bracketing through autoexposure, a camera that vanishes, a recording from a camera
// that stops, and a missing dark.
#include <signal.h>

#include <chrono>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>

#include "pipeline_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;

constexpr milliseconds kRunLimit(60000);

class GenICam : public PipelineTest {
 protected:
  Env settings(int frames) const {
    return {{"MODEL", rgb_model()},
            {"DARK", "dark-level=0"},
            {"CAMERA", "127.0.0.1"},
            // 128x128: larger frames exceed the default socket buffer as non-root (PLATFORM.md).
            {"CAPS", "video/x-bayer,format=rggb,width=128,height=128"},
            // The fake camera keeps what a client set: every run sets both.
            {"EXPOSURE_US", "10000"},
            {"GAIN_DB", "0"},
            {"NUM_BUFFERS", std::to_string(frames)},
            // A live compositor that waits less than the temperature branch takes on a loaded
            // machine sends a frame without its overlay, or an extra one (16 for 15 seen at
            // load 9): 1 s covers that without changing what is checked.
            {"LATENCY_MS", "1000"},
            {"SINK", raw_sink(dir, "cam-")}};
  }
};

TEST_F(GenICam, fake_gige_camera_through_the_full_chain) {
  constexpr int kFrames = 15;
  FakeGigECamera camera(log("camera"));
  ASSERT_TRUE(camera.ok()) << camera.error();
  const ScriptRun run =
      run_script("genicam-live.sh", {}, settings(kFrames), log("genicam"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;
  const auto frames = frames_in_files(dir.path().string(), "cam-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));
  std::set<Bytes> distinct;
  for (const Bytes& f : frames) {
    ASSERT_EQ(f.size(), static_cast<std::size_t>(128 * 128 * 4));
    distinct.insert(f);
    // The fake camera's test pattern: bright somewhere, not a blank frame.
    EXPECT_GT(*std::max_element(f.begin(), f.end()), 100);
  }
  EXPECT_GT(distinct.size(), 1u) << "the camera sent the same frame every time";
}

// BRACKET with a real camera: autoexposure brackets it, holding each exposure for
// EXPOSURE_LATENCY + 1 = 2 frames and passing the last of each, so 15 camera frames give 7
// views (the first frame starts the bracket), each with its overlay.
TEST_F(GenICam, bracket_through_autoexposure_passes_one_frame_per_step) {
  FakeGigECamera camera(log("camera"));
  ASSERT_TRUE(camera.ok()) << camera.error();
  Env env = settings(15);
  env["BRACKET"] = "1,2";
  env["EXPOSURE_LATENCY"] = "1";
  const ScriptRun run = run_script("genicam-live.sh", {}, env, log("genicam"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;
  EXPECT_EQ(frames_in_files(dir.path().string(), "cam-").size(), 7u) << run.log;
}

TEST_F(GenICam, camera_that_vanishes_ends_in_a_clear_error_n) {
  FakeGigECamera camera(log("camera"));
  ASSERT_TRUE(camera.ok()) << camera.error();
  Env env = settings(-1);
  env["WATCHDOG_MS"] = "1000";
  Process view({pipeline_script("genicam-live.sh")}, env, log("genicam"));
  ASSERT_TRUE(wait_until(
      [&] { return files_in(dir.path().string(), "cam-", ".rgba").size() >= 5 || !view.running(); },
      milliseconds(20000)))
      << view.log();
  ASSERT_TRUE(view.running()) << view.log();

  // The diagnosis comes as soon as the watchdog fires, or as soon as aravissrc stops with its own
  // error, whichever is first (both happen: which depends on when Aravis notices the loss);
  // Aravis then spends several seconds on control-channel timeouts to the vanished camera before
  // gst-launch can exit.
  const std::string watchdog = "camera 127.0.0.1 sent no frame for 1000 ms";
  const std::string source_error = "camera 127.0.0.1 stopped streaming (aravissrc's error above)";
  const auto diagnosed = [&] {
    const std::string log = view.log();
    return log.find("genicam-live: " + watchdog + ": unplugged") != std::string::npos ||
           log.find("genicam-live: " + source_error + ": unplugged") != std::string::npos;
  };
  const auto gone = std::chrono::steady_clock::now();
  const auto since_gone = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - gone).count();
  };
  camera.kill_now();
  // A guard against a view that never says, not a speed target (the latency is printed).
  ASSERT_TRUE(wait_until(diagnosed, milliseconds(30000)))
      << "no diagnosis within 30 s of the camera vanishing: " << view.log();
  const double message_s = since_gone();
  const auto status = view.wait_for(milliseconds(30000));
  ASSERT_TRUE(status.has_value()) << "still running 30 s after the camera vanished: " << view.log();
  std::cout << "[ info     ] camera gone -> diagnosis after " << message_s << " s, exit status "
            << *status << " after " << since_gone() << " s\n";
  EXPECT_EQ(*status, 1) << view.log();
  // The diagnosis names what stopped: the watchdog's error or aravissrc's is in the log.
  const std::string log = view.log();
  EXPECT_TRUE(log.find("GstWatchdog:camera-sent-no-frame") != std::string::npos ||
              log.find("ERROR: from element /GstPipeline:pipeline0/GstAravis:") !=
                  std::string::npos)
      << log;
}

TEST_F(GenICam, recording_from_a_camera_that_stops_keeps_its_closed_segments_n) {
  FakeGigECamera camera(log("camera"));
  ASSERT_TRUE(camera.ok()) << camera.error();
  const std::string rec = (dir / "rec").string();
  Process recording({pipeline_script("record.sh")},
                    {{"MODEL", rgb_model()},
                     {"DARK", "dark-level=0"},
                     {"OUT", rec},
                     {"SOURCE", "aravissrc camera-name=127.0.0.1 exposure=10000 gain=0"},
                     {"CAPS", "video/x-bayer,format=rggb,width=128,height=128"},
                     {"SEGMENT_SECONDS", "0.4"},
                     // Not 1 s: starting the chain (model, lookup table) held the camera's
                     // branches for over a second when the suite ran two tests at once on 2
                     // cores, and the watchdog fired before any segment closed.
                     {"WATCHDOG_MS", "3000"}},
                    log("record"));
  const auto segments = [&] { return files_in(rec, "temperature-", ".mkv"); };
  ASSERT_TRUE(wait_until([&] { return segments().size() >= 3 || !recording.running(); },
                         milliseconds(20000)))
      << recording.log();
  ASSERT_TRUE(recording.running()) << recording.log();
  // The segments closed before the camera stops: all but the one being written. (Not those
  // left at the end: frames the camera sends after it resumes, while the pipeline goes down
  // after the error, can start a segment past the one that was open, which is then not the
  // last, nor closed.)
  std::vector<std::string> closed = segments();
  closed.pop_back();

  // The camera stops sending (frozen, not gone); once the error is out it resumes, so that
  // Aravis stops it without waiting for control-channel timeouts. The error is the watchdog's
  // or aravissrc's own (it gives up on a camera silent for about 2 s, before a 3 s watchdog):
  // either ends the recording; the watchdog's diagnosis has its own test above.
  camera.freeze();
  const bool stopped = wait_until(
      [&] {
        const std::string l = recording.log();
        return l.find("GstWatchdog:camera-sent-no-frame") != std::string::npos ||
               l.find("GstAravis") != std::string::npos;
      },
      milliseconds(8000));
  camera.thaw();
  ASSERT_TRUE(stopped) << "no error within 8 s of the camera stopping: " << recording.log();
  const auto status = recording.wait_for(milliseconds(30000));
  ASSERT_TRUE(status.has_value()) << recording.log();
  EXPECT_NE(*status, 0) << recording.log();

  ASSERT_GE(closed.size(), 2u);
  std::size_t frames = 0;
  for (const std::string& file : closed) {
    const Video seg = decode_segment(file);
    ASSERT_TRUE(seg.error.empty())
        << file << ": " << seg.error << " (" << closed.size()
        << " segments closed before the camera stopped, " << segments().size() << " files in all)";
    EXPECT_FALSE(seg.frames.empty()) << file;
    EXPECT_EQ(seg.width, 128);
    EXPECT_EQ(seg.height, 128);
    for (const Bytes& f : seg.frames) EXPECT_EQ(f.size(), static_cast<std::size_t>(128 * 128 * 2));
    frames += seg.frames.size();
  }
  std::cout << "[ info     ] " << closed.size() << " closed segments kept, " << frames
            << " frames (" << segments().size() << " segment files in all)\n";
}

TEST_F(GenICam, rejects_a_missing_dark_n) {
  Env env = settings(5);
  env["DARK"] = "";
  const ScriptRun run = run_script("genicam-live.sh", {}, env, log("genicam"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 2);
  EXPECT_NE(run.log.find("set DARK"), std::string::npos) << run.log;
}

// Caps the camera cannot give (the fake camera's frames are at most 2048 pixels wide) are said
// to be the caps, not a camera that stopped streaming.
TEST_F(GenICam, caps_the_camera_cannot_give_are_named_n) {
  FakeGigECamera camera(log("camera"));
  ASSERT_TRUE(camera.ok()) << camera.error();
  Env env = settings(5);
  env["CAPS"] = "video/x-bayer,format=rggb,width=4000,height=4000";
  const ScriptRun run = run_script("genicam-live.sh", {}, env, log("genicam"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 1) << run.log;
  EXPECT_NE(run.log.find("camera 127.0.0.1 cannot send CAPS (video/x-bayer,format=rggb,width=4000"),
            std::string::npos)
      << run.log;
  EXPECT_EQ(run.log.find("stopped streaming ("), std::string::npos) << run.log;
}

// A camera that is not there (an address of TEST-NET-1, RFC 5737) is named as not found, not
// as one that stopped streaming. Aravis gives up on it after about 5 s, within the watchdog's
// time here.
TEST_F(GenICam, a_camera_not_found_says_so_n) {
  Env env = settings(5);
  env["CAMERA"] = "192.0.2.1";
  env["WATCHDOG_MS"] = "60000";
  const ScriptRun run = run_script("genicam-live.sh", {}, env, log("genicam"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 1) << run.log;
  EXPECT_NE(run.log.find("camera 192.0.2.1 not found"), std::string::npos) << run.log;
  EXPECT_EQ(run.log.find("stopped streaming"), std::string::npos) << run.log;
}

}  // namespace
}  // namespace pyrocam::test
