// The scripts in pipelines/, each run as users run it (a child process with settings in its
// environment, bounded frames, a time limit), what came out checked against the same frames
// computed by a reference pipeline in this process: recorded temperatures bit-exact, frame
// counts, caps, the overlay pixel by pixel, a stream received on loopback.
#include <gst/pbutils/pbutils.h>
#include <signal.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <thread>

#include "element_support.h"
#include "pipeline_support.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;

// Small frames keep every run within seconds; the simulated camera is seeded, so the same
// settings give the same frames in a script and in a reference pipeline.
constexpr int kWidth = 160, kHeight = 120, kFps = 30;
const std::string kCaps = "video/x-bayer,width=160,height=120,framerate=30/1";
const std::string kDark = "dark-level=50";
const std::string kScene = "pyrocamsrc scene=melt-pool seed=7";
const std::string kLiveScene = kScene + " is-live=true";
constexpr milliseconds kRunLimit(60000);

// Raw camera frames to temperatures, as in the scripts.
std::string temperature_elements() {
  return "darksub " + kDark + " ! demosaic25 ! ratiotemp model=\"" + rgb_model() + "\"";
}
std::string temperature_chain() { return kCaps + " ! " + temperature_elements(); }

// The reference frames, computed here without the scripts.
Video reference_temperatures(int frames) {
  return pull_frames(kScene + " num-buffers=" + std::to_string(frames) + " ! " +
                     temperature_chain() + " ! appsink name=out");
}
Video reference_overlay(int frames) {
  return pull_frames(
      kScene + " num-buffers=" + std::to_string(frames) + " ! " + temperature_chain() +
      " ! thermalcolormap scale-bar=true ! video/x-raw,format=RGBA ! appsink name=out");
}
Video reference_camera(int frames) {
  return pull_frames(kScene + " num-buffers=" + std::to_string(frames) + " ! " + kCaps +
                     " ! bayer2rgb ! video/x-raw,format=RGBA ! appsink name=out");
}

// The overlay over the camera image as the stream sends it, before H.264: through I420 (4:2:0).
Video reference_stream_view(int frames) {
  return pull_frames(kScene + " num-buffers=" + std::to_string(frames) + " ! " + kCaps +
                     " ! tee name=camera camera. ! queue ! bayer2rgb ! video/x-raw,format=RGBA ! "
                     "mix.sink_0 camera. ! queue ! " +
                     temperature_elements() +
                     " ! thermalcolormap scale-bar=true ! video/x-raw,format=RGBA ! mix.sink_1 "
                     "compositor name=mix sink_0::zorder=0 sink_1::zorder=1 ! "
                     "video/x-raw,format=RGBA ! videoconvert ! video/x-raw,format=I420 ! "
                     "videoconvert ! video/x-raw,format=RGBA ! appsink name=out");
}

// The melt pool must give readings, or a bit-exact comparison of empty frames would prove little.
// At 160x120 the simulated pool is 5 pixels in radius and its core saturates: demosaic25's
// matched kernels read about 5 rim pixels a frame (bilinear read 18, half of them more than
// 150 degC off).
void expect_readings(const Video& temperatures) {
  std::size_t valid = 0;
  for (const Bytes& f : temperatures.frames)
    for (std::size_t i = 0; i + 1 < f.size(); i += 2) valid += (f[i] | f[i + 1]) != 0;
  EXPECT_GE(valid, temperatures.frames.size() * 3)
      << "the reference frames hold fewer than 3 readings a frame";
}

// ---------------------------------------------------------------------------------------------

