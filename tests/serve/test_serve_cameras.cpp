// pyrocam-serve with a 5x5 camera (its temperatures, one per macro-pixel, drawn over the frame)
// and the page's ?servers= list, whose names are shown as text, never as markup.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

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
