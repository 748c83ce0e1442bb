// pyrocam-calib export: a recording of known codes (made here with stock GStreamer elements:
// raw GRAY16_LE frames through FFV1 into two Matroska segments, as record.sh writes them) to
// .npy, TIFF and CSV, checked value by value; and the messages for inputs that are no recording.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdint>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/region_stats.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;
namespace fs = std::filesystem;

// An odd width: GRAY16 rows are padded to 4 bytes in GStreamer, not in the exports.
constexpr int kW = 7, kH = 5, kFrames = 6;

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

struct ToolResult {
  int exit_code = -1;
  std::string err;
};
ToolResult run(const std::string& command, const fs::path& err) {
  const int status = std::system((command + " < /dev/null > /dev/null 2> " + q(err)).c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, read_all(err)};
}
ToolResult run_export(const std::string& args, const ScratchDir& dir) {
  return run("timeout 120 " + q(PYROCAM_CALIB_TOOL) + " export " + args, dir / "stderr.txt");
}

// Frame f: codes from `base` (12732: 1000 degC) that differ per pixel and frame, some pixels
// without a reading, and frame 2 with none at all.
cv::Mat frame_codes(int f, int base = 12732) {
  cv::Mat m(kH, kW, CV_16U);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x)
      m.at<std::uint16_t>(y, x) = f == 2 || (x + y + f) % 5 == 0
                                      ? 0
                                      : static_cast<std::uint16_t>(base + 37 * x + 101 * y + 7 * f);
  return m;
}

