// pyrocam-serve as users run it (a child process), on loopback with the ports the system picks
// (--rtsp-port 0 --http-port 0; it prints them): RTSP clients in this process receive both
// streams, two at a time and after another client vanished; the temperature stream is compared
// bit-exactly with the same seeded camera's temperatures computed here; the camera vanishes and
// returns; bad input gives clear messages; headless Chromium shows the page.
#include <arpa/inet.h>
#include <gst/app/gstappsink.h>
#include <gst/gst.h>
#include <gst/video/video.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "http_client.h"
#include "pipeline_support.h"
#include "serve_support.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

// An RTSP client in this process: rtspsrc, H.264 decoder, appsink.
class RtspClient {
 public:
  RtspClient(const std::string& url, const std::string& tail, const std::string& protocols) {
    const std::string description =
        "rtspsrc location=" + url + " latency=200 protocols=" + protocols +
        " ! rtph264depay ! h264parse ! avdec_h264 ! " + tail + " ! appsink name=out sync=false";
    GError* error = nullptr;
    pipeline_ = gst_parse_launch(description.c_str(), &error);
    if (error != nullptr) {
      error_ = error->message;
      g_error_free(error);
      return;
    }
    sink_ = gst_bin_get_by_name(GST_BIN(pipeline_), "out");
    gst_element_set_state(pipeline_, GST_STATE_PLAYING);
  }
  ~RtspClient() {
    if (pipeline_ != nullptr) {
      gst_element_set_state(pipeline_, GST_STATE_NULL);
      if (sink_ != nullptr) gst_object_unref(sink_);
      gst_object_unref(pipeline_);
    }
  }
  RtspClient(const RtspClient&) = delete;
  RtspClient& operator=(const RtspClient&) = delete;

  // Pulls until `count` frames came, an end of stream, an error, or `timeout`.
  void pull(std::size_t count, milliseconds timeout) {
    const auto deadline = Clock::now() + timeout;
    GstBus* bus = gst_element_get_bus(pipeline_);
    while (frames.size() < count && error_.empty() && !eos && Clock::now() < deadline) {
      if (GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
        GError* err = nullptr;
        gst_message_parse_error(msg, &err, nullptr);
        error_ = err->message;
        g_error_free(err);
        gst_message_unref(msg);
        break;
      }
      GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink_), 100 * GST_MSECOND);
      if (sample == nullptr) {
        eos = gst_app_sink_is_eos(GST_APP_SINK(sink_));
        continue;
      }
      GstVideoInfo info;
      gst_video_info_from_caps(&info, gst_sample_get_caps(sample));
      GstVideoFrame frame;
      if (gst_video_frame_map(&frame, &info, gst_sample_get_buffer(sample), GST_MAP_READ)) {
        width = info.width;
        height = info.height;
        format = gst_video_format_to_string(GST_VIDEO_INFO_FORMAT(&info));
        Bytes packed;
        // Planes without row padding, one after the other.
        for (guint p = 0; p < GST_VIDEO_FRAME_N_PLANES(&frame); ++p) {
          const int row_bytes =
              GST_VIDEO_FRAME_COMP_WIDTH(&frame, p) * GST_VIDEO_FRAME_COMP_PSTRIDE(&frame, p);
          for (int y = 0; y < GST_VIDEO_FRAME_COMP_HEIGHT(&frame, p); ++y) {
            const auto* row =
                static_cast<const std::uint8_t*>(GST_VIDEO_FRAME_PLANE_DATA(&frame, p)) +
                y * GST_VIDEO_FRAME_PLANE_STRIDE(&frame, p);
            packed.insert(packed.end(), row, row + row_bytes);
          }
        }
        frames.push_back(std::move(packed));
        gst_video_frame_unmap(&frame);
      }
      gst_sample_unref(sample);
    }
    gst_object_unref(bus);
  }
  const std::string& error() const { return error_; }

  std::vector<Bytes> frames;
  int width = 0, height = 0;
  std::string format;
  bool eos = false;

 private:
  GstElement* pipeline_ = nullptr;
  GstElement* sink_ = nullptr;
  std::string error_;
};

