// pyrocam-serve with a 5x5 camera (its temperatures, one per macro-pixel, drawn over the frame)
// and the page's ?servers= list, whose names are shown as text, never as markup.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "http_client.h"
#include "serve_support.h"

namespace pyrocam::test {
namespace {

TEST(Serve, Cameras5x5IsServed) {
  ScratchDir dir("serve-5x5");
  Server server = start_server(
      dir, {"--camera", "pyrocamsrc is-live=true profile=nir5x5-reference scene=plate seed=11"},
      true, "video/x-raw,width=160,height=120,framerate=10/1",
      test_model("test-model-nir5x5.json"));
  ASSERT_NE(server.http, 0) << server.log();
  ASSERT_TRUE(wait_until(
      [&] { return http_get(server.http, "/status.json").find("\"stats\"") != std::string::npos; },
      milliseconds(30000)))
      << server.log();
  const std::string status = http_get(server.http, "/status.json");
  const auto json = nlohmann::json::parse(status.substr(status.find("\r\n\r\n") + 4));
  EXPECT_EQ(json["camera"]["state"], "running") << status;
  EXPECT_GT(json["stats"]["median-c"].get<double>(), 500.0) << status;
  EXPECT_EQ(http_get(server.http, "/frame.jpg").rfind("HTTP/1.1 200", 0), 0u) << server.log();
  EXPECT_EQ(server.log().find("does not fit"), std::string::npos) << server.log();
  // A reading spans 5x5 sensor pixels; the page gives the peak's place in sensor pixels, at
  // the centre of its macro-pixel (it gave the macro-pixel's indices, a fifth of the place).
  EXPECT_EQ(json["output-pixel"], 5) << status;
  // The peak with what the model says a reading there may be off by (its systematic terms).
  EXPECT_GT(json["stats"].value("peak-u-sys-c", 0.0), 0.0) << status;
  if (std::filesystem::exists("/usr/bin/chromium")) {
    Chromium chromium(dir.path());
    ASSERT_TRUE(chromium.ok()) << chromium.log();
    ASSERT_TRUE(chromium.open("http://127.0.0.1:" + std::to_string(server.http) + "/"))
        << chromium.log();
    const std::regex place("id=\"peak-at-0\"[^>]*>([0-9]+), ([0-9]+)<");
    std::string dom;
    std::smatch m;
    ASSERT_TRUE(wait_until(
        [&] {
          dom = chromium.evaluate("document.documentElement.outerHTML");
          return std::regex_search(dom, m, place);
        },
        milliseconds(30000)))
        << dom;
    const int x = std::stoi(m[1].str()), y = std::stoi(m[2].str());
    EXPECT_TRUE(x % 5 == 2 && x < 160 && y % 5 == 2 && y < 120) << x << ", " << y;
    EXPECT_NE(dom.find("sensor px"), std::string::npos) << dom;
    const std::regex peak("id=\"peak-0\"[^>]*>[0-9.]+ °C ± [0-9]+ sys\\.<");
    EXPECT_TRUE(std::regex_search(dom, peak)) << dom;
  }
  EXPECT_TRUE(server.process->running()) << server.log();
}

TEST(Serve, Cameras5x5NeedsItsFrameSize) {
  ScratchDir dir("serve-5x5-caps");
  const std::string log_path = (dir / "serve.log").string();
  Process p(
      {serve_binary(), "--address", "127.0.0.1", "--rtsp-port", "0", "--http-port", "0", "--model",
       test_model("test-model-nir5x5.json"), "--caps", "video/x-raw,framerate=10/1"},
      Env{}, log_path);
  const auto status = p.wait_for(milliseconds(20000));
  ASSERT_TRUE(status.has_value()) << p.log();
  EXPECT_EQ(*status, 2);
  EXPECT_NE(p.log().find("multiples of 5"), std::string::npos) << p.log();
}

// A warning from the chain (here darksub's: a dark 20 DN below the camera's black) reaches the
// log and the page: under gst-launch it is printed, and the server dropped it while the page
// showed a plate 60 degC too cold. An alarm that is set shows as clear from the start.
TEST(Serve, CamerasChainWarningsReachThePageAndAnArmedAlarmShowsClear) {
  ScratchDir dir("serve-warning");
  Server server = start_server(
      dir, {"--camera", kCamera, "--dark", "dark-level=30", "--alarm-threshold-c", "3000"});
  ASSERT_NE(server.http, 0) << server.log();
  nlohmann::json json;
  ASSERT_TRUE(wait_until(
      [&] {
        const std::string status = http_get(server.http, "/status.json");
        json = nlohmann::json::parse(status.substr(status.find("\r\n\r\n") + 4));
        return json.contains("warning");
      },
      milliseconds(30000)))
      << server.log();
  EXPECT_EQ(json["warning"]["source"], "darksub0") << json;
  EXPECT_NE(json["warning"]["message"].get<std::string>().find("20 DN too low"), std::string::npos)
      << json;
  EXPECT_NE(server.log().find("warning: darksub0: after the dark"), std::string::npos)
      << server.log();
  EXPECT_EQ(json["alarm"]["state"], "clear") << json;
  EXPECT_EQ(json["alarm"]["threshold-c"], 3000.0) << json;
}

// Options that cannot work: a usage error (exit 2) naming them, before anything starts. A NaN
// threshold passed CLI11's range check and left thermalalarm off, silently; unknown options
// exited 109.
TEST(Serve, BadInputAlarmAndUsageErrorsExitTwo) {
  ScratchDir dir("serve-usage");
  int k = 0;
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"--alarm-threshold-c", "nan"},
        {"--alarm-threshold-c", "-300"},
        {"--alarm-hysteresis-c", "nan"},
        {"--key-seconds", "nan"},          // every frame a key frame
        {"--server", "--print-pipeline"},  // the next option taken as a server
        {"--no-such-option"}}) {
    std::vector<std::string> argv = {serve_binary(), "--rtsp-port", "0", "--http-port", "0",
                                     "--model",      rgb_model()};
    argv.insert(argv.end(), args.begin(), args.end());
    Process p(argv, Env{}, (dir / ("usage" + std::to_string(k++) + ".log")).string());
    const auto status = p.wait_for(milliseconds(20000));
    ASSERT_TRUE(status.has_value()) << args[0] << ": still running";
    EXPECT_EQ(*status, 2) << args[0] << ": " << p.log();
    EXPECT_NE(p.log().find(args[0]), std::string::npos) << p.log();
  }
}