class CliExport : public ::testing::Test {
 protected:
  void SetUp() override { record(rec); }
  // A recording without pyrocam tags of frame_codes(f, base) in `folder`, segments of
  // `segment_ms`; `restarting`: each segment's times from 0, as record.sh writes them.
  void record(const fs::path& folder, int base = 12732, int segment_ms = 300,
              bool restarting = false) {
    fs::create_directories(folder);
    // rawvideoparse reads rows at GStreamer's stride: 2 * 7 bytes padded to 16.
    constexpr int kStride = (2 * kW + 3) / 4 * 4;
    std::ofstream raw(dir / "frames.raw", std::ios::binary);
    for (int f = 0; f < kFrames; ++f) {
      const cv::Mat m = frame_codes(f, base);
      for (int y = 0; y < kH; ++y) {
        std::string row(reinterpret_cast<const char*>(m.ptr(y)), 2 * kW);
        row.resize(kStride, '\0');
        raw << row;
      }
    }
    raw.close();
    // 10 fps, segments of 0.3 s: 3 frames in each. pyrocam-launch, not gst-launch-1.0, which
    // hangs at the end of this pipeline in about one run in three (GStreamer 1.22).
    const ToolResult r =
        run("timeout 60 " + q(PYROCAM_LAUNCH) + " filesrc location=" + q(dir / "frames.raw") +
                " blocksize=" + std::to_string(kStride * kH) +
                " ! rawvideoparse format=gray16-le width=" + std::to_string(kW) +
                " height=" + std::to_string(kH) +
                " framerate=10/1 ! avenc_ffv1 gop-size=1 ! splitmuxsink "
                "async-finalize=true muxer-factory=matroskamux " +
                (restarting ? "'muxer-properties=properties,min-cluster-duration=(guint64)0,"
                              "offset-to-zero=true' "
                            : "") +
                "max-size-time=" + std::to_string(segment_ms) +
                "000000 location=" + q(folder / "temperature-%05d.mkv"),
            dir / "gst.txt");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  ScratchDir dir{"cli-export"};
  fs::path rec = dir / "rec";
};

TEST_F(CliExport, writes_the_codes_and_their_statistics) {
  const fs::path npy = dir / "t.npy", tif = dir / "t.tif", csv = dir / "t.csv";
  const ToolResult r = run_export("--recording " + q(rec) + " --npy " + q(npy) + " --tiff " +
                                      q(tif) + " --csv " + q(csv) + " --peak-window 3",
                                  dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Recorded without ratiotemp: no tags, said so.
  EXPECT_NE(r.err.find("no pyrocam tags"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("6 frames of 7x5 from 2 segment(s)"), std::string::npos) << r.err;

  std::string codes;
  for (int f = 0; f < kFrames; ++f) {
    const cv::Mat m = frame_codes(f);
    codes.append(reinterpret_cast<const char*>(m.data), m.total() * 2);
  }
  const std::string n = read_all(npy);
  ASSERT_GT(n.size(), 10u);
  EXPECT_EQ(n.substr(0, 8), std::string("\x93NUMPY\x01\x00", 8));
  const std::size_t header = static_cast<unsigned char>(n[8]) | static_cast<unsigned char>(n[9])
                                                                    << 8;
  EXPECT_EQ((10 + header) % 64, 0u);  // the format's alignment
  EXPECT_NE(n.find("'descr': '<u2', 'fortran_order': False, 'shape': (6, 5, 7), }"),
            std::string::npos)
      << n.substr(0, 10 + header);
  EXPECT_TRUE(n.substr(10 + header) == codes) << "the .npy data differ from the frames";

  std::vector<cv::Mat> pages;
  ASSERT_TRUE(cv::imreadmulti(tif.string(), pages, cv::IMREAD_UNCHANGED));
  ASSERT_EQ(pages.size(), static_cast<std::size_t>(kFrames));
  for (int f = 0; f < kFrames; ++f) {
    ASSERT_EQ(pages[f].type(), CV_16UC1);
    EXPECT_EQ(cv::countNonZero(pages[f] != frame_codes(f)), 0) << "page " << f;
  }

  std::istringstream lines(read_all(csv));
  std::string line;
  std::getline(lines, line);
  EXPECT_EQ(line, "index,timestamp_s,valid_fraction,min_c,median_c,mean_c,max_c,peak_c");
  for (int f = 0; f < kFrames; ++f) {
    ASSERT_TRUE(std::getline(lines, line)) << "row " << f;
    const cv::Mat t = decode_decikelvin(frame_codes(f));
    const RegionStats s = region_stats(t);
    const RegionPeak p = region_peak(t, 3);
    char expected[256];
    const auto cell = [](double v, int decimals) {
      char b[40] = "";
      if (std::isfinite(v)) std::snprintf(b, sizeof b, "%.*f", decimals, v);
      return std::string(b);
    };
    std::snprintf(expected, sizeof expected, "%d,%.6f,%.6f,%s,%s,%s,%s,%s", f, f / 10.0,
                  s.valid_fraction, cell(s.min_c, 2).c_str(), cell(s.median_c, 2).c_str(),
                  cell(s.mean_c, 3).c_str(), cell(s.max_c, 2).c_str(), cell(p.c, 2).c_str());
    EXPECT_EQ(line, expected);
  }
  // Frame 2 has no reading: its temperatures are empty cells, not 0 or -273.15.
  EXPECT_EQ(std::string(read_all(csv)).find("2,0.200000,0.000000,,,,,\n") != std::string::npos,
            true)
      << read_all(csv);
  EXPECT_FALSE(std::getline(lines, line));
}

// Without tags (matroskamux writes them at a segment's end, so one cut short has none) an
// uncertainty recording's codes would read as temperatures near -200 degC.
TEST_F(CliExport, rejects_untagged_codes_that_read_below_freezing_n) {
  record(dir / "u", 150);
  const ToolResult r =
      run_export("--recording " + q(dir / "u") + " --csv " + q(dir / "u.csv"), dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("no pyrocam tags, and 140 of its 140 readings would be below 0 degC: not "
                       "temperatures"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "u.csv"));
}

TEST_F(CliExport, rejects_a_missing_folder_n) {
  const ToolResult r =
      run_export("--recording " + q(dir / "nowhere") + " --npy " + q(dir / "t.npy"), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nowhere: no such recording"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "t.npy"));
}

TEST_F(CliExport, rejects_a_folder_without_segments_n) {
  fs::create_directories(dir / "empty");
  const ToolResult r =
      run_export("--recording " + q(dir / "empty") + " --csv " + q(dir / "t.csv"), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("not a recording (no temperature-NNNNN.mkv segments)"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(dir / "t.csv"));
}

TEST_F(CliExport, rejects_a_segment_that_is_not_matroska_n) {
  test::write_text(rec / "temperature-00002.mkv", "not a video\n");
  const ToolResult r = run_export(
      "--recording " + q(rec) + " --npy " + q(dir / "t.npy") + " --csv " + q(dir / "t.csv"), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("temperature-00002.mkv: not a readable recording segment"),
            std::string::npos)
      << r.err;
  // Nothing under the names asked for, and no partial files left.
  EXPECT_FALSE(fs::exists(dir / "t.npy"));
  EXPECT_FALSE(fs::exists(dir / "t.csv"));
  EXPECT_FALSE(fs::exists(dir / "t.npy.partial"));
}

// Cut short before its first frame: a segment inside the recording is refused; the last one is
// what a recording killed as it began that segment leaves, and the rest is read, with a warning.
TEST_F(CliExport, rejects_a_segment_truncated_before_its_first_frame_n) {
  const fs::path first = rec / "temperature-00000.mkv", last = rec / "temperature-00001.mkv";
  const std::string first_bytes = read_all(first), last_bytes = read_all(last);
  ASSERT_GT(first_bytes.size(), 200u);
  ASSERT_GT(last_bytes.size(), 200u);
  std::ofstream(first, std::ios::binary | std::ios::trunc) << first_bytes.substr(0, 120);
  ToolResult r = run_export("--recording " + q(rec) + " --npy " + q(dir / "t.npy"), dir);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("temperature-00000.mkv"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "t.npy"));
  std::ofstream(first, std::ios::binary | std::ios::trunc) << first_bytes;
  std::ofstream(last, std::ios::binary | std::ios::trunc) << last_bytes.substr(0, 120);
  r = run_export("--recording " + q(rec) + " --npy " + q(dir / "t.npy"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("temperature-00001.mkv: not a readable"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("last segment, cut short"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("3 frames of 7x5 from 2 segment(s)"), std::string::npos) << r.err;
}

// A segment inside the recording cut short after its first frame (a copy, a full disk): its
// missing frame is said, and the next segment, whose times restart at 0, still starts at 0.4 s
// (it was read at 0.3 s, each later frame a frame early). A segment missing from the numbering is
// refused: the frames after it could not be placed in time.
TEST_F(CliExport, a_cut_middle_segment_keeps_later_times_and_a_missing_one_is_refused_n) {
  const fs::path cut = dir / "cut";
  record(cut, 12732, 200, true);  // 0-1, 2-3, 4-5
  const fs::path middle = cut / "temperature-00001.mkv";
  const std::string bytes = read_all(middle);
  const std::string cluster = "\x1f\x43\xb6\x75";
  const auto second = bytes.find(cluster, bytes.find(cluster) + 1);
  ASSERT_NE(second, std::string::npos);
  std::ofstream(middle, std::ios::binary | std::ios::trunc) << bytes.substr(0, second);
  ToolResult r = run_export("--recording " + q(cut) + " --csv " + q(dir / "cut.csv"), dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("temperature-00001.mkv: its frames end 0.1 s into its 0.2 s: cut short"),
            std::string::npos)
      << r.err;
  std::istringstream lines(read_all(dir / "cut.csv"));
  std::string line;
  std::vector<std::string> times;
  std::getline(lines, line);  // the header
  while (std::getline(lines, line)) times.push_back(line.substr(0, line.find(',', 2)));
  EXPECT_EQ(times, (std::vector<std::string>{"0,0.000000", "1,0.100000", "2,0.200000", "3,0.400000",
                                             "4,0.500000"}));
  fs::remove(middle);
  r = run_export("--recording " + q(cut) + " --csv " + q(dir / "gap.csv"), dir);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_NE(r.err.find("temperature-00001.mkv is missing"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir / "gap.csv"));
}

TEST_F(CliExport, needs_an_output_and_a_tiff_name_n) {
  ToolResult r = run_export("--recording " + q(rec), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("at least one of --tiff, --npy, --csv"), std::string::npos) << r.err;
  r = run_export("--recording " + q(rec) + " --tiff " + q(dir / "t.png"), dir);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find(".tif or .tiff"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace pyrocam