const std::string kRgba = "videoconvert ! video/x-raw,format=RGBA";
const std::string kY444 = "video/x-raw,format=Y444";

// The 0.1 K codes from a received Y444 frame (Y = high byte, U = low byte, V = 128).
std::vector<std::uint16_t> unpack(const Bytes& y444, int width, int height) {
  const std::size_t n = static_cast<std::size_t>(width) * height;
  std::vector<std::uint16_t> codes(n);
  for (std::size_t i = 0; i < n; ++i)
    codes[i] = static_cast<std::uint16_t>(y444[i] << 8 | y444[n + i]);
  return codes;
}

TEST(Serve, StreamsToTwoClientsAfterOneVanished) {
  ScratchDir dir("serve-streams");
  Server server = start_server(dir, {"--camera", kCamera});
  ASSERT_NE(server.rtsp, 0) << server.log();
  ASSERT_TRUE(server.process->running()) << server.log();

  // A client that is killed mid-stream (SIGKILL: no TEARDOWN) must not disturb the others.
  {
    Process gone(
        {"gst-launch-1.0", "-q", "rtspsrc", "location=" + server.url("/thermal"), "!", "fakesink"},
        Env{}, (dir / "killed-client.log").string());
    std::this_thread::sleep_for(milliseconds(3000));
    EXPECT_TRUE(gone.running()) << gone.log();
    gone.signal(SIGKILL);
    gone.wait_for(milliseconds(5000));
  }

  RtspClient thermal1(server.url("/thermal"), kRgba, "udp");
  RtspClient thermal2(server.url("/thermal"), kRgba, "tcp");
  RtspClient temperature1(server.url("/temperature"), kY444, "udp");
  RtspClient temperature2(server.url("/temperature"), kY444, "tcp");
  for (RtspClient* c : {&thermal1, &thermal2, &temperature1, &temperature2}) {
    c->pull(15, milliseconds(30000));
    EXPECT_EQ(c->error(), "");
    EXPECT_FALSE(c->eos);
    EXPECT_GE(c->frames.size(), 15u);
    EXPECT_EQ(c->width, 160);
    EXPECT_EQ(c->height, 120);
  }
  EXPECT_EQ(thermal1.format, "RGBA");
  EXPECT_EQ(temperature1.format, "Y444");
  // The overlay shows the plate: the picture is not uniform.
  ASSERT_FALSE(thermal1.frames.empty());
  const Bytes& f = thermal1.frames.back();
  EXPECT_NE(*std::min_element(f.begin(), f.end()), *std::max_element(f.begin(), f.end()));
  // The plate (about 1270 degC) reads between 500 and 3500 degC at the centre. From the TCP
  // client: over UDP a lost packet damages frames until the next key frame (docs/serve.md).
  ASSERT_FALSE(temperature2.frames.empty());
  const auto codes = unpack(temperature2.frames.back(), 160, 120);
  const double centre_c = codes[60 * 160 + 80] / 10.0 - 273.15;
  EXPECT_GT(centre_c, 500.0);
  EXPECT_LT(centre_c, 3500.0);
  EXPECT_TRUE(server.process->running()) << server.log();
}

