// Recordings as data: record.sh's segments describe themselves in tags (read back with
// GstDiscoverer, in every segment), STATS_CSV logs ratiotemp's statistics, `pyrocam-calib
// export` gives the recorded codes bit-exactly as .npy and TIFF and per-frame statistics as CSV,
// and examples/read_recording.py reads the same numbers into NumPy.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <tuple>
#include <vector>

#include "element_support.h"
#include "pipeline_support.h"
#include "recording_files.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

namespace fs = std::filesystem;
using namespace recording_files;  // NOLINT(google-build-using-namespace)

// 320x240: the simulated pool is 10 pixels in radius, enough readings a frame for a window peak
// (at 160x120, 5 pixels, matched demosaicking reads only its rim: about 6 a frame).
constexpr int kWidth = 320, kHeight = 240, kFps = 30, kFrames = 30;  // two 0.5 s segments
const std::string kCaps = "video/x-bayer,width=320,height=240,framerate=30/1";
const std::string kScene = "pyrocamsrc scene=melt-pool seed=7";
constexpr int kStatsIntervalMs = 100;

// One recording made by record.sh for every test here, with STATS_CSV, and the same frames
// computed directly.
class Recordings : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir = new ScratchDir("recordings");
    rec = *dir / "rec";
    const Env env = {{"MODEL", rgb_model()},
                     {"OUT", rec.string()},
                     {"SOURCE", kScene},
                     {"CAPS", kCaps},
                     {"NUM_BUFFERS", std::to_string(kFrames)},
                     {"SEGMENT_SECONDS", "0.5"},
                     {"STATS_CSV", (*dir / "stats.csv").string()},
                     {"STATS_INTERVAL_MS", std::to_string(kStatsIntervalMs)}};
    run = new ScriptRun(
        run_script("record.sh", {}, env, (*dir / "record.log").string(), milliseconds(60000)));
    reference =
        new Video(pull_frames(kScene + " num-buffers=" + std::to_string(kFrames) + " ! " + kCaps +
                              " ! darksub dark-level=50 ! demosaic25 ! " + "ratiotemp model=\"" +
                              rgb_model() + "\" ! appsink name=out"));
  }
  static void TearDownTestSuite() {
    delete reference;
    delete run;
    delete dir;
  }
  void SetUp() override {
    for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
    ASSERT_EQ(run->status, 0) << run->log;
    ASSERT_EQ(reference->frames.size(), static_cast<std::size_t>(kFrames)) << reference->error;
  }
  static std::vector<std::string> segments() {
    return files_in(rec.string(), "temperature-", ".mkv");
  }
  // The reference frames' codes, rows without padding (320 pixels: none).
  static std::string reference_bytes() {
    std::string all;
    for (const Bytes& f : reference->frames) all.append(f.begin(), f.end());
    return all;
  }
  static inline ScratchDir* dir = nullptr;
  static inline fs::path rec;
  static inline ScriptRun* run = nullptr;
  static inline Video* reference = nullptr;
};

TEST_F(Recordings, every_segment_says_its_units_model_profile_and_method) {
  // The model's fingerprint is its file's checksum.
  const std::string model = read_text(rgb_model());
  const std::size_t at = model.find("\"checksum_fnv1a64\": \"");
  ASSERT_NE(at, std::string::npos);
  const std::string fingerprint = model.substr(at + 21, 16);
  const auto files = segments();
  ASSERT_EQ(files.size(), 2u);
  for (const auto& file : files) {
    const auto [title, comment] = discovered_tags(file);
    EXPECT_NE(title.find("0.1 K per code"), std::string::npos) << file << ": " << title;
    EXPECT_EQ(comment.rfind("pyrocam-recording; quantity=temperature; unit=0.1 K; no-reading=0; "
                            "model=test-model-rgb.json; model-fingerprint=" +
                                fingerprint + "; profile=rgb-reference; method=",
                            0),
              0u)
        << file << ": " << comment;
    EXPECT_NE(comment.find("; e-slope=0 %/100 nm"), std::string::npos) << comment;
    // demosaic25 linked to ratiotemp (the fused path) says its method in the caps too.
    EXPECT_NE(comment.find("; demosaic=matched"), std::string::npos) << comment;
  }
}