TEST(Files, every_pipeline_has_a_purpose_line_and_a_test) {
  const std::set<std::string> tested = {"live-view.sh", "record.sh",       "playback.sh",
                                        "stream.sh",    "watch-stream.sh", "genicam-live.sh"};
  std::set<std::string> found;
  for (const auto& entry : fs::directory_iterator(pipeline_script(""))) {
    if (entry.is_directory()) continue;  // lib/: what the scripts source, not a job
    const std::string name = entry.path().filename().string();
    found.insert(name);
    EXPECT_TRUE(tested.count(name)) << name << " is in pipelines/ but no test runs it";
    std::ifstream in(entry.path());
    std::string shebang, purpose;
    std::getline(in, shebang);
    std::getline(in, purpose);
    EXPECT_EQ(shebang, "#!/usr/bin/env bash") << name;
    EXPECT_EQ(purpose.rfind("# ", 0), 0u) << name << ": line 2 must be '# <purpose>'";
    EXPECT_GE(purpose.size(), 30u) << name << ": a one-line purpose on line 2";
    EXPECT_TRUE((fs::status(entry.path()).permissions() & fs::perms::owner_exec) != fs::perms::none)
        << name << " is not executable";
  }
  for (const auto& name : tested) EXPECT_TRUE(found.count(name)) << name << " is missing";
}

// The duration GstDiscoverer (gst-discoverer-1.0, players) reports for a file, in seconds; -1
// when it cannot tell.
double discovered_duration_s(const std::string& path) {
  GError* error = nullptr;
  GstDiscoverer* discoverer = gst_discoverer_new(10 * GST_SECOND, &error);
  if (!discoverer) {
    g_clear_error(&error);
    return -1;
  }
  gchar* uri = gst_filename_to_uri(path.c_str(), nullptr);
  GstDiscovererInfo* info = gst_discoverer_discover_uri(discoverer, uri, &error);
  g_free(uri);
  g_clear_error(&error);
  double seconds = -1;
  if (info) {
    const GstClockTime d = gst_discoverer_info_get_duration(info);
    if (GST_CLOCK_TIME_IS_VALID(d)) seconds = static_cast<double>(d) / GST_SECOND;
    g_object_unref(info);
  }
  g_object_unref(discoverer);
  return seconds;
}

// ---------------------------------------------------------------------------------------------

// pyrocam-launch, which the scripts run their pipelines with: gst-launch-1.0 of GStreamer 1.22
// hangs after an early error in about one run in three (a race in its bus handling).
std::string launcher() {
  const char* path = std::getenv("PYROCAM_LAUNCH");
  return path && *path ? path : "pyrocam-launch";
}

TEST(Launcher, ends_every_early_error_with_exit_1_and_the_message_n) {
  REQUIRE_ELEMENT("pyrocamsrc");
  ScratchDir dir("launcher");
  for (int run = 0; run < 50; ++run) {
    const std::string log = (dir / ("run-" + std::to_string(run) + ".log")).string();
    // A Bayer size that is not whole periods: pyrocamsrc refuses the caps as it starts.
    Process p({launcher(), "pyrocamsrc", "num-buffers=3", "!", "video/x-bayer,width=4097,height=3",
               "!", "fakesink"},
              {}, log);
    const auto status = p.wait_for(milliseconds(20000));  // the guard that detects a hang
    if (!status) p.signal(SIGKILL);
    ASSERT_TRUE(status.has_value()) << "run " << run << " hung after the error: " << p.log();
    ASSERT_EQ(*status, 1) << "run " << run << ": " << p.log();
    ASSERT_NE(p.log().find("ERROR: from element"), std::string::npos) << p.log();
    ASSERT_NE(p.log().find("4097"), std::string::npos) << p.log();
  }
}

TEST(Launcher, ends_a_missing_file_error_that_hangs_gst_launch_n) {
  ScratchDir dir("launcher-file");
  for (int run = 0; run < 20; ++run) {
    Process p({launcher(), "multifilesrc", "location=" + (dir / "nonexistent-%d.png").string(), "!",
               "fakesink"},
              {}, (dir / ("run-" + std::to_string(run) + ".log")).string());
    const auto status = p.wait_for(milliseconds(20000));
    if (!status) p.signal(SIGKILL);
    ASSERT_TRUE(status.has_value()) << "run " << run << " hung: " << p.log();
    ASSERT_EQ(*status, 1) << p.log();
    ASSERT_NE(p.log().find("ERROR: from element"), std::string::npos) << p.log();
  }
}