// The received frames that are no frame of the seeded camera exactly: the camera's temperatures
// are computed here frame by frame until every received frame is found (1200 frames: 2 minutes of
// the camera, more than the test runs). `computed` receives how many it took.
std::set<std::size_t> frames_not_from_camera(
    const std::vector<std::vector<std::uint16_t>>& received, int* computed) {
  std::set<std::size_t> unmatched;
  for (std::size_t i = 0; i < received.size(); ++i) unmatched.insert(i);
  const std::string reference = "pyrocamsrc scene=plate seed=11 num-buffers=1200 ! " + kCaps +
                                " ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=\"" +
                                rgb_model() + "\" ! appsink name=out sync=false";
  GstElement* pipeline = gst_parse_launch(reference.c_str(), nullptr);
  if (pipeline == nullptr) return unmatched;
  GstElement* sink = gst_bin_get_by_name(GST_BIN(pipeline), "out");
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  *computed = 0;
  while (!unmatched.empty()) {
    GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink), 10 * GST_SECOND);
    if (sample == nullptr) break;  // the reference's end (1200 frames) or its failure
    ++*computed;
    GstMapInfo map;
    GstBuffer* buffer = gst_sample_get_buffer(sample);
    gst_buffer_map(buffer, &map, GST_MAP_READ);
    for (auto it = unmatched.begin(); it != unmatched.end();) {
      const auto& got = received[*it];
      if (map.size == got.size() * 2 && std::memcmp(map.data, got.data(), map.size) == 0)
        it = unmatched.erase(it);
      else
        ++it;
    }
    gst_buffer_unmap(buffer, &map);
    gst_sample_unref(sample);
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(sink);
  gst_object_unref(pipeline);
  return unmatched;
}

// Frames of a raw yuv444p file written by ffmpeg, unpacked to codes; the V plane must be 128.
std::vector<std::vector<std::uint16_t>> read_yuv444(const std::string& path, int width, int height,
                                                    std::size_t* bad_v) {
  const Bytes bytes = read_bytes(path);
  const std::size_t n = static_cast<std::size_t>(width) * height;
  std::vector<std::vector<std::uint16_t>> frames;
  for (std::size_t at = 0; at + 3 * n <= bytes.size(); at += 3 * n) {
    const Bytes frame(bytes.begin() + static_cast<std::ptrdiff_t>(at),
                      bytes.begin() + static_cast<std::ptrdiff_t>(at + 3 * n));
    for (std::size_t i = 0; i < n; ++i) *bad_v += frame[2 * n + i] != 128 ? 1 : 0;
    frames.push_back(unpack(frame, width, height));
  }
  return frames;
}