TEST_F(Recordings, export_gives_the_recorded_codes_and_their_statistics) {
  const fs::path npy = *dir / "t.npy", csv = *dir / "t.csv", tiff = *dir / "t.tif";
  ASSERT_EQ(run_command("'" + std::string(PYROCAM_CALIB_TOOL) + "' export --recording '" +
                            rec.string() + "' --npy '" + npy.string() + "' --csv '" + csv.string() +
                            "' --tiff '" + tiff.string() + "'",
                        *dir / "export.log"),
            0)
      << read_text(*dir / "export.log");
  const Npy n = read_npy(npy);
  EXPECT_EQ(n.descr, "<u2");
  EXPECT_EQ(n.shape, (std::vector<long>{kFrames, kHeight, kWidth}));
  EXPECT_TRUE(n.data == reference_bytes()) << "the .npy codes differ from the recorded frames";
  // The TIFF: one 16-bit page per frame (checked by its size: 2 bytes a pixel, uncompressed or
  // not, it cannot hold the frames in fewer than a few kB; the pages are read back by the CLI
  // tests).
  EXPECT_GT(fs::file_size(tiff), 1000u);
  EXPECT_FALSE(fs::exists(tiff.string() + ".partial.tif"));

  const auto rows = read_csv(csv);
  ASSERT_EQ(rows.size(), static_cast<std::size_t>(kFrames + 1));
  EXPECT_EQ(rows[0], (std::vector<std::string>{"index", "timestamp_s", "valid_fraction", "min_c",
                                               "median_c", "mean_c", "max_c", "peak_c"}));
  std::size_t total_valid = 0;
  int peaks = 0;
  for (int i = 0; i < kFrames; ++i) {
    const auto& r = rows[static_cast<std::size_t>(i + 1)];
    ASSERT_EQ(r.size(), 8u);
    EXPECT_EQ(std::stoi(r[0]), i);
    // Matroska keeps milliseconds; the second segment follows the first.
    EXPECT_NEAR(std::stod(r[1]), static_cast<double>(i) / kFps, 0.0015) << i;
    // Against the codes of the reference frame, computed here.
    const Bytes& f = reference->frames[static_cast<std::size_t>(i)];
    std::size_t valid = 0;
    double lo = INFINITY, hi = -INFINITY;
    for (std::size_t p = 0; p + 1 < f.size(); p += 2) {
      const int code = f[p] | f[p + 1] << 8;
      if (!code) continue;
      ++valid;
      lo = std::min(lo, code / 10.0 - 273.15);
      hi = std::max(hi, code / 10.0 - 273.15);
    }
    ASSERT_GT(valid, 0u) << "frame " << i << " of the melt pool has no readings";
    total_valid += valid;
    EXPECT_NEAR(std::stod(r[2]), static_cast<double>(valid) / (kWidth * kHeight), 1e-6);
    EXPECT_NEAR(std::stod(r[3]), lo, 0.006);
    EXPECT_NEAR(std::stod(r[6]), hi, 0.006);
    EXPECT_LE(std::stod(r[3]), std::stod(r[4]));
    EXPECT_LE(std::stod(r[4]), std::stod(r[6]));
    // A window median is no maximum; no window at least half read: no peak (an empty cell).
    if (!r[7].empty()) {
      EXPECT_LE(std::stod(r[7]), std::stod(r[6]) + 0.006);
      ++peaks;
    }
  }
  EXPECT_GT(total_valid, static_cast<std::size_t>(kFrames) * 10);
  EXPECT_GT(peaks, 0);
}

