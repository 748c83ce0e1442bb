// pyrocam-serve's monitoring page over HTTP (libsoup 3):
//   /             the page (several servers with ?servers=host:port,host:port)
//   /events       Server-Sent Events: `stats` (ratiotemp's statistics), `alarm` (thermalalarm's
//                 changes), `camera` (running or lost, why), `frame` (a new JPEG's number)
//   /frame.jpg    the latest overlay frame
//   /stream.mjpg  the overlay as it comes (MJPEG, multipart/x-mixed-replace), what the page shows
//   /status.json  the latest of each event, the alarm log and the RTSP URLs
//   /chart.js     Chart.js from the Debian package libjs-chart.js
// The event stream and the JSON carry CORS headers so that a page on one server shows others.
#pragma once

#include <gst/gst.h>
#include <libsoup/soup.h>

#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace pyrocam::serve {

struct WebConfig {
  std::string address = "0.0.0.0";
  int port = 8080;
  std::string chart_js;              // path of Chart.js
  std::vector<std::string> servers;  // host:port of other servers the page lists by default
  int rtsp_port = 8554;
  int output_pixel = 1;  // sensor pixels a temperature spans, a side (5 for a 5x5 camera)
};

// A GstStructure's fields as JSON (unknown times and NaN as null), with its name as "type".
nlohmann::json structure_to_json(const GstStructure* s);

class WebServer {
 public:
  using JpegSource =
      std::function<std::shared_ptr<const std::vector<std::uint8_t>>(std::uint64_t&)>;
  WebServer(WebConfig config, JpegSource jpeg);
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  bool start(std::string& error);
  int bound_port() const { return bound_port_; }

  // Main context: to every open event stream, and kept for /status.json and new streams.
  void publish(const std::string& event, const nlohmann::json& data);
  void log_alarm(const nlohmann::json& alarm);
  // The last data published for `event` (null if none).
  nlohmann::json latest(const std::string& event) const {
    const auto it = latest_.find(event);
    return it == latest_.end() ? nlohmann::json() : *it;
  }

 private:
  static void on_request(SoupServer* server, SoupServerMessage* msg, const char* path,
                         GHashTable* query, gpointer self);
  static void on_events_finished(SoupServerMessage* msg, gpointer self);
  static gboolean on_tick(gpointer self);
  struct Stream {
    SoupServerMessage* msg;
    bool mjpeg;
    std::size_t pending = 0;  // bytes handed to libsoup and not yet written
    bool ended = false;       // an event stream completed for a reader that stopped reading
  };
  void open_stream(SoupServerMessage* msg, bool mjpeg);
  static void on_wrote_body_data(SoupServerMessage* msg, guint size, gpointer self);
  void append(Stream& stream, const std::string& bytes);
  void send(Stream& stream, const std::string& event, const std::string& data);
  void send_frame(Stream& stream);
  nlohmann::json status() const;

  WebConfig config_;
  JpegSource jpeg_;
  SoupServer* server_ = nullptr;
  int bound_port_ = 0;
  guint tick_ = 0;
  std::uint64_t last_frame_seq_ = 0;
  int ticks_since_ping_ = 0;
  std::vector<Stream> streams_;
  nlohmann::json latest_ = nlohmann::json::object();  // event name -> last data
  std::deque<nlohmann::json> alarm_log_;
};

}  // namespace pyrocam::serve