// Every frame a client decodes is one of the camera's, bit for bit: rtspsrc with avdec_h264
// live, and (where ffmpeg is installed) ffmpeg's own RTSP client and a copy it stored and
// decoded afterwards. With two slices a frame, the last two gave hundreds of wrong codes a frame.
TEST(Serve, TemperatureStreamIsLossless) {
  ScratchDir dir("serve-lossless");
  Server server = start_server(dir, {"--camera", kCamera});
  ASSERT_NE(server.rtsp, 0) << server.log();
  RtspClient client(server.url("/temperature"), kY444, "tcp");
  client.pull(20, milliseconds(30000));
  ASSERT_EQ(client.error(), "");
  ASSERT_GE(client.frames.size(), 20u);
  // The encoder is asked for its lossless profile: no error line per client on the console.
  EXPECT_EQ(server.log().find("x264 [error]"), std::string::npos) << server.log();
  struct Path {
    std::string name;
    std::vector<std::vector<std::uint16_t>> frames;
  };
  std::vector<Path> paths(1, {"rtspsrc ! avdec_h264", {}});
  for (const Bytes& f : client.frames) paths[0].frames.push_back(unpack(f, 160, 120));

  const std::string ffmpeg = "/usr/bin/ffmpeg";
  if (std::filesystem::exists(ffmpeg)) {
    const std::string live = (dir / "ffmpeg-live.yuv").string();
    const std::string stored = (dir / "ffmpeg-stored.h264").string();
    const std::string decoded = (dir / "ffmpeg-stored.yuv").string();
    Process receive({ffmpeg,
                     "-nostdin",
                     "-loglevel",
                     "error",
                     "-rtsp_transport",
                     "tcp",
                     "-i",
                     server.url("/temperature"),
                     "-map",
                     "0:v",
                     "-c",
                     "copy",
                     "-frames:v",
                     "20",
                     "-f",
                     "h264",
                     "-y",
                     stored,
                     "-map",
                     "0:v",
                     "-frames:v",
                     "20",
                     "-f",
                     "rawvideo",
                     "-pix_fmt",
                     "yuv444p",
                     "-y",
                     live},
                    Env{}, (dir / "ffmpeg-receive.log").string());
    const auto received = receive.wait_for(milliseconds(60000));
    ASSERT_TRUE(received.has_value()) << "ffmpeg did not end in 60 s";
    EXPECT_EQ(*received, 0) << receive.log();
    Process decode({ffmpeg, "-nostdin", "-loglevel", "error", "-i", stored, "-f", "rawvideo",
                    "-pix_fmt", "yuv444p", "-y", decoded},
                   Env{}, (dir / "ffmpeg-decode.log").string());
    const auto done = decode.wait_for(milliseconds(60000));
    ASSERT_TRUE(done.has_value()) << "ffmpeg did not end in 60 s";
    EXPECT_EQ(*done, 0) << decode.log();
    for (const auto& [name, file] : {std::pair{"ffmpeg's RTSP client", live},
                                     std::pair{"ffmpeg -c copy, decoded afterwards", decoded}}) {
      std::size_t bad_v = 0;
      paths.push_back({name, read_yuv444(file, 160, 120, &bad_v)});
      EXPECT_GE(paths.back().frames.size(), 15u) << name;
      EXPECT_EQ(bad_v, 0u) << name << ": V samples other than 128";
    }
  } else {
    std::cout << "[ info     ] no " << ffmpeg << ": only rtspsrc is checked\n";
  }

  std::vector<std::vector<std::uint16_t>> received;
  for (const Path& p : paths) received.insert(received.end(), p.frames.begin(), p.frames.end());
  int computed = 0;
  const std::set<std::size_t> unmatched = frames_not_from_camera(received, &computed);
  std::size_t first = 0;
  for (const Path& p : paths) {
    std::size_t wrong = 0;
    for (std::size_t i = first; i < first + p.frames.size(); ++i) wrong += unmatched.count(i);
    first += p.frames.size();
    std::cout << "[ info     ] " << p.name << ": " << p.frames.size() - wrong << " of "
              << p.frames.size() << " frames are the camera's exactly (among its first " << computed
              << ")\n";
    EXPECT_EQ(wrong, 0u) << p.name << ": " << wrong << " of " << p.frames.size()
                         << " received frames are no frame of the camera exactly";
  }
}

TEST(Serve, CameraVanishesAndReturns) {
  ScratchDir dir("serve-vanish");
  // 40 frames (4 s), then the camera ends; the server restarts it after 1 s. The plate is above
  // the alarm's threshold: raised in the first run, and so in the second.
  Server server = start_server(dir, {"--camera", kCamera + " num-buffers=40", "--alarm-threshold-c",
                                     "500", "--alarm-frames", "1"});
  ASSERT_NE(server.rtsp, 0) << server.log();
  RtspClient watching(server.url("/thermal"), kRgba, "tcp");
  watching.pull(100000, milliseconds(20000));
  EXPECT_TRUE(watching.eos || !watching.error().empty())
      << "the client neither ended nor failed when the camera went; frames: "
      << watching.frames.size();
  ASSERT_TRUE(wait_until([&] { return server.log().find("camera stopped") != std::string::npos; },
                         milliseconds(20000)))
      << server.log();
  EXPECT_TRUE(server.process->running()) << server.log();
  // Meanwhile the last image is not served as if it were live: 503, unless the camera came back
  // first (it says "camera running" before its first frame).
  const std::string frame = http_get(server.http, "/frame.jpg");
  const auto back = [&] {
    const std::string log = server.log();
    const auto first = log.find("camera running");
    return first != std::string::npos && log.find("camera running", first + 1) != std::string::npos;
  };
  std::cout << "[ info     ] /frame.jpg while the camera was lost: " << frame.substr(0, 21) << "\n";
  if (frame.rfind("HTTP/1.1 200", 0) == 0)
    EXPECT_TRUE(wait_until(back, milliseconds(5000)))
        << "an image served while the camera was lost";
  else
    EXPECT_EQ(frame.rfind("HTTP/1.1 503", 0), 0u) << frame.substr(0, 200);
  // The camera is back: a new client gets frames.
  ASSERT_TRUE(wait_until(back, milliseconds(20000))) << server.log();
  RtspClient again(server.url("/temperature"), kY444, "tcp");
  again.pull(10, milliseconds(20000));
  EXPECT_GE(again.frames.size(), 10u) << again.error() << "\n" << server.log();
  EXPECT_TRUE(server.process->running());
  // The restarted chain's alarm starts clear, and the page says so (the raised alarm of the first
  // run stayed on it while the new frames read below the threshold); then the new run raises it.
  const std::string log = server.log();
  const auto restarted = log.find("ALARM cleared: the camera restarted");
  ASSERT_NE(restarted, std::string::npos) << log;
  EXPECT_NE(log.find("ALARM raised"), std::string::npos) << log;
  EXPECT_TRUE(
      wait_until([&] { return server.log().find("ALARM raised", restarted) != std::string::npos; },
                 milliseconds(20000)))
      << server.log();
}