TEST_F(Recordings, stats_csv_has_a_row_per_statistics_message_matching_the_export) {
  const auto rows = read_csv(*dir / "stats.csv");
  ASSERT_GE(rows.size(), 2u) << read_text(*dir / "stats.csv");
  const auto& header = rows[0];
  ASSERT_GE(header.size(), 14u);
  EXPECT_EQ(header[0], "element");
  EXPECT_EQ(header[1], "timestamp");
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  const std::size_t ts = column("timestamp"), median = column("median-c");
  ASSERT_LT(median, header.size());
  // A row for the first frame and then one at least every 100 ms of 1 s of frames: 8 to 11.
  const std::size_t messages = rows.size() - 1;
  EXPECT_GE(messages, 8u);
  EXPECT_LE(messages, 11u);
  // Each row's median of the unquantised temperatures is within half a code (0.05 K) of the
  // recorded frame's median at that time (the export's, from the codes, printed to 0.01: 0.005
  // more).
  const fs::path csv = *dir / "for-stats.csv";
  ASSERT_EQ(run_command("'" + std::string(PYROCAM_CALIB_TOOL) + "' -q export --recording '" +
                            rec.string() + "' --csv '" + csv.string() + "' ",
                        *dir / "export2.log"),
            0);
  const auto exported = read_csv(csv);
  ASSERT_EQ(exported.size(), static_cast<std::size_t>(kFrames + 1));
  guint64 last = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), header.size()) << "row " << i;
    EXPECT_EQ(rows[i][0], "ratiotemp0");
    const guint64 t = std::stoull(rows[i][ts]);
    if (i > 1) {
      EXPECT_GE(t, last + kStatsIntervalMs * GST_MSECOND - GST_MSECOND) << "row " << i;
    }
    last = t;
    const auto frame = static_cast<std::size_t>(std::llround(t * 1e-9 * kFps));
    ASSERT_LT(frame, static_cast<std::size_t>(kFrames));
    EXPECT_NEAR(std::stod(rows[i][median]), std::stod(exported[frame + 1][4]), 0.0551)
        << "frame " << frame;
  }
}

