// What the pyrocam-serve test files share: the server started as users run it (a child process,
// on loopback, with the ports the system picks), its log and ports.
#pragma once

#include <cstdlib>
#include <fstream>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include "http_client.h"
#include "pipeline_support.h"
#include "test_support.h"

namespace pyrocam::test {

// 10 fps: the thermal chain of a plate filling the frame costs about 40 ms of a core per frame
// here, and the tests run side by side on two cores.
inline const std::string kCaps = "video/x-bayer,width=160,height=120,framerate=10/1";
inline const std::string kCamera = "pyrocamsrc is-live=true scene=plate seed=11";

inline std::string serve_binary() {
  const char* p = std::getenv("PYROCAM_SERVE");
  return p != nullptr ? p : "pyrocam-serve";
}
inline std::string rgb_model() { return test_model("test-model-rgb.json"); }

inline std::string read_file(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A running pyrocam-serve and the ports it printed.
struct Server {
  std::unique_ptr<Process> process;
  std::string log_path;
  int rtsp = 0, http = 0;
  std::string log() const { return read_file(log_path); }
  std::string url(const std::string& mount) const {
    return "rtsp://127.0.0.1:" + std::to_string(rtsp) + mount;
  }
};

// Starts the server; with `running` waits until the camera delivers (else until it printed its
// ports or exited). `caps` and `model`: the colour camera's unless given.
inline Server start_server(const ScratchDir& dir, std::vector<std::string> args,
                           bool running = true, const std::string& caps = kCaps,
                           const std::string& model = rgb_model()) {
  Server s;
  s.log_path = (dir / "serve.log").string();
  std::vector<std::string> argv = {serve_binary(), "--address", "127.0.0.1", "--rtsp-port", "0",
                                   "--http-port", "0", "--caps", caps, "--model", model,
                                   "--stats-interval-ms", "200",
                                   // a loaded test machine can take seconds to the first frame
                                   "--watchdog-ms", "20000"};
  argv.insert(argv.end(), args.begin(), args.end());
  s.process = std::make_unique<Process>(argv, Env{}, s.log_path);
  const std::regex ports("RTSP on port (\\d+).*the page on port (\\d+)");
  wait_until(
      [&] {
        const std::string log = s.log();
        std::smatch m;
        if (s.rtsp == 0 && std::regex_search(log, m, ports)) {
          s.rtsp = std::stoi(m[1]);
          s.http = std::stoi(m[2]);
        }
        if (!s.process->running()) return true;
        return s.rtsp != 0 && (!running || log.find("camera running") != std::string::npos);
      },
      milliseconds(60000));
  return s;
}

inline std::string http_get(int port, const std::string& path) {
  return http_exchange(port,
                       "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
}

}  // namespace pyrocam::test
