/* pyrocam-serve's HTTP side: the page, the event stream, the latest frame. */
#include "web.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <utility>

#include "page.h"

GST_DEBUG_CATEGORY_EXTERN(pyrocam_serve_debug);
#define GST_CAT_DEFAULT pyrocam_serve_debug

namespace pyrocam::serve {
namespace {

constexpr guint kTickMs = 50;
constexpr int kTicksPerPing = 200;  // a comment every 10 s finds streams whose reader has gone
constexpr std::size_t kAlarmLogSize = 100;
// A reader this far behind misses frames (a stalled screen must not grow the server's memory).
constexpr std::size_t kMaxPendingBytes = 2 << 20;
// An event stream's: about 3.5 minutes of events at the default rates.
constexpr std::size_t kMaxPendingEventBytes = 256 << 10;
constexpr const char* kBoundary = "pyrocamframe";

gboolean add_field(GQuark field, const GValue* value, gpointer data) {
  auto& out = *static_cast<nlohmann::json*>(data);
  const char* name = g_quark_to_string(field);
  const GType type = G_VALUE_TYPE(value);
  if (type == G_TYPE_DOUBLE) {
    const double v = g_value_get_double(value);
    out[name] = std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
  } else if (type == G_TYPE_FLOAT) {
    const double v = g_value_get_float(value);
    out[name] = std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
  } else if (type == G_TYPE_INT) {
    out[name] = g_value_get_int(value);
  } else if (type == G_TYPE_UINT) {
    out[name] = g_value_get_uint(value);
  } else if (type == G_TYPE_INT64) {
    out[name] = g_value_get_int64(value);
  } else if (type == G_TYPE_UINT64) {
    const guint64 v = g_value_get_uint64(value);
    out[name] = v == GST_CLOCK_TIME_NONE ? nlohmann::json() : nlohmann::json(v);
  } else if (type == G_TYPE_BOOLEAN) {
    out[name] = g_value_get_boolean(value) != FALSE;
  } else if (type == G_TYPE_STRING) {
    const char* s = g_value_get_string(value);
    out[name] = s != nullptr ? s : "";
  } else {
    gchar* s = gst_value_serialize(value);
    if (s != nullptr) out[name] = s;
    g_free(s);
  }
  return TRUE;
}

void set_common_headers(SoupServerMessage* msg) {
  SoupMessageHeaders* h = soup_server_message_get_response_headers(msg);
  soup_message_headers_replace(h, "Access-Control-Allow-Origin", "*");
  soup_message_headers_replace(h, "Cache-Control", "no-store");
}

void respond(SoupServerMessage* msg, guint status, const char* type, const std::string& body) {
  set_common_headers(msg);
  soup_server_message_set_status(msg, status, nullptr);
  soup_server_message_set_response(msg, type, SOUP_MEMORY_COPY, body.data(), body.size());
}

// JSON text that never throws: a message that is not valid UTF-8 (an error text quoting a path)
// gets U+FFFD in place of its bad bytes, where dump() would throw inside a GLib callback.
std::string json_text(const nlohmann::json& j) {
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

nlohmann::json structure_to_json(const GstStructure* s) {
  nlohmann::json out = nlohmann::json::object();
  out["type"] = gst_structure_get_name(s);
  gst_structure_foreach(s, add_field, &out);
  return out;
}

WebServer::WebServer(WebConfig config, JpegSource jpeg)
    : config_(std::move(config)), jpeg_(std::move(jpeg)) {}

WebServer::~WebServer() {
  if (tick_ != 0) g_source_remove(tick_);
  for (Stream& stream : streams_) g_signal_handlers_disconnect_by_data(stream.msg, this);
  if (server_ != nullptr) {
    soup_server_disconnect(server_);
    g_object_unref(server_);
  }
}

bool WebServer::start(std::string& error) {
  server_ = soup_server_new("server-header", "pyrocam-serve ", nullptr);
  soup_server_add_handler(server_, nullptr, on_request, this, nullptr);
  GError* err = nullptr;
  GInetAddress* address = g_inet_address_new_from_string(config_.address.c_str());
  if (address == nullptr) {
    error = "'" + config_.address + "' is not an IP address";
    return false;
  }
  GSocketAddress* socket_address =
      g_inet_socket_address_new(address, static_cast<guint16>(config_.port));
  g_object_unref(address);
  const gboolean ok = soup_server_listen(server_, socket_address, SoupServerListenOptions(0), &err);
  g_object_unref(socket_address);
  if (!ok) {
    error = err != nullptr ? err->message : "unknown error";
    if (err != nullptr) g_error_free(err);
    return false;
  }
  GSList* uris = soup_server_get_uris(server_);
  if (uris != nullptr) bound_port_ = g_uri_get_port(static_cast<GUri*>(uris->data));
  g_slist_free_full(uris, reinterpret_cast<GDestroyNotify>(g_uri_unref));
  tick_ = g_timeout_add(kTickMs, on_tick, this);
  return true;
}

nlohmann::json WebServer::status() const {
  nlohmann::json s = latest_;
  s["alarm-log"] = nlohmann::json::array();
  for (const auto& a : alarm_log_) s["alarm-log"].push_back(a);
  s["rtsp-port"] = config_.rtsp_port;
  s["servers"] = config_.servers;
  s["output-pixel"] = config_.output_pixel;
  return s;
}

void WebServer::on_request(SoupServer*, SoupServerMessage* msg, const char* path, GHashTable*,
                           gpointer data) {
  auto* self = static_cast<WebServer*>(data);
  const std::string method = soup_server_message_get_method(msg);
  const std::string p = path != nullptr ? path : "";
  if (method != "GET" && method != "HEAD") {
    soup_message_headers_replace(soup_server_message_get_response_headers(msg), "Allow",
                                 "GET, HEAD");
    respond(msg, SOUP_STATUS_METHOD_NOT_ALLOWED, "text/plain",
            "pyrocam-serve: only GET and HEAD are served, not " + method + "\n");
    return;
  }
  if (p == "/" || p == "/index.html") {
    respond(msg, SOUP_STATUS_OK, "text/html; charset=utf-8", kPage);
  } else if (p == "/events") {
    self->open_stream(msg, false);
  } else if (p == "/stream.mjpg") {
    self->open_stream(msg, true);
  } else if (p == "/status.json") {
    respond(msg, SOUP_STATUS_OK, "application/json", json_text(self->status()));
  } else if (p == "/frame.jpg") {
    std::uint64_t seq = 0;
    auto jpeg = self->jpeg_(seq);
    if (jpeg == nullptr || jpeg->empty()) {
      respond(msg, SOUP_STATUS_SERVICE_UNAVAILABLE, "text/plain",
              "pyrocam-serve: no current frame: the camera is not running (its state is in "
              "/status.json)\n");
      return;
    }
    set_common_headers(msg);
    soup_server_message_set_status(msg, SOUP_STATUS_OK, nullptr);
    soup_server_message_set_response(msg, "image/jpeg", SOUP_MEMORY_COPY,
                                     reinterpret_cast<const char*>(jpeg->data()), jpeg->size());
  } else if (p == "/chart.js") {
    std::ifstream in(self->config_.chart_js, std::ios::binary);
    if (!in) {
      respond(msg, SOUP_STATUS_NOT_FOUND, "text/plain",
              "pyrocam-serve: Chart.js not found at " + self->config_.chart_js +
                  " (install the Debian package libjs-chart.js, or give --chart-js)\n");
      return;
    }
    std::ostringstream body;
    body << in.rdbuf();
    respond(msg, SOUP_STATUS_OK, "text/javascript", body.str());
  } else {
    respond(msg, SOUP_STATUS_NOT_FOUND, "text/plain", "pyrocam-serve: no page " + p + "\n");
  }
}

void WebServer::open_stream(SoupServerMessage* msg, bool mjpeg) {
  set_common_headers(msg);
  SoupMessageHeaders* h = soup_server_message_get_response_headers(msg);
  if (mjpeg)
    soup_message_headers_replace(
        h, "Content-Type",
        (std::string("multipart/x-mixed-replace; boundary=") + kBoundary).c_str());
  else
    soup_message_headers_set_content_type(h, "text/event-stream", nullptr);
  soup_message_headers_set_encoding(h, SOUP_ENCODING_CHUNKED);
  soup_server_message_set_status(msg, SOUP_STATUS_OK, nullptr);
  soup_message_body_set_accumulate(soup_server_message_get_response_body(msg), FALSE);
  g_signal_connect(msg, "finished", G_CALLBACK(on_events_finished), this);
  g_signal_connect(msg, "wrote-body-data", G_CALLBACK(on_wrote_body_data), this);
  streams_.push_back(Stream{msg, mjpeg});
  // A new reader gets the latest at once, not at the next change.
  if (mjpeg)
    send_frame(streams_.back());
  else
    send(streams_.back(), "hello", json_text(status()));
  GST_INFO("%s stream opened (%zu open)", mjpeg ? "MJPEG" : "event", streams_.size());
}

void WebServer::on_events_finished(SoupServerMessage* msg, gpointer data) {
  auto* self = static_cast<WebServer*>(data);
  g_signal_handlers_disconnect_by_data(msg, self);
  self->streams_.erase(std::remove_if(self->streams_.begin(), self->streams_.end(),
                                      [msg](const Stream& s) { return s.msg == msg; }),
                       self->streams_.end());
  GST_INFO("stream closed (%zu open)", self->streams_.size());
}

void WebServer::on_wrote_body_data(SoupServerMessage* msg, guint size, gpointer data) {
  auto* self = static_cast<WebServer*>(data);
  for (Stream& s : self->streams_)
    if (s.msg == msg) s.pending -= std::min<std::size_t>(s.pending, size);
}

void WebServer::append(Stream& stream, const std::string& bytes) {
  stream.pending += bytes.size();
  soup_message_body_append(soup_server_message_get_response_body(stream.msg), SOUP_MEMORY_COPY,
                           bytes.data(), bytes.size());
  soup_server_message_unpause(stream.msg);
}

void WebServer::send(Stream& stream, const std::string& event, const std::string& data) {
  if (stream.ended) return;
  // A reader that stopped reading grew the server's memory by every event (4 MB an hour each at
  // the default rates): past the limit its stream ends, and a reader that wakes up reconnects
  // and gets the latest state in its hello. (Dropping events instead would leave its page
  // showing a state that is no longer so.)
  if (stream.pending > kMaxPendingEventBytes) {
    GST_WARNING("an event stream's reader took no data for %zu bytes: ending its stream",
                stream.pending);
    stream.ended = true;
    soup_message_body_complete(soup_server_message_get_response_body(stream.msg));
    soup_server_message_unpause(stream.msg);
    return;
  }
  append(stream, event.empty() ? ": ping\n\n" : "event: " + event + "\ndata: " + data + "\n\n");
}

void WebServer::send_frame(Stream& stream) {
  std::uint64_t seq = 0;
  auto jpeg = jpeg_(seq);
  if (jpeg == nullptr || jpeg->empty() || stream.pending > kMaxPendingBytes) return;
  append(stream,
         std::string("--") + kBoundary +
             "\r\nContent-Type: image/jpeg\r\nContent-Length: " + std::to_string(jpeg->size()) +
             "\r\n\r\n" + std::string(jpeg->begin(), jpeg->end()) + "\r\n");
}

void WebServer::publish(const std::string& event, const nlohmann::json& data) {
  latest_[event] = data;
  const std::string text = json_text(data);
  // By index: a write error can end a stream (and erase it) while we go.
  for (std::size_t i = 0; i < streams_.size(); ++i)
    if (!streams_[i].mjpeg) send(streams_[i], event, text);
}

void WebServer::log_alarm(const nlohmann::json& alarm) {
  alarm_log_.push_back(alarm);
  while (alarm_log_.size() > kAlarmLogSize) alarm_log_.pop_front();
}

gboolean WebServer::on_tick(gpointer data) {
  auto* self = static_cast<WebServer*>(data);
  std::uint64_t seq = 0;
  self->jpeg_(seq);
  if (seq != self->last_frame_seq_) {
    self->last_frame_seq_ = seq;
    self->publish("frame", nlohmann::json{{"seq", seq}});
    for (std::size_t i = 0; i < self->streams_.size(); ++i)
      if (self->streams_[i].mjpeg) self->send_frame(self->streams_[i]);
  }
  if (++self->ticks_since_ping_ >= kTicksPerPing) {
    self->ticks_since_ping_ = 0;
    for (std::size_t i = 0; i < self->streams_.size(); ++i)
      if (!self->streams_[i].mjpeg) self->send(self->streams_[i], "", "");
  }
  return G_SOURCE_CONTINUE;
}

}  // namespace pyrocam::serve