TEST_F(Recordings, python_example_reads_the_recording_in_celsius) {
  const fs::path npy = *dir / "celsius.npy", log = *dir / "python.log";
  if (run_command("/usr/bin/python3 -c 'import gi, numpy'", log) != 0)
    FAIL() << "python3-gi or python3-numpy missing (scripts/install-deps.sh --tests): "
           << read_text(log);
  ASSERT_EQ(
      run_command("/usr/bin/python3 '" + std::string(PYROCAM_EXAMPLES_DIR) +
                      "/read_recording.py' '" + rec.string() + "' --save '" + npy.string() + "'",
                  log),
      0)
      << read_text(log);
  EXPECT_NE(read_text(log).find("# 30 frames of 320x240; pyrocam-recording"), std::string::npos)
      << read_text(log);
  const Npy n = read_npy(npy);
  EXPECT_EQ(n.descr, "<f4");
  ASSERT_EQ(n.shape, (std::vector<long>{kFrames, kHeight, kWidth}));
  ASSERT_EQ(n.data.size(), static_cast<std::size_t>(kFrames * kHeight * kWidth * 4));
  const std::string codes = reference_bytes();
  std::size_t wrong = 0, readings = 0;
  for (std::size_t i = 0; i < codes.size() / 2; ++i) {
    const int code = static_cast<unsigned char>(codes[2 * i]) |
                     static_cast<unsigned char>(codes[2 * i + 1]) << 8;
    float c = 0;
    std::memcpy(&c, n.data.data() + 4 * i, 4);
    if (code == 0) {
      wrong += !std::isnan(c);
    } else {
      ++readings;
      wrong += !(std::fabs(c - (code / 10.0 - 273.15)) < 1e-3);  // float32 of a 0.1 K step
    }
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GT(readings, static_cast<std::size_t>(kFrames) * 10);
}

// A recording killed as a segment began leaves that segment empty: export, the Python example
// and playback.sh read the segments before it, saying what they left out. An empty segment
// inside a recording stays an error.
TEST_F(Recordings, a_last_segment_cut_off_as_it_began_leaves_the_rest_readable) {
  const fs::path cut = *dir / "cut";
  fs::create_directories(cut);
  for (const std::string& s : segments()) fs::copy_file(s, cut / fs::path(s).filename());
  // The segment after the last, as splitmuxsink numbers them (a gap is refused).
  char next[32];
  std::snprintf(next, sizeof next, "temperature-%05zu.mkv", segments().size());
  write_text(cut / next, "");
  const std::string tool = "'" + std::string(PYROCAM_CALIB_TOOL) + "' ";
  const fs::path csv = *dir / "cut.csv", log = *dir / "cut.log";
  ASSERT_EQ(
      run_command(tool + "export --recording '" + cut.string() + "' --csv '" + csv.string() + "'",
                  log),
      0)
      << read_text(log);
  EXPECT_NE(read_text(log).find(std::string(next) + ": not a readable"), std::string::npos)
      << read_text(log);
  EXPECT_EQ(read_csv(csv).size(), static_cast<std::size_t>(kFrames + 1));
  ASSERT_EQ(run_command("/usr/bin/python3 '" + std::string(PYROCAM_EXAMPLES_DIR) +
                            "/read_recording.py' '" + cut.string() + "'",
                        log),
            0)
      << read_text(log);
  EXPECT_NE(read_text(log).find("# 30 frames of 320x240"), std::string::npos) << read_text(log);
  const ScriptRun played = run_script("playback.sh", {cut.string()}, {{"SINK", "fakesink"}},
                                      (*dir / "cut-playback.log").string(), milliseconds(60000));
  EXPECT_EQ(played.status, 0) << played.log;
  EXPECT_NE(played.log.find("leaving out segments of"), std::string::npos) << played.log;
  EXPECT_NE(played.log.find(next), std::string::npos) << played.log;
  // Its Matroska header and no frame (a copy cut short, a full disk): splitmuxsrc waited on it
  // for ever.
  const std::string whole = read_text(segments().front());
  const auto first_cluster = whole.find("\x1f\x43\xb6\x75");
  ASSERT_NE(first_cluster, std::string::npos);
  write_text(cut / next, whole.substr(0, first_cluster));
  const ScriptRun headed =
      run_script("playback.sh", {cut.string()}, {{"SINK", "fakesink"}},
                 (*dir / "cut-header-playback.log").string(), milliseconds(60000));
  EXPECT_EQ(headed.status, 0) << headed.log;
  EXPECT_NE(headed.log.find(next), std::string::npos) << headed.log;
  // Emptied inside the recording, a segment is an error.
  write_text(cut / "temperature-00000.mkv", "");
  EXPECT_EQ(
      run_command(tool + "export --recording '" + cut.string() + "' --csv '" + csv.string() + "'",
                  log),
      1);
  EXPECT_NE(read_text(log).find("temperature-00000.mkv"), std::string::npos) << read_text(log);
}

// A segment missing from the numbering is a gap in time that splitmuxsrc plays through:
// playback.sh names it.
TEST_F(Recordings, a_missing_segment_is_named_when_played) {
  const fs::path gap = *dir / "gap";
  fs::create_directories(gap);
  const std::vector<std::string> all = segments();
  ASSERT_GE(all.size(), 2u);  // the gap is between two
  for (std::size_t i = 0; i < all.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "temperature-%05zu.mkv", i + 1 == all.size() ? i + 1 : i);
    fs::copy_file(all[i], gap / name);
  }
  const ScriptRun played = run_script("playback.sh", {gap.string()}, {{"SINK", "fakesink"}},
                                      (*dir / "gap-playback.log").string(), milliseconds(60000));
  EXPECT_EQ(played.status, 0) << played.log;
  const std::string missing =
      "segment " + std::to_string(all.size() - 1) + " of " + gap.string() + " is missing";
  EXPECT_NE(played.log.find(missing), std::string::npos) << played.log;
}

// Segments past temperature-99999 (record.sh numbers on: about 2.8 hours of 0.1 s segments)
// follow it by number, not as text: export and the Python example refused such a recording as
// having a gap, and playback.sh would have said so.
TEST_F(Recordings, segments_past_99999_follow_by_number) {
  const fs::path big = *dir / "big";
  fs::create_directories(big);
  const std::vector<std::string> all = segments();
  ASSERT_GE(all.size(), 2u);
  fs::copy_file(all[0], big / "temperature-99999.mkv");
  fs::copy_file(all[1], big / "temperature-100000.mkv");
  const std::string tool = "'" + std::string(PYROCAM_CALIB_TOOL) + "' ";
  const fs::path csv = *dir / "big.csv", log = *dir / "big.log";
  ASSERT_EQ(
      run_command(tool + "export --recording '" + big.string() + "' --csv '" + csv.string() + "'",
                  log),
      0)
      << read_text(log);
  ASSERT_EQ(run_command("/usr/bin/python3 '" + std::string(PYROCAM_EXAMPLES_DIR) +
                            "/read_recording.py' '" + big.string() + "'",
                        log),
            0)
      << read_text(log);
  const ScriptRun played = run_script("playback.sh", {big.string()}, {{"SINK", "fakesink"}},
                                      (*dir / "big-playback.log").string(), milliseconds(60000));
  EXPECT_EQ(played.status, 0) << played.log;
  EXPECT_EQ(played.log.find("missing"), std::string::npos) << played.log;
}