TEST(Serve, BadInputHttpRequests) {
  ScratchDir dir("serve-http");
  Server server = start_server(dir, {"--camera", kCamera});
  ASSERT_NE(server.http, 0) << server.log();
  // libsoup answers what it cannot parse with 400 (HTTP/1.0 when even the version is unknown).
  const std::regex bad_request("^HTTP/1\\.[01] 400 ");
  for (const std::string& request :
       {std::string("THIS IS NOT HTTP\r\n\r\n"),
        std::string("GET / HTTP/1.1\r\nBroken line\r\n\r\n"), std::string(20000, 'A') + "\r\n\r\n",
        std::string("\x01\x02\xff garbage\r\n\r\n", 16)}) {
    const std::string reply = http_exchange(server.http, request);
    EXPECT_TRUE(std::regex_search(reply, bad_request)) << request.substr(0, 40) << " -> " << reply;
  }
  const std::string post = http_exchange(
      server.http,
      "POST / HTTP/1.1\r\nHost: x\r\nContent-Length: 2\r\nConnection: close\r\n\r\nhi");
  EXPECT_EQ(post.rfind("HTTP/1.1 405", 0), 0u) << post;
  EXPECT_EQ(http_get(server.http, "/no-such-page").rfind("HTTP/1.1 404", 0), 0u);
  // A reader that goes after the first bytes of the event stream.
  EXPECT_NE(
      http_exchange(server.http, "GET /events HTTP/1.1\r\nHost: x\r\n\r\n").find("event: hello"),
      std::string::npos);
  // Still answering, with statistics from the camera.
  ASSERT_TRUE(wait_until(
      [&] { return http_get(server.http, "/status.json").find("\"stats\"") != std::string::npos; },
      milliseconds(10000)));
  const std::string status = http_get(server.http, "/status.json");
  const auto json = nlohmann::json::parse(status.substr(status.find("\r\n\r\n") + 4));
  EXPECT_GT(json["stats"]["median-c"].get<double>(), 500.0);
  EXPECT_EQ(json["output-pixel"], 1);  // a Bayer camera reads every sensor pixel
  const std::string jpeg = http_get(server.http, "/frame.jpg");
  EXPECT_EQ(jpeg.rfind("HTTP/1.1 200", 0), 0u);
  EXPECT_NE(jpeg.find("image/jpeg"), std::string::npos);
  EXPECT_TRUE(server.process->running()) << server.log();
}