TEST(Launcher, ends_at_eos_with_exit_0_and_refuses_a_bad_description_or_value_n) {
  ScratchDir dir("launcher-eos");
  Process ok({launcher(), "videotestsrc", "num-buffers=3", "!", "fakesink"}, {},
             (dir / "eos.log").string());
  ASSERT_EQ(ok.wait_for(milliseconds(20000)), 0) << ok.log();
  Process bad({launcher(), "no-such-element", "!", "fakesink"}, {}, (dir / "bad.log").string());
  ASSERT_EQ(bad.wait_for(milliseconds(20000)), 2) << bad.log();
  EXPECT_NE(bad.log().find("no-such-element"), std::string::npos) << bad.log();
  // A value out of its range: refused (gst-launch-1.0 warns and keeps the default).
  Process range({launcher(), "fakesrc", "num-buffers=1", "!", "identity", "drop-probability=2"}, {},
                (dir / "range.log").string());
  ASSERT_EQ(range.wait_for(milliseconds(20000)), 2) << range.log();
  EXPECT_NE(range.log().find("drop-probability"), std::string::npos) << range.log();
}

TEST(Launcher, sigint_sends_eos_and_ends_with_exit_0) {
  ScratchDir dir("launcher-sigint");
  const std::string file = (dir / "out.mkv").string();
  Process p(
      {launcher(), "-e", "videotestsrc", "is-live=true", "!", "video/x-raw,width=64,height=48", "!",
       "avenc_ffv1", "!", "matroskamux", "!", "filesink", "location=" + file},
      {}, (dir / "sigint.log").string());
  ASSERT_TRUE(wait_until([&] { return fs::exists(file) && fs::file_size(file) > 1000; },
                         milliseconds(20000)))
      << p.log();
  p.signal(SIGINT);
  const auto status = p.wait_for(milliseconds(20000));
  if (!status) p.signal(SIGKILL);
  ASSERT_TRUE(status.has_value()) << p.log();
  EXPECT_EQ(*status, 0) << p.log();
  EXPECT_NE(p.log().find("Got EOS"), std::string::npos) << p.log();
}

// ---------------------------------------------------------------------------------------------

class LiveView : public PipelineTest {};