// Settings that gst-launch took silently (a host that resolves to nothing streamed nowhere, a
// KEY_SECONDS that is not a number made every frame a key frame) or refused naming an element's
// property are refused by name, before the camera starts.
TEST(StreamSettings, bad_settings_are_refused_by_name_n) {
  ScratchDir dir("stream-bad-settings");
  for (const auto& [script, key, value] :
       std::vector<std::tuple<std::string, std::string, std::string>>{
           {"stream.sh", "HOST", "not..a.host"},
           {"stream.sh", "PORT", "0"},
           {"stream.sh", "PORT", "70000"},
           {"stream.sh", "BITRATE", "abc"},
           {"stream.sh", "KEY_SECONDS", "abc"},
           {"stream.sh", "KEY_SECONDS", "-5"},
           {"watch-stream.sh", "ADDRESS", "300.1.1.1"},
           {"watch-stream.sh", "PORT", "x"},
           {"watch-stream.sh", "LATENCY_MS", "soon"}}) {
    const ScriptRun run = run_script(
        script, {},
        {{key, value}, {"MODEL", rgb_model()}, {"NUM_BUFFERS", "3"}, {"SINK", "fakesink"}},
        (dir / ("bad-" + key + ".log")).string(), milliseconds(60000));
    ASSERT_TRUE(run.status.has_value()) << "hung";
    EXPECT_EQ(*run.status, 2) << script << " " << key << "=" << value << ": " << run.log;
    EXPECT_NE(run.log.find(key + " "), std::string::npos) << run.log;
    EXPECT_NE(run.log.find("'" + value + "'"), std::string::npos) << run.log;
  }
}

// Refused by record.sh, naming the variable (gst-launch named only the element's property), before
// anything is calibrated or recorded.
// SEGMENT_SECONDS=1e-12 was one unsplit segment (0 ns: no limit), 1e30 an error naming
// splitmuxsink's property.
TEST(RecordingsScript, bad_snapshot_rate_and_watchdog_are_refused_by_name_n) {
  ScratchDir dir("record-bad-settings");
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, std::string>>{{"SNAPSHOT_RATE", "0"},
                                                        {"SNAPSHOT_RATE", "fast"},
                                                        {"WATCHDOG_MS", "abc"},
                                                        {"WATCHDOG_MS", "-5"},
                                                        {"NUM_BUFFERS", "abc"},
                                                        {"SEGMENT_SECONDS", "1e-12"},
                                                        {"SEGMENT_SECONDS", "1e30"},
                                                        {"SEGMENT_SECONDS", "0.01"}}) {
    Env env = {{"MODEL", rgb_model()},
               {"OUT", (dir / "rec").string()},
               {"SOURCE", kScene},
               {"CAPS", kCaps},
               {"NUM_BUFFERS", "2"}};
    env[key] = value;
    const ScriptRun r =
        run_script("record.sh", {}, env, (dir / (key + ".log")).string(), milliseconds(60000));
    ASSERT_TRUE(r.status.has_value()) << "hung";
    EXPECT_EQ(*r.status, 2) << key << "=" << value << ": " << r.log;
    EXPECT_NE(r.log.find(key + (key == "SEGMENT_SECONDS" ? " must be a number of seconds from 0.1"
                                                         : " must be a whole number")),
              std::string::npos)
        << r.log;
    EXPECT_FALSE(fs::exists(dir / "rec")) << key << "=" << value;
  }
}