TEST(Serve, BadInputPortInUse) {
  ScratchDir dir("serve-port");
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ASSERT_EQ(listen(fd, 1), 0);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  const std::string port = std::to_string(ntohs(addr.sin_port));
  for (const std::string option : {"--http-port", "--rtsp-port"}) {
    const std::string log_path = (dir / ("port" + option + ".log")).string();
    const std::string other = option == "--http-port" ? "--rtsp-port" : "--http-port";
    Process p({serve_binary(), "--address", "127.0.0.1", other, "0", "--model", rgb_model(), option,
               port},
              Env{}, log_path);
    const auto status = p.wait_for(milliseconds(20000));
    ASSERT_TRUE(status.has_value()) << option << ": still running with its port in use";
    EXPECT_EQ(*status, 1);
    const std::string log = p.log();
    EXPECT_NE(log.find("port " + port), std::string::npos) << log;
    EXPECT_NE(log.find(option), std::string::npos) << log;
  }
  close(fd);
}

// Options that contradict each other: a clear message and exit 2 before anything starts; with
// --region the tracking reaches ratiotemp.
TEST(Serve, BadInputRegionTracking) {
  ScratchDir dir("serve-tracking");
  Process p({serve_binary(), "--rtsp-port", "0", "--http-port", "0", "--model", rgb_model(),
             "--region-tracks-peak"},
            Env{}, (dir / "no-region.log").string());
  const auto status = p.wait_for(milliseconds(20000));
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(*status, 2);
  EXPECT_NE(p.log().find("--region-tracks-peak needs --region"), std::string::npos) << p.log();
  Process printed({serve_binary(), "--model", rgb_model(), "--region", "0,0,40,40",
                   "--region-tracks-peak", "--print-pipeline"},
                  Env{}, (dir / "print.log").string());
  const auto printed_status = printed.wait_for(milliseconds(20000));
  ASSERT_TRUE(printed_status.has_value());
  EXPECT_EQ(*printed_status, 0) << printed.log();
  EXPECT_NE(printed.log().find("region-tracks-peak=true"), std::string::npos) << printed.log();
  // Exposure control: autoexposure right after the caps, with darksub's dark level.
  Process controlled(
      {serve_binary(), "--model", rgb_model(), "--exposure-control", "--print-pipeline"}, Env{},
      (dir / "exposure.log").string());
  const auto controlled_status = controlled.wait_for(milliseconds(20000));
  ASSERT_TRUE(controlled_status.has_value());
  EXPECT_EQ(*controlled_status, 0) << controlled.log();
  EXPECT_NE(controlled.log().find("framerate=30/1 ! autoexposure dark-level=50 ! watchdog"),
            std::string::npos)
      << controlled.log();
  EXPECT_EQ(printed.log().find("autoexposure"), std::string::npos) << printed.log();
}

TEST(Serve, BadInputModel) {
  ScratchDir dir("serve-model");
  {
    Process p({serve_binary(), "--rtsp-port", "0", "--http-port", "0", "--model",
               (dir / "missing.json").string()},
              Env{}, (dir / "missing.log").string());
    const auto status = p.wait_for(milliseconds(20000));
    ASSERT_TRUE(status.has_value());
    EXPECT_EQ(*status, 1);
    EXPECT_NE(p.log().find("missing.json"), std::string::npos) << p.log();
    EXPECT_NE(p.log().find("main-job.sh"), std::string::npos) << p.log();
  }
  {
    write_text(dir / "corrupt.json", "{\"format\": \"pyrocam-model\", \"trunc");
    Process p({serve_binary(), "--address", "127.0.0.1", "--rtsp-port", "0", "--http-port", "0",
               "--caps", kCaps, "--model", (dir / "corrupt.json").string()},
              Env{}, (dir / "corrupt.log").string());
    const auto status = p.wait_for(milliseconds(30000));
    ASSERT_TRUE(status.has_value()) << "still running with a corrupt model";
    EXPECT_EQ(*status, 1);
    EXPECT_NE(p.log().find("failed before the first frame"), std::string::npos) << p.log();
    EXPECT_NE(p.log().find("corrupt.json"), std::string::npos) << p.log();
  }
}