TEST_F(LiveView, overlay_over_the_camera_image_frame_by_frame) {
  constexpr int kFrames = 20;
  const ScriptRun run = run_script("live-view.sh", {},
                                   {{"MODEL", rgb_model()},
                                    {"SOURCE", kScene},
                                    {"CAPS", kCaps},
                                    {"NUM_BUFFERS", std::to_string(kFrames)},
                                    {"SINK", raw_sink(dir, "view-")}},
                                   log("live-view"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;
  const auto frames = frames_in_files(dir.path().string(), "view-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));
  const Video camera = reference_camera(kFrames), overlay = reference_overlay(kFrames);
  ASSERT_EQ(camera.frames.size(), static_cast<std::size_t>(kFrames)) << camera.error;
  ASSERT_EQ(overlay.frames.size(), static_cast<std::size_t>(kFrames)) << overlay.error;
  int opaque = 0;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_EQ(frames[i].size(), static_cast<std::size_t>(kWidth * kHeight * 4)) << "frame " << i;
    const CompositeCheck c = check_composite(frames[i], camera.frames[i], overlay.frames[i]);
    EXPECT_EQ(c.wrong, 0) << "frame " << i << ": " << c.opaque << " opaque, " << c.transparent
                          << " transparent, " << c.blended << " blended overlay pixels";
    opaque += c.opaque;
  }
  EXPECT_GT(opaque, kFrames * 100)
      << "no overlay drawn (no opaque pixel: no reading, no scale bar)";
}

TEST_F(LiveView, rejects_a_missing_model_n) {
  const std::string missing = (dir / "no-such-model.json").string();
  const ScriptRun run = run_script("live-view.sh", {},
                                   {{"MODEL", missing}, {"NUM_BUFFERS", "5"}, {"SINK", "fakesink"}},
                                   log("live-view"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_NE(*run.status, 0);
  EXPECT_NE(run.log.find(missing), std::string::npos) << run.log;
}

// ---------------------------------------------------------------------------------------------

class Record : public PipelineTest {
 protected:
  Env settings(const std::string& source, int frames) const {
    return {{"MODEL", rgb_model()},
            {"OUT", (dir / "rec").string()},
            {"SOURCE", source},
            {"CAPS", kCaps},
            {"NUM_BUFFERS", std::to_string(frames)},
            {"SEGMENT_SECONDS", "0.5"},
            {"SNAPSHOT_RATE", std::to_string(kFps)}};
  }
  std::vector<std::string> segments() const {
    return files_in((dir / "rec").string(), "temperature-", ".mkv");
  }
  // record.sh run with `env` into one segment of `frames` frames: that segment decoded (no
  // frames, with a failure, where the run or the segment is not that).
  Video record_one_segment(const Env& env, const std::string& name, int frames) {
    const ScriptRun run = run_script("record.sh", {}, env, log(name), kRunLimit);
    EXPECT_EQ(run.status, 0) << run.log;
    const auto files = segments();
    EXPECT_EQ(files.size(), 1u);
    if (run.status != 0 || files.size() != 1) return {};
    Video recorded = decode_segment(files[0]);
    EXPECT_EQ(recorded.frames.size(), static_cast<std::size_t>(frames)) << recorded.error;
    return recorded;
  }
  static constexpr int kFramesPerSegment = kFps / 2;  // SEGMENT_SECONDS = 0.5
};

TEST_F(Record, temperatures_decode_bit_exact_in_segments_with_a_snapshot) {
  constexpr int kFrames = 3 * kFramesPerSegment;
  const ScriptRun run =
      run_script("record.sh", {}, settings(kScene, kFrames), log("record"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;

  const Video reference = reference_temperatures(kFrames);
  ASSERT_EQ(reference.frames.size(), static_cast<std::size_t>(kFrames)) << reference.error;
  ASSERT_EQ(reference.frames[0].size(), static_cast<std::size_t>(kWidth * kHeight * 2));
  expect_readings(reference);

  const auto files = segments();
  ASSERT_EQ(files.size(), 3u);
  int next = 0;
  for (const auto& file : files) {
    // Each segment decodes alone: its own key frames and header.
    const Video seg = decode_segment(file);
    ASSERT_TRUE(seg.error.empty()) << file << ": " << seg.error;
    EXPECT_EQ(seg.frames.size(), static_cast<std::size_t>(kFramesPerSegment)) << file;
    EXPECT_EQ(seg.format, "GRAY16_LE");
    EXPECT_EQ(seg.width, kWidth);
    EXPECT_EQ(seg.height, kHeight);
    EXPECT_EQ(seg.fps_n, kFps);
    EXPECT_EQ(seg.fps_d, 1);
    for (const Bytes& frame : seg.frames) {
      ASSERT_LT(next, kFrames);
      EXPECT_TRUE(frame == reference.frames[next]) << file << ": frame " << next << " differs";
      ++next;
    }
  }
  EXPECT_EQ(next, kFrames);

  // The container holds FFV1, and the segments play as one stream in order.
  const Video encoded =
      pull_frames("filesrc location=\"" + files[0] + "\" ! matroskademux ! appsink name=out");
  EXPECT_EQ(encoded.media, "video/x-ffv") << encoded.error;
  const Video joined =
      pull_frames("splitmuxsrc location=\"" + (dir / "rec" / "temperature-*.mkv").string() +
                  "\" ! avdec_ffv1 ! appsink name=out");
  ASSERT_EQ(joined.frames.size(), static_cast<std::size_t>(kFrames)) << joined.error;
  EXPECT_TRUE(joined.frames == reference.frames);

  // The snapshot is the last frame's colour-mapped view over the camera image.
  const Video snapshot =
      pull_frames("filesrc location=\"" + (dir / "rec" / "view.png").string() +
                  "\" ! pngdec ! videoconvert ! video/x-raw,format=RGBA ! appsink name=out");
  ASSERT_EQ(snapshot.frames.size(), 1u) << snapshot.error;
  EXPECT_EQ(snapshot.width, kWidth);
  EXPECT_EQ(snapshot.height, kHeight);
  const Video camera = reference_camera(kFrames), overlay = reference_overlay(kFrames);
  ASSERT_EQ(camera.frames.size(), static_cast<std::size_t>(kFrames)) << camera.error;
  ASSERT_EQ(overlay.frames.size(), static_cast<std::size_t>(kFrames)) << overlay.error;
  const CompositeCheck c =
      check_composite(snapshot.frames[0], camera.frames.back(), overlay.frames.back());
  EXPECT_EQ(c.wrong, 0);
  EXPECT_GT(c.opaque, 100);
}

// BRIGHTNESS_RADIUS: ratiotemp reads each pixel from its own sample; the recording holds the
// frames of the same chain with brightness-radius, which differ from the ratio readings; bad
// values are refused.
TEST_F(Record, brightness_radius_records_the_brightness_readings) {
  constexpr int kFrames = 4;
  Env env = settings(kScene, kFrames);
  env["BRIGHTNESS_RADIUS"] = "2";
  const Video recorded = record_one_segment(env, "record-brightness", kFrames);
  ASSERT_EQ(recorded.frames.size(), static_cast<std::size_t>(kFrames));
  const Video bright = pull_frames(kScene + " num-buffers=" + std::to_string(kFrames) + " ! " +
                                   temperature_chain() + " brightness-radius=2 ! appsink name=out");
  ASSERT_EQ(bright.frames.size(), static_cast<std::size_t>(kFrames)) << bright.error;
  EXPECT_TRUE(recorded.frames == bright.frames);
  EXPECT_FALSE(bright.frames == reference_temperatures(kFrames).frames)
      << "the same as the ratio readings: a weak test";
  for (const char* bad : {"9", "-1", "two"}) {
    env["BRIGHTNESS_RADIUS"] = bad;
    const ScriptRun refused =
        run_script("record.sh", {}, env, log("record-brightness-bad"), kRunLimit);
    EXPECT_EQ(refused.status, 2) << bad << ": " << refused.log;
    EXPECT_NE(refused.log.find("BRIGHTNESS_RADIUS"), std::string::npos) << refused.log;
  }
}

// BRACKET: the simulated camera cycles through the exposures and the recording holds the fused
// frames, bit for bit those of the same chain with thermalfuse; bad settings are refused.
TEST_F(Record, bracket_records_the_fused_frames) {
  constexpr int kFrames = 12;
  const std::string bracket = "1,0.333,0.111";
  Env env = settings(kScene, kFrames);
  env["BRACKET"] = bracket;
  env["SEGMENT_SECONDS"] = "10";
  const Video recorded = record_one_segment(env, "record-bracket", kFrames);
  ASSERT_EQ(recorded.frames.size(), static_cast<std::size_t>(kFrames));
  const std::string camera = kScene + " bracket=" + bracket +
                             " num-buffers=" + std::to_string(kFrames) + " ! " + kCaps + " ! " +
                             temperature_elements();
  const Video fused = pull_frames(camera + " ! thermalfuse frames=3 ! appsink name=out");
  const Video single = pull_frames(camera + " ! appsink name=out");
  ASSERT_EQ(fused.frames.size(), static_cast<std::size_t>(kFrames)) << fused.error;
  ASSERT_EQ(single.frames.size(), static_cast<std::size_t>(kFrames)) << single.error;
  EXPECT_TRUE(recorded.frames == fused.frames);
  EXPECT_FALSE(fused.frames == single.frames) << "the fusion changed nothing: a weak test";

  // BRACKET_FUSION=mosaics: mosaicfuse between darksub and demosaic25 instead, and ratiotemp's
  // blur correction (BLUR_CORRECTION's default there).
  env["BRACKET_FUSION"] = "mosaics";
  env["OUT"] = (dir / "rec-mosaics").string();
  const ScriptRun mosaics = run_script("record.sh", {}, env, log("record-mosaics"), kRunLimit);
  ASSERT_EQ(mosaics.status, 0) << mosaics.log;
  const auto mosaic_files = files_in((dir / "rec-mosaics").string(), "temperature-", ".mkv");
  ASSERT_EQ(mosaic_files.size(), 1u);
  const Video recorded_mosaics = decode_segment(mosaic_files[0]);
  const Video fused_mosaics = pull_frames(
      kScene + " bracket=" + bracket + " num-buffers=" + std::to_string(kFrames) + " ! " + kCaps +
      " ! darksub " + kDark + " ! mosaicfuse frames=3 ! demosaic25 ! ratiotemp model=\"" +
      rgb_model() + "\" blur-correction=true ! appsink name=out");
  ASSERT_EQ(fused_mosaics.frames.size(), static_cast<std::size_t>(kFrames)) << fused_mosaics.error;
  EXPECT_TRUE(recorded_mosaics.frames == fused_mosaics.frames);
  EXPECT_FALSE(fused_mosaics.frames == fused.frames) << "the same as fusing readings";

  for (const auto& [key, value] :
       std::vector<std::pair<std::string, std::string>>{{"BRACKET", "1,zero"},
                                                        {"SOURCE", "videotestsrc"},
                                                        {"EXPOSURE_CONTROL", "1"},
                                                        {"BRACKET_FUSION", "pixels"},
                                                        {"RAW", "1"}}) {
    Env bad = settings(kScene, 2);
    bad["BRACKET"] = "1,0.1";
    bad["OUT"] = (dir / ("rec-bad-" + key)).string();
    bad[key] = value;
    const ScriptRun r = run_script("record.sh", {}, bad, log("record-bracket-bad"), kRunLimit);
    ASSERT_TRUE(r.status.has_value()) << "hung";
    EXPECT_EQ(*r.status, 2) << key << "=" << value << ": " << r.log;
    EXPECT_NE(r.log.find("BRACKET"), std::string::npos) << r.log;
  }
}

TEST_F(Record, ctrl_c_finalises_the_last_segment) {
  Process rec({pipeline_script("record.sh")}, settings(kLiveScene, -1), log("record"));
  // Two segments on disk: the first is closed, the second is being written.
  ASSERT_TRUE(
      wait_until([&] { return segments().size() >= 2 || !rec.running(); }, milliseconds(20000)))
      << rec.log();
  ASSERT_TRUE(rec.running()) << rec.log();
  std::this_thread::sleep_for(milliseconds(200));
  rec.signal_group(SIGINT);  // what Ctrl-C in a terminal does
  const auto status = rec.wait_for(milliseconds(15000));
  ASSERT_TRUE(status.has_value()) << "no exit 15 s after SIGINT: " << rec.log();
  EXPECT_EQ(*status, 0) << rec.log();

  std::vector<Bytes> recorded;
  const auto files = segments();
  for (const auto& file : files) {
    const Video seg = decode_segment(file);
    ASSERT_TRUE(seg.error.empty()) << file << " was not finalised: " << seg.error;
    EXPECT_FALSE(seg.frames.empty()) << file;
    recorded.insert(recorded.end(), seg.frames.begin(), seg.frames.end());
  }
  ASSERT_GT(recorded.size(), static_cast<std::size_t>(kFramesPerSegment));
  const Video reference = reference_temperatures(static_cast<int>(recorded.size()));
  ASSERT_EQ(reference.frames.size(), recorded.size()) << reference.error;
  for (std::size_t i = 0; i < recorded.size(); ++i)
    EXPECT_TRUE(recorded[i] == reference.frames[i]) << "frame " << i << " differs";
}

TEST_F(Record, sigkill_loses_at_most_the_last_segment) {
  Process rec({pipeline_script("record.sh")}, settings(kLiveScene, -1), log("record"));
  ASSERT_TRUE(
      wait_until([&] { return segments().size() >= 3 || !rec.running(); }, milliseconds(20000)))
      << rec.log();
  ASSERT_TRUE(rec.running()) << rec.log();
  std::this_thread::sleep_for(milliseconds(300));  // some frames into the last segment
  rec.signal_group(SIGKILL);
  ASSERT_EQ(rec.wait_for(milliseconds(5000)), 128 + SIGKILL);

  const auto files = segments();
  ASSERT_GE(files.size(), 3u);
  std::vector<Bytes> recorded;
  for (std::size_t s = 0; s + 1 < files.size(); ++s) {
    const Video seg = decode_segment(files[s]);
    ASSERT_TRUE(seg.error.empty()) << files[s] << ": " << seg.error;
    EXPECT_EQ(seg.frames.size(), static_cast<std::size_t>(kFramesPerSegment)) << files[s];
    recorded.insert(recorded.end(), seg.frames.begin(), seg.frames.end());
  }
  const Video reference = reference_temperatures(static_cast<int>(recorded.size()));
  ASSERT_EQ(reference.frames.size(), recorded.size()) << reference.error;
  for (std::size_t i = 0; i < recorded.size(); ++i)
    EXPECT_TRUE(recorded[i] == reference.frames[i]) << "frame " << i << " differs";

  // The killed segment has no index and no duration; with a Matroska cluster per frame the
  // duration a player estimates (from the last cluster) is that of the frames it decodes, not
  // up to a cluster (0.5 s by default) short.
  const std::string& last = files.back();
  const Video tail = decode_segment(last);
  const double decoded_s = static_cast<double>(tail.frames.size()) / kFps;
  const double estimated_s = discovered_duration_s(last);
  std::cout << "[ info     ] killed segment: " << tail.frames.size() << " frames decoded ("
            << decoded_s << " s), discoverer's duration " << estimated_s << " s\n";
  if (tail.frames.size() >= 2) {
    EXPECT_NEAR(estimated_s, decoded_s, 3.0 / kFps) << last;
  }
}

TEST_F(Record, rejects_a_corrupt_model_n) {
  const std::string model = (dir / "corrupt-model.json").string();
  write_text(model, "{ \"format\": \"pyrocam-model\", \"version\": 1, ");
  Env env = settings(kScene, 10);
  env["MODEL"] = model;
  const ScriptRun run = run_script("record.sh", {}, env, log("record"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_NE(*run.status, 0) << run.log;
  EXPECT_NE(run.log.find("corrupt-model.json"), std::string::npos) << run.log;
  for (const auto& file : segments())
    EXPECT_TRUE(decode_segment(file).frames.empty()) << file << " holds frames from a bad model";
}

// ---------------------------------------------------------------------------------------------

class Playback : public PipelineTest {};

TEST_F(Playback, colour_frames_of_a_recording_match_thermalcolormap) {
  constexpr int kFrames = 30;
  const std::string rec = (dir / "rec").string();
  const ScriptRun recording = run_script("record.sh", {},
                                         {{"MODEL", rgb_model()},
                                          {"OUT", rec},
                                          {"SOURCE", kScene},
                                          {"CAPS", kCaps},
                                          {"NUM_BUFFERS", std::to_string(kFrames)},
                                          {"SEGMENT_SECONDS", "0.5"}},
                                         log("record"), kRunLimit);
  ASSERT_EQ(recording.status, 0) << recording.log;
  ASSERT_EQ(files_in(rec, "temperature-", ".mkv").size(), 2u);

  const ScriptRun run = run_script("playback.sh", {rec}, {{"SINK", raw_sink(dir, "play-")}},
                                   log("playback"), kRunLimit);
  ASSERT_EQ(run.status, 0) << run.log;
  const auto frames = frames_in_files(dir.path().string(), "play-");
  const Video reference = reference_overlay(kFrames);
  ASSERT_EQ(reference.frames.size(), static_cast<std::size_t>(kFrames)) << reference.error;
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));
  for (int i = 0; i < kFrames; ++i)
    EXPECT_TRUE(frames[i] == reference.frames[i]) << "colour frame " << i << " differs";
}

TEST_F(Playback, rejects_a_folder_without_segments_n) {
  const ScriptRun run = run_script("playback.sh", {dir.path().string()}, {{"SINK", "fakesink"}},
                                   log("playback"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_NE(*run.status, 0);
  EXPECT_NE(run.log.find("no temperature-*.mkv segments"), std::string::npos) << run.log;
}

// ---------------------------------------------------------------------------------------------

class Stream : public PipelineTest {};

TEST_F(Stream, received_on_loopback_by_watch_stream) {
  constexpr int kFrames = 30;
  const int port = free_udp_port();
  ASSERT_GT(port, 0);
  Process screen(
      {pipeline_script("watch-stream.sh")},
      {{"ADDRESS", "127.0.0.1"}, {"PORT", std::to_string(port)}, {"SINK", raw_sink(dir, "rx-")}},
      log("watch-stream"));
  ASSERT_TRUE(
      wait_until([&] { return udp_port_bound(port) || !screen.running(); }, milliseconds(10000)))
      << screen.log();
  ASSERT_TRUE(screen.running()) << screen.log();

  const ScriptRun sent = run_script("stream.sh", {},
                                    {{"HOST", "127.0.0.1"},
                                     {"PORT", std::to_string(port)},
                                     {"MODEL", rgb_model()},
                                     // Not live: a live compositor sends a frame every
                                     // interval with whatever has arrived, so on a loaded
                                     // machine frames go out without their overlay, or
                                     // repeated (72 instead of 30 at load 12 on 2 cores).
                                     // Not live, what is sent depends on the frames alone.
                                     {"SOURCE", kScene},
                                     {"CAPS", kCaps},
                                     {"NUM_BUFFERS", std::to_string(kFrames)}},
                                    log("stream"), kRunLimit);
  ASSERT_EQ(sent.status, 0) << sent.log;
  // A screen shows frames until stopped: wait for the last one and any extra, then stop it.
  const auto received = [&] { return files_in(dir.path().string(), "rx-", ".rgba").size(); };
  const auto all = [&] { return received() >= static_cast<std::size_t>(kFrames); };
  ASSERT_TRUE(wait_until(all, milliseconds(60000))) << received() << " " << screen.log();
  std::this_thread::sleep_for(milliseconds(300));
  ASSERT_TRUE(screen.running()) << screen.log();
  screen.signal_group(SIGINT);
  const auto status = screen.wait_for(milliseconds(10000));
  ASSERT_TRUE(status.has_value()) << "the screen did not stop on Ctrl-C: " << screen.log();
  EXPECT_EQ(*status, 0) << screen.log();

  const auto frames = frames_in_files(dir.path().string(), "rx-");
  ASSERT_EQ(frames.size(), static_cast<std::size_t>(kFrames));
  const Video reference = reference_stream_view(kFrames);
  ASSERT_EQ(reference.frames.size(), static_cast<std::size_t>(kFrames)) << reference.error;
  double worst = INFINITY;
  for (int i = 0; i < kFrames; ++i) {
    ASSERT_EQ(frames[i].size(), static_cast<std::size_t>(kWidth * kHeight * 4));
    // H.264 is lossy: the frame must be the same picture, not the same bytes. A missing
    // overlay or a frame out of order falls far below 30 dB.
    const double db = psnr(frames[i], reference.frames[i]);
    worst = std::min(worst, db);
    EXPECT_GT(db, 30.0) << "frame " << i;
  }
  std::cout << "[ info     ] worst PSNR of the received frames: " << worst << " dB\n";
}

TEST_F(Stream, screen_without_packets_ends_in_an_error_n) {
  const int port = free_udp_port();
  ASSERT_GT(port, 0);
  const ScriptRun run = run_script("watch-stream.sh", {},
                                   {{"ADDRESS", "127.0.0.1"},
                                    {"PORT", std::to_string(port)},
                                    {"WATCHDOG_MS", "500"},
                                    {"SINK", "fakesink"}},
                                   log("watch-stream"), kRunLimit);
  ASSERT_TRUE(run.status.has_value()) << "hung";
  EXPECT_EQ(*run.status, 1) << run.log;
  EXPECT_NE(run.log.find("GstWatchdog:no-stream-packets"), std::string::npos) << run.log;
  // A guard against a screen that waits far longer than its watchdog, not a speed target: 500 ms
  // of watchdog plus the start of a pipeline, with room for a machine slowed many times over.
  EXPECT_LT(run.seconds, 30.0);
}

}  // namespace
}  // namespace pyrocam::test