// pyrocam-launch --stats-csv on its own: frames without a reading keep every column (empty
// temperature cells), and a file that cannot be created is a usage error before anything runs.
TEST(RecordingsLauncher, stats_csv_keeps_its_columns_without_readings_and_refuses_a_bad_path_n) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
  const char* env = std::getenv("PYROCAM_LAUNCH");
  const std::string launch = env && *env ? env : "pyrocam-launch";
  ScratchDir dir("launcher-csv");
  const fs::path csv = dir / "stats.csv";
  // A dark level just below the saturation level (220 DN): no readings at all.
  Process p(
      {launch, "--stats-csv=" + csv.string(), "pyrocamsrc", "num-buffers=3", "!",
       "video/x-bayer,width=16,height=12,framerate=30/1", "!", "darksub", "dark-level=219", "!",
       "demosaic25", "!", "ratiotemp", "model=" + rgb_model(), "stats-interval=1", "!", "fakesink"},
      {}, (dir / "run.log").string());
  ASSERT_EQ(p.wait_for(milliseconds(30000)), 0) << p.log();
  const auto rows = read_csv(csv);
  ASSERT_EQ(rows.size(), 4u) << read_text(csv);
  const auto& header = rows[0];
  const auto col = [&](const char* name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  ASSERT_LT(col("region-peak-y"), header.size());
  ASSERT_EQ(col("region-saturated"), header.size() - 6);  // columns only get appended
  ASSERT_EQ(col("region-tracks-peak"), header.size() - 5);
  ASSERT_EQ(col("above-range"), header.size() - 4);
  ASSERT_EQ(col("region-above-range"), header.size() - 3);
  ASSERT_EQ(col("peak-u-sys-c"), header.size() - 2);
  ASSERT_EQ(col("region-peak-u-sys-c"), header.size() - 1);
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), header.size()) << "row " << i;
    EXPECT_NE(rows[i][col("saturated")], "");  // a count, 0 or more
    EXPECT_EQ(rows[i][col("above-range")], "0");
    EXPECT_EQ(rows[i][col("region-saturated")], "");
    EXPECT_EQ(rows[i][col("region-above-range")], "");
    EXPECT_EQ(rows[i][col("peak-u-sys-c")], "");  // no reading, no peak
    EXPECT_EQ(rows[i][col("region-peak-u-sys-c")], "");
    EXPECT_EQ(rows[i][col("region-tracks-peak")], "");
    EXPECT_EQ(rows[i][col("valid")], "0");
    EXPECT_EQ(rows[i][col("pixels")], "192");
    EXPECT_EQ(rows[i][col("min-c")], "");
    EXPECT_EQ(rows[i][col("region-x")], "");  // no region set
    EXPECT_EQ(rows[i][col("width")], "16");
  }

  Process bad({launch, "--stats-csv=" + (dir / "no-such-folder" / "s.csv").string(), "videotestsrc",
               "num-buffers=1", "!", "fakesink"},
              {}, (dir / "bad.log").string());
  ASSERT_EQ(bad.wait_for(milliseconds(20000)), 2) << bad.log();
  EXPECT_NE(bad.log().find("--stats-csv: cannot create"), std::string::npos) << bad.log();
  EXPECT_NE(bad.log().find("no-such-folder"), std::string::npos) << bad.log();

  // An option without its '=' (the value after a space) is no pipeline: the usage, exit 2;
  // --help is the usage on standard output, exit 0.
  Process spaced(
      {launch, "--stats-csv", csv.string(), "videotestsrc", "num-buffers=1", "!", "fakesink"}, {},
      (dir / "spaced.log").string());
  ASSERT_EQ(spaced.wait_for(milliseconds(20000)), 2) << spaced.log();
  EXPECT_NE(spaced.log().find("unknown option '--stats-csv'"), std::string::npos) << spaced.log();
  EXPECT_NE(spaced.log().find("usage: pyrocam-launch"), std::string::npos) << spaced.log();
  Process help({launch, "--help"}, {}, (dir / "help.log").string());
  ASSERT_EQ(help.wait_for(milliseconds(20000)), 0) << help.log();
  EXPECT_NE(help.log().find("usage: pyrocam-launch"), std::string::npos) << help.log();
}