// Chromium's DOM of the page after it ran a while.
std::string element_text(const std::string& dom, const std::string& id) {
  const std::regex re("id=\"" + id + "\"[^>]*>([^<]*)<");
  std::smatch m;
  return std::regex_search(dom, m, re) ? m[1].str() : "";
}

TEST(Serve, PageInHeadlessChromium) {
  if (!fs::exists("/usr/bin/chromium"))
    GTEST_SKIP() << "no /usr/bin/chromium (scripts/install-deps.sh --tests installs it)";
  ScratchDir dir("serve-page");
  // The plate reads about 1270 degC: an alarm at 1200 degC is raised after 3 frames.
  Server server = start_server(dir, {"--camera", kCamera, "--region", "40,30,80,60",
                                     "--alarm-threshold-c", "1200", "--alarm-frames", "3"});
  ASSERT_NE(server.http, 0) << server.log();
  const std::string url = "http://127.0.0.1:" + std::to_string(server.http) + "/";
  Chromium chromium(dir.path());
  ASSERT_TRUE(chromium.ok()) << chromium.log();
  ASSERT_TRUE(chromium.open(url)) << chromium.log();
  const std::string dom_js = "document.documentElement.outerHTML";
  std::string first, second;
  // Until the page shows the image, some statistics and the alarm (or 30 s).
  wait_until(
      [&] {
        first = chromium.evaluate(dom_js);
        return first.find("data-width=\"160\"") != std::string::npos &&
               std::atoi(element_text(first, "updates-0").c_str()) >= 2 &&
               element_text(first, "alarm-0").find("ALARM") != std::string::npos;
      },
      milliseconds(30000));
  // The statistics move on (a slow machine given half a minute): more updates, another time.
  const auto updates = [](const std::string& dom) {
    return std::atoi(element_text(dom, "updates-0").c_str());
  };
  wait_until(
      [&] {
        second = chromium.evaluate(dom_js);
        return updates(second) > updates(first);
      },
      milliseconds(30000));
  for (const std::string* dom : {&first, &second}) {
    EXPECT_NE(dom->find("data-width=\"160\""), std::string::npos) << "no image shown:\n" << *dom;
    EXPECT_NE(element_text(*dom, "camera-0").find("camera running"), std::string::npos) << *dom;
    const std::string median = element_text(*dom, "median-0");
    ASSERT_FALSE(median.empty()) << *dom;
    const double c = std::atof(median.c_str());
    EXPECT_GT(c, 500.0) << median;
    EXPECT_LT(c, 3500.0) << median;
    // Chart.js sized the plot's canvas.
    EXPECT_TRUE(std::regex_search(*dom, std::regex("id=\"chart-0\"[^>]*box-sizing")))
        << "Chart.js did not load";
  }
  EXPECT_GT(updates(second), updates(first));
  EXPECT_NE(element_text(first, "time-0"), element_text(second, "time-0"));
  // The alarm: on the page, and logged.
  EXPECT_NE(element_text(second, "alarm-0").find("ALARM median"), std::string::npos) << second;
  EXPECT_NE(server.log().find("ALARM raised: median"), std::string::npos) << server.log();
  // A screenshot kept as the test's artefact.
  const char* artefacts = std::getenv("PYROCAM_SERVE_ARTEFACTS");
  const fs::path shot = fs::path(artefacts != nullptr ? artefacts : dir.path()) / "serve-page.png";
  const auto png = chromium.call("Page.captureScreenshot", {{"format", "png"}});
  ASSERT_TRUE(png.is_object() && png.contains("data")) << chromium.log();
  gsize size = 0;
  guchar* bytes = g_base64_decode(png["data"].get<std::string>().c_str(), &size);
  std::ofstream(shot, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(size));
  g_free(bytes);
  EXPECT_GT(fs::file_size(shot), 10000u) << shot;
  EXPECT_TRUE(server.process->running()) << server.log();
}

}  // namespace
}  // namespace pyrocam::test
