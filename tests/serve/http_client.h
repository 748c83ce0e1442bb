// Loopback clients for the serve tests: one HTTP exchange on a raw socket (for requests no
// library would send), and headless Chromium driven over its DevTools protocol.
#pragma once

#include <arpa/inet.h>
#include <glib.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline_support.h"

namespace pyrocam::test {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// One HTTP exchange on a fresh connection: what the server answered until it closed, or in 3 s.
inline std::string http_exchange(int port, const std::string& request) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    close(fd);
    return "";
  }
  timeval tv{0, 200000};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  const auto deadline = Clock::now() + milliseconds(3000);  // an event stream never ends
  if (send(fd, request.data(), request.size(), MSG_NOSIGNAL) < 0) {
    close(fd);
    return "";
  }
  std::string reply;
  char buf[4096];
  while (Clock::now() < deadline) {
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK)) break;
    if (n < 0) continue;
    reply.append(buf, static_cast<std::size_t>(n));
    if (reply.size() > (1 << 20)) break;
  }
  close(fd);
  return reply;
}
// Headless Chromium driven over its DevTools protocol (a WebSocket on loopback): the page is
// read while it runs (its event stream never ends, so a one-shot --dump-dom would read it at
// its load event, before any update).
class Chromium {
 public:
  explicit Chromium(const fs::path& dir) : profile_(dir / "chromium-profile") {
    fs::create_directories(profile_);
    process_ = std::make_unique<Process>(
        std::vector<std::string>{
            "/usr/bin/chromium", "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
            "--no-first-run", "--disable-background-networking", "--disable-component-update",
            "--disable-sync", "--user-data-dir=" + profile_.string(), "--window-size=1300,1000",
            "--remote-debugging-port=0", "about:blank"},
        Env{}, (dir / "chromium.log").string());
    wait_until(
        [&] {
          std::ifstream in(profile_ / "DevToolsActivePort");
          return static_cast<bool>(in >> port_) && port_ > 0;
        },
        milliseconds(30000));
  }
  ~Chromium() {
    if (fd_ >= 0) close(fd_);
  }
  bool ok() const { return port_ > 0; }
  std::string log() const { return process_->log(); }

  // Opens `url` in a new tab and connects to it; false if that failed.
  bool open(const std::string& url) {
    const std::string reply =
        http_exchange(port_, "PUT /json/new?" + url +
                                 " HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n");
    const auto body = reply.find("\r\n\r\n");
    if (body == std::string::npos) return false;
    const auto json = nlohmann::json::parse(reply.substr(body + 4), nullptr, false);
    if (!json.is_object() || !json.contains("webSocketDebuggerUrl")) return false;
    const std::string ws = json["webSocketDebuggerUrl"];
    const std::string path = ws.substr(ws.find('/', std::string("ws://").size()));
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(port_));
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) return false;
    timeval tv{20, 0};
    setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    const std::string upgrade =
        "GET " + path +
        " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
        "Connection: Upgrade\r\nSec-WebSocket-Key: cHlyb2NhbXNlcnZldGVzdA==\r\n"
        "Sec-WebSocket-Version: 13\r\n\r\n";
    if (send(fd_, upgrade.data(), upgrade.size(), MSG_NOSIGNAL) < 0) return false;
    std::string head;
    char c;
    while (head.find("\r\n\r\n") == std::string::npos && recv(fd_, &c, 1, 0) == 1) head += c;
    return head.rfind("HTTP/1.1 101", 0) == 0;
  }

  // A DevTools command's result (null on failure).
  nlohmann::json call(const std::string& method, const nlohmann::json& params) {
    const int id = ++last_id_;
    if (!send_frame(nlohmann::json{{"id", id}, {"method", method}, {"params", params}}.dump()))
      return nullptr;
    for (;;) {
      std::string text;
      if (!recv_message(text)) return nullptr;
      auto reply = nlohmann::json::parse(text, nullptr, false);
      if (reply.is_object() && reply.value("id", -1) == id)
        return reply.contains("result") ? reply["result"] : nlohmann::json();
    }
  }
  std::string evaluate(const std::string& expression) {
    auto r = call("Runtime.evaluate", {{"expression", expression}, {"returnByValue", true}});
    return r.is_object() && r["result"].contains("value") && r["result"]["value"].is_string()
               ? r["result"]["value"].get<std::string>()
               : "";
  }

 private:
  bool send_frame(const std::string& text) {
    std::string frame(1, '\x81');  // FIN, text
    const std::size_t n = text.size();
    if (n < 126) {
      frame += static_cast<char>(0x80 | n);
    } else if (n < 65536) {
      frame += static_cast<char>(0x80 | 126);
      frame += static_cast<char>(n >> 8);
      frame += static_cast<char>(n & 0xff);
    } else {
      frame += static_cast<char>(0x80 | 127);
      for (int i = 7; i >= 0; --i) frame += static_cast<char>((n >> (8 * i)) & 0xff);
    }
    frame += std::string(4, '\0');  // a zero mask leaves the payload as it is
    frame += text;
    return send(fd_, frame.data(), frame.size(), MSG_NOSIGNAL) ==
           static_cast<ssize_t>(frame.size());
  }
  bool recv_all(void* data, std::size_t n) {
    auto* p = static_cast<char*>(data);
    while (n > 0) {
      const ssize_t got = recv(fd_, p, n, 0);
      if (got <= 0) return false;
      p += got;
      n -= static_cast<std::size_t>(got);
    }
    return true;
  }
  bool recv_message(std::string& text) {
    text.clear();
    for (;;) {
      unsigned char h[2];
      if (!recv_all(h, 2)) return false;
      std::uint64_t n = h[1] & 0x7f;
      if (n == 126 || n == 127) {
        unsigned char ext[8];
        const int bytes = n == 126 ? 2 : 8;
        if (!recv_all(ext, static_cast<std::size_t>(bytes))) return false;
        n = 0;
        for (int i = 0; i < bytes; ++i) n = n << 8 | ext[i];
      }
      std::string payload(n, '\0');
      if (n > 0 && !recv_all(payload.data(), n)) return false;
      text += payload;
      if (h[0] & 0x80) return true;  // FIN
    }
  }

  fs::path profile_;
  std::unique_ptr<Process> process_;
  int port_ = 0;
  int fd_ = -1;
  int last_id_ = 0;
};

}  // namespace pyrocam::test