// -e after an error mid-stream (a camera that vanished: the watchdog's error, then the
// source's): the end of stream goes in past the source, whose thread is stuck on or failing
// with the camera, so the file being written is finalised (its index, Matroska's Cues, at the
// end) with every frame before the error. Sent to the pipeline, aravissrc stopped with an error
// instead, and the launcher's stop guard exited before the file was closed.
TEST(RecordingsLauncher, an_error_mid_stream_with_e_still_finalises_the_file_n) {
  for (const char* e : {"avenc_ffv1", "matroskamux", "identity"}) REQUIRE_ELEMENT(e);
  const char* env = std::getenv("PYROCAM_LAUNCH");
  const std::string launch = env && *env ? env : "pyrocam-launch";
  ScratchDir dir("launcher-error");
  const fs::path file = dir / "rec.mkv";
  Process p({launch, "-e", "videotestsrc", "is-live=true", "num-buffers=100", "!",
             "video/x-raw,format=GRAY16_LE,width=32,height=24,framerate=30/1", "!", "identity",
             "error-after=10", "!", "avenc_ffv1", "!", "matroskamux", "!", "filesink",
             "location=" + file.string()},
            {}, (dir / "run.log").string());
  ASSERT_EQ(p.wait_for(milliseconds(30000)), 1) << p.log();
  EXPECT_NE(p.log().find("sending EOS so that the files are finalised"), std::string::npos)
      << p.log();
  const std::string bytes = read_text(file);
  const std::string cues = "\x1C\x53\xBB\x6B";  // also in the header's seek table
  EXPECT_NE(bytes.rfind(cues), bytes.find(cues)) << "no index at the end: not finalised";
  const Video v = pull_frames("filesrc location=" + file.string() +
                              " ! matroskademux ! avdec_ffv1 ! appsink name=out");
  ASSERT_TRUE(v.error.empty()) << v.error;
  EXPECT_EQ(v.frames.size(), 9u);  // identity fails the tenth
}

// --alarm-csv: thermalalarm's change of state as a row with the alarm's columns.
TEST(RecordingsLauncher, alarm_csv_has_a_row_per_change_of_state) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp", "thermalalarm"})
    REQUIRE_ELEMENT(e);
  const char* env = std::getenv("PYROCAM_LAUNCH");
  const std::string launch = env && *env ? env : "pyrocam-launch";
  ScratchDir dir("launcher-alarm");
  const fs::path csv = dir / "alarms.csv";
  // A plate at 1200 degC watched with a threshold of 1000 degC: raised on the second frame.
  Process p({launch,
             "--alarm-csv=" + csv.string(),
             "pyrocamsrc",
             "scene=plate",
             "temperature=1200",
             "num-buffers=6",
             "!",
             "video/x-bayer,width=32,height=24,framerate=30/1",
             "!",
             "darksub",
             "dark-level=50",
             "!",
             "demosaic25",
             "!",
             "ratiotemp",
             "model=" + rgb_model(),
             "!",
             "thermalalarm",
             "threshold-c=1000",
             "frames=2",
             "!",
             "fakesink"},
            {}, (dir / "run.log").string());
  ASSERT_EQ(p.wait_for(milliseconds(30000)), 0) << p.log();
  const auto rows = read_csv(csv);
  ASSERT_EQ(rows.size(), 2u) << read_text(csv);
  EXPECT_EQ(rows[0], (std::vector<std::string>{
                         "element", "state", "active", "statistic", "value-c", "threshold-c",
                         "clear-c", "frames", "timestamp", "running-time", "region-x", "region-y",
                         "region-width", "region-height", "saturated", "above-range"}));
  const auto& r = rows[1];
  ASSERT_EQ(r.size(), rows[0].size());
  EXPECT_EQ(r[0], "thermalalarm0");
  EXPECT_EQ(r[1], "raised");
  EXPECT_EQ(r[2], "true");
  EXPECT_EQ(r[3], "median");
  EXPECT_NEAR(std::stod(r[4]), 1200, 60);  // the plate read through the test model
  EXPECT_EQ(r[5], "1000");
  EXPECT_EQ(r[6], "990");
  EXPECT_EQ(r[7], "2");
  EXPECT_EQ(r[8], std::to_string(GST_SECOND / 30));  // the second frame
  EXPECT_EQ(r[12], "32");
}

}  // namespace
}  // namespace pyrocam::test