// Caps the camera refuses (not a whole number of mosaic periods) fail for good: the server
// retried them forever.
TEST(Serve, BadInputCapsTheCameraRefusesEndTheServer) {
  ScratchDir dir("serve-bad-caps");
  Process p({serve_binary(), "--address", "127.0.0.1", "--rtsp-port", "0", "--http-port", "0",
             "--model", rgb_model(), "--caps", "video/x-bayer,width=63,height=64,framerate=10/1"},
            Env{}, (dir / "serve.log").string());
  const auto status = p.wait_for(milliseconds(30000));
  ASSERT_TRUE(status.has_value()) << "still retrying: " << p.log();
  EXPECT_EQ(*status, 1);
  EXPECT_NE(p.log().find("63x64 is not a whole number of RGGB mosaic periods"), std::string::npos)
      << p.log();
}

TEST(Serve, PageNamesServersAsText) {
  if (!std::filesystem::exists("/usr/bin/chromium"))
    GTEST_SKIP() << "no /usr/bin/chromium (scripts/install-deps.sh --tests installs it)";
  ScratchDir dir("serve-page-names");
  Server server = start_server(dir, {"--camera", kCamera}, false);
  ASSERT_NE(server.http, 0) << server.log();
  const std::string self = "127.0.0.1:" + std::to_string(server.http);
  // A crafted link: markup in a server's name (URL-encoded), then a real server.
  const std::string url = "http://" + self +
                          "/?servers=%3Cimg%20src%3Dx%20onerror%3D%22document.body.dataset."
                          "pwned%3D1%22%3E," +
                          self;
  Chromium chromium(dir.path());
  ASSERT_TRUE(chromium.ok()) << chromium.log();
  ASSERT_TRUE(chromium.open(url)) << chromium.log();
  std::string dom;
  wait_until(
      [&] {
        dom = chromium.evaluate("document.documentElement.outerHTML");
        return dom.find("id=\"name-0\"") != std::string::npos;
      },
      milliseconds(20000));
  EXPECT_EQ(dom.find("data-pwned"), std::string::npos) << dom;
  EXPECT_EQ(dom.find("<img src=\"x\""), std::string::npos) << dom;
  EXPECT_NE(dom.find("id=\"name-0\">" + self + "<"), std::string::npos) << dom;
  EXPECT_EQ(dom.find("id=\"name-1\""), std::string::npos) << "the crafted name got a panel";
}

}  // namespace
}  // namespace pyrocam::test
