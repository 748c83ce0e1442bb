/* pyrocam-serve: one camera's thermal chain as RTSP streams and a live monitoring page.
 *
 *   pyrocam-serve                                  # simulated camera, out/model-rgb.json
 *   pyrocam-serve --camera "aravissrc camera-name=Cam1" --model cam.json \
 *     --caps video/x-bayer,format=rggb,width=1024,height=768 --alarm-threshold-c 1600
 *
 * rtsp://HOST:8554/thermal (H.264 overlay), rtsp://HOST:8554/temperature (lossless 16-bit in
 * H.264 4:4:4), http://HOST:8080/ (the page). docs/serve.md describes them. */
#include <glib-unix.h>
#include <gst/gst.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <limits>
#include <optional>
#include <regex>
#include <string>

#include "camera.h"
#include "page.h"
#include "rtsp.h"
#include "web.h"

GST_DEBUG_CATEGORY(pyrocam_serve_debug);

namespace {

using namespace pyrocam::serve;

constexpr const char* kName = "pyrocam-serve";
constexpr const char* kChartJs = "/usr/share/javascript/chart.js/chart.min.js";

struct Options {
  CameraConfig camera;
  RtspConfig rtsp;
  WebConfig web;
  std::optional<double> alarm_threshold_c;
  int alarm_frames = 5;
  double alarm_hysteresis_c = 10;
  std::string alarm_statistic = "median";
  double key_seconds = 1;
  bool print_pipeline = false;
};

gboolean on_signal(gpointer loop) {
  g_main_loop_quit(static_cast<GMainLoop*>(loop));
  return G_SOURCE_CONTINUE;
}

// The caps' frame rate and size, where they give them (fixed values); -1 for caps that do not
// parse.
int caps_fields(const std::string& caps_text, double& fps, int& width, int& height) {
  GstCaps* caps = gst_caps_from_string(caps_text.c_str());
  if (caps == nullptr) return -1;
  int n = 0, d = 1;
  if (gst_caps_get_size(caps) > 0) {
    const GstStructure* s = gst_caps_get_structure(caps, 0);
    if (gst_structure_get_fraction(s, "framerate", &n, &d) && d > 0)
      fps = static_cast<double>(n) / d;
    if (!gst_structure_get_int(s, "width", &width)) width = 0;
    if (!gst_structure_get_int(s, "height", &height)) height = 0;
  }
  gst_caps_unref(caps);
  return 0;
}

std::string host_name() {
  char name[256] = {};
  return gethostname(name, sizeof name - 1) == 0 ? name : "localhost";
}

}  // namespace

int main(int argc, char** argv) {
  gst_init(&argc, &argv);
  GST_DEBUG_CATEGORY_INIT(pyrocam_serve_debug, "pyrocam-serve", 0, "pyrocam-serve");

  Options o;
  o.camera.model = "out/model-rgb.json";
  o.web.chart_js = kChartJs;
  CLI::App app{
      "pyrocam-serve: one camera's temperatures as RTSP streams (rtsp://HOST:PORT/thermal, "
      "the colour-mapped overlay in H.264; rtsp://HOST:PORT/temperature, the 0.1 K codes "
      "in lossless H.264 4:4:4, high byte in Y, low byte in U) and a live monitoring page "
      "(http://HOST:PORT/). Ctrl-C stops it.",
      kName};
  app.add_option("--camera", o.camera.camera,
                 "Camera element with its properties (gst-launch syntax)")
      ->capture_default_str();
  app.add_option("--caps", o.camera.caps, "Caps after the camera: format, size, frame rate")
      ->capture_default_str();
  app.add_option("--dark", o.camera.dark, "darksub settings: dark-level=N or location=dark.pgm")
      ->capture_default_str();
  app.add_option("--model", o.camera.model,
                 "Calibrated model (pyrocam-calib calibrate; scripts/main-job.sh writes "
                 "out/model-rgb.json)")
      ->capture_default_str();
  app.add_flag("--exposure-control", o.camera.exposure_control,
               "Put autoexposure after the camera: it sets the camera's exposure (pyrocamsrc, "
               "aravissrc) so that the frame's brightest sample sits at 70 % of the usable range; "
               "without it a melt pool's core saturates, has no reading, and the page's peak is "
               "only a lower bound");
  app.add_option("--profile", o.camera.profile,
                 "Camera profile for ratiotemp (a 5x5 camera that does not say its band map)");
  app.add_option("--region", o.camera.region,
                 "Region whose statistics the page shows and the alarm watches: x,y,width,height "
                 "in output pixels (empty: the whole frame)");
  app.add_flag("--region-tracks-peak", o.camera.region_tracks_peak,
               "Centre the page's statistics region (its size from --region) on the frame's peak, "
               "so that it follows a moving melt pool (the alarm's region stays put)");
  app.add_option("--peak-window", o.camera.peak_window,
                 "Peak statistic's window, odd pixels (ratiotemp peak-window)")
      ->capture_default_str()
      ->check(CLI::Range(1, 255));
  app.add_option("--stats-interval-ms", o.camera.stats_interval_ms,
                 "Milliseconds between statistics updates")
      ->capture_default_str()
      ->check(CLI::Range(10, 60000));
  app.add_option("--jpeg-fps", o.camera.jpeg_fps, "Frames a second at most of the page's image")
      ->capture_default_str()
      ->check(CLI::Range(1, 60));
  app.add_option("--address", o.rtsp.address, "Address to listen on (0.0.0.0: all)")
      ->capture_default_str();
  app.add_option("--rtsp-port", o.rtsp.port, "RTSP port (0: any free one, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  app.add_option("--http-port", o.web.port, "HTTP port of the page (0: any free one, printed)")
      ->capture_default_str()
      ->check(CLI::Range(0, 65535));
  app.add_option("--bitrate", o.rtsp.bitrate_kbit, "H.264 bit rate of /thermal, kbit/s")
      ->capture_default_str()
      ->check(CLI::Range(100, 100000));
  app.add_option("--key-seconds", o.key_seconds,
                 "Seconds between key frames: how long a joining client waits for a picture")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 60.0));
  app.add_option("--server", o.web.servers,
                 "Another pyrocam-serve (host:port of its page) that the page lists too; repeat")
      ->take_all();
  app.add_option("--chart-js", o.web.chart_js, "Chart.js file the page loads")
      ->capture_default_str();
  app.add_option("--alarm-threshold-c", o.alarm_threshold_c,
                 "Raise an alarm when the statistic stays above this many degC (inserts "
                 "thermalalarm; default: no alarm)");
  app.add_option("--alarm-frames", o.alarm_frames, "Consecutive frames that raise or clear it")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  app.add_option("--alarm-hysteresis-c", o.alarm_hysteresis_c,
                 "Cleared below threshold minus this, degC")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--alarm-statistic", o.alarm_statistic, "Statistic the alarm watches")
      ->capture_default_str()
      ->check(CLI::IsMember({"median", "peak"}));
  app.add_option("--watchdog-ms", o.camera.watchdog_ms,
                 "The camera counts as gone when it sends nothing this long, ms")
      ->capture_default_str()
      ->check(CLI::Range(100, 600000));
  app.add_flag("--print-pipeline", o.print_pipeline, "Print the camera pipeline and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);  // prints the help, or the error and the usage
    return code == 0 ? 0 : 2;      // a usage error: 2, as pyrocam-calib's
  }
  // NaN passes CLI::Range, and thermalalarm would keep its default: the alarm off, silently.
  if (o.alarm_threshold_c && !(*o.alarm_threshold_c > -273.15 && *o.alarm_threshold_c <= 10000)) {
    std::cerr << kName << ": --alarm-threshold-c must be a temperature above -273.15 and at "
              << "most 10000 degC, not " << *o.alarm_threshold_c << "\n";
    return 2;
  }
  if (!(o.key_seconds >= 0.1 && o.key_seconds <= 60)) {  // NaN made every frame a key frame
    std::cerr << kName << ": --key-seconds must be from 0.1 to 60 s, not " << o.key_seconds << "\n";
    return 2;
  }
  // The page's panels take host:port (a host name, an IPv4 address or an [IPv6] one): anything
  // else, such as the next option taken as the value, is no server.
  static const std::regex host_port(PYROCAM_SERVE_HOST_PORT);
  for (const std::string& server : o.web.servers)
    if (server.empty() || server[0] == '-' || !std::regex_match(server, host_port)) {
      std::cerr << kName << ": --server takes host:port of another pyrocam-serve's page, not '"
                << server << "'\n";
      return 2;
    }
  if (!(o.alarm_hysteresis_c >= 0 && o.alarm_hysteresis_c <= 1000)) {
    std::cerr << kName << ": --alarm-hysteresis-c must be from 0 to 1000 degC, not "
              << o.alarm_hysteresis_c << "\n";
    return 2;
  }

  double fps = 30;
  int width = 0, height = 0;
  if (caps_fields(o.camera.caps, fps, width, height) != 0) {
    std::cerr << kName << ": --caps '" << o.camera.caps << "' are not valid caps\n";
    return 2;
  }
  if (o.camera.caps.rfind("video/x-bayer", 0) != 0) {
    // A snapshot camera: its temperatures are scaled up to the frame under the overlay.
    if (width <= 0 || height <= 0 || width % 5 != 0 || height % 5 != 0) {
      std::cerr << kName << ": a 5x5 camera needs --caps with a width and height that are "
                << "multiples of 5 (its temperatures, one per 5x5 macro-pixel, are drawn over "
                << "the frame), not '" << o.camera.caps << "'\n";
      return 2;
    }
    o.camera.sensor_width = width;
    o.camera.sensor_height = height;
    o.web.output_pixel = 5;
  }
  o.rtsp.key_frames = std::max(1, static_cast<int>(o.key_seconds * fps + 0.5));
  o.web.address = o.rtsp.address;
  if (o.alarm_threshold_c) {
    o.camera.alarm = {"threshold-c=" + std::to_string(*o.alarm_threshold_c),
                      "frames=" + std::to_string(o.alarm_frames),
                      "hysteresis-c=" + std::to_string(o.alarm_hysteresis_c),
                      "statistic=" + o.alarm_statistic,
                      "peak-window=" + std::to_string(o.camera.peak_window)};
    if (!o.camera.region.empty()) o.camera.alarm.push_back("region=\"" + o.camera.region + "\"");
  }
  if (o.camera.region_tracks_peak && o.camera.region.empty()) {
    std::cerr << kName << ": --region-tracks-peak needs --region (its width and height)\n";
    return 2;
  }
  if (o.print_pipeline) {
    std::cout << camera_description(o.camera) << "\n";
    return 0;
  }
  if (access(o.camera.model.c_str(), R_OK) != 0) {
    std::cerr << kName << ": cannot read the model file " << o.camera.model
              << ": make it with scripts/main-job.sh (writes out/model-rgb.json) or "
                 "pyrocam-calib calibrate, or give another with --model\n";
    return 1;
  }
  for (const char* element : {"ratiotemp", "thermaloverlay", "x264enc", "rtph264pay", "jpegenc"}) {
    GstElementFactory* f = gst_element_factory_find(element);
    if (f == nullptr) {
      std::cerr << kName << ": GStreamer element " << element
                << " is missing (the pyrocam plugin in GST_PLUGIN_PATH, or the Debian packages "
                   "from scripts/install-deps.sh)\n";
      return 1;
    }
    gst_object_unref(f);
  }
  if (o.alarm_threshold_c) {
    GstElementFactory* f = gst_element_factory_find("thermalalarm");
    if (f == nullptr) {
      std::cerr << kName
                << ": the alarm options need the thermalalarm element, which this "
                   "pyrocam plugin does not have\n";
      return 1;
    }
    gst_object_unref(f);
  }
  if (access(o.web.chart_js.c_str(), R_OK) != 0)
    std::cerr << kName << ": warning: no Chart.js at " << o.web.chart_js
              << " (install the Debian package libjs-chart.js): the page shows no plot\n";

  RtspOut rtsp(o.rtsp);
  std::string error;
  if (!rtsp.start(error)) {
    std::cerr << kName << ": cannot serve RTSP on " << o.rtsp.address << " port " << o.rtsp.port
              << ": " << error
              << " (is another server on that port? choose one with --rtsp-port)\n";
    return 1;
  }
  o.web.rtsp_port = rtsp.bound_port();

  GMainLoop* loop = g_main_loop_new(nullptr, FALSE);
  int exit_code = 0;
  Camera* camera_ptr = nullptr;
  WebServer web(o.web, [&camera_ptr](std::uint64_t& seq) {
    seq = 0;
    return camera_ptr != nullptr ? camera_ptr->latest_jpeg(seq)
                                 : std::shared_ptr<const std::vector<std::uint8_t>>();
  });
  if (!web.start(error)) {
    std::cerr << kName << ": cannot serve HTTP on " << o.web.address << " port " << o.web.port
              << ": " << error
              << " (is another server on that port? choose one with --http-port)\n";
    return 1;
  }

  Camera::Callbacks callbacks;
  callbacks.on_overlay = [&rtsp](GstSample* s) { rtsp.push_overlay(s); };
  callbacks.on_temperature = [&rtsp](GstSample* s) { rtsp.push_temperature(s); };
  callbacks.on_message = [&web](const GstStructure* s) {
    const std::string name = gst_structure_get_name(s);
    if (name == "pyrocam-temperature-stats") {
      web.publish("stats", structure_to_json(s));
    } else if (name == "pyrocam-alarm") {
      nlohmann::json alarm = structure_to_json(s);
      alarm["wall-time"] = g_get_real_time() / 1000;
      web.publish("alarm", alarm);
      web.log_alarm(alarm);
      const double value = alarm.value("value-c", nlohmann::json()).is_number()
                               ? alarm["value-c"].get<double>()
                               : std::numeric_limits<double>::quiet_NaN();
      // No levels: the alarm was turned off.
      char levels[96] = "turned off";
      if (alarm.value("threshold-c", nlohmann::json()).is_number())
        std::snprintf(levels, sizeof levels, "raised above %.1f, cleared below %.1f degC",
                      alarm["threshold-c"].get<double>(), alarm.value("clear-c", 0.0));
      gchar* line = g_strdup_printf(
          "%s: ALARM %s: %s %.1f degC%s%s (%s)", kName, alarm.value("state", "?").c_str(),
          alarm.value("statistic", "?").c_str(), value,
          alarm.value("saturated", false) ? " and saturated samples" : "",
          alarm.value("above-range", false) ? " and pixels above the model's range" : "", levels);
      std::cerr << line << std::endl;
      g_free(line);
    }
  };
  callbacks.on_warning = [&web](const std::string& source, const std::string& text) {
    // Most elements' messages name them already.
    const bool named = text.rfind(source + ":", 0) == 0;
    std::cerr << kName << ": warning: " << (named ? "" : source + ": ") << text << std::endl;
    web.publish("warning",
                {{"source", source}, {"message", text}, {"wall-time", g_get_real_time() / 1000}});
  };
  callbacks.on_running = [&web]() {
    std::cerr << kName << ": camera running" << std::endl;
    web.publish("camera", {{"state", "running"}});
    // A restarted chain's thermalalarm starts clear and says so only when it is raised again: the
    // alarm raised before the restart stayed on the page while the new frames read below it.
    nlohmann::json alarm = web.latest("alarm");
    if (alarm.is_object() && alarm.value("state", "") == "raised") {
      alarm["state"] = "cleared";
      alarm["value-c"] = nullptr;
      alarm["why"] = "camera restarted: the alarm starts clear";
      alarm["wall-time"] = g_get_real_time() / 1000;
      web.publish("alarm", alarm);
      web.log_alarm(alarm);
      std::cerr << kName << ": ALARM cleared: the camera restarted and the alarm starts clear"
                << std::endl;
    }
  };
  callbacks.on_lost = [&](const std::string& why, bool fatal) {
    rtsp.camera_lost();
    web.publish("camera", {{"state", "lost"}, {"why", why}});
    if (fatal) {
      std::cerr << kName << ": the thermal chain failed before the first frame: " << why
                << std::endl;
      exit_code = 1;
      g_main_loop_quit(loop);
    } else {
      std::cerr << kName << ": camera stopped (" << why << "); clients get an end of stream, "
                << "retrying" << std::endl;
    }
  };
  if (o.alarm_threshold_c)  // armed and clear until thermalalarm says otherwise
    web.publish("alarm", {{"state", "clear"},
                          {"statistic", o.alarm_statistic},
                          {"threshold-c", *o.alarm_threshold_c},
                          {"clear-c", *o.alarm_threshold_c - o.alarm_hysteresis_c}});
  Camera camera(o.camera, callbacks);
  camera_ptr = &camera;
  if (!camera.start(error)) {
    std::cerr << kName << ": the camera pipeline does not parse: " << error
              << " (check --camera, --caps, --dark, --region)\n";
    return 1;
  }
  // All addresses: the host's name; an IPv6 address goes in brackets in a URL.
  const std::string host = o.rtsp.address == "0.0.0.0" || o.rtsp.address == "::" ? host_name()
                           : o.rtsp.address.find(':') != std::string::npos
                               ? "[" + o.rtsp.address + "]"
                               : o.rtsp.address;
  std::cerr << kName << ": RTSP on port " << rtsp.bound_port() << ": rtsp://" << host << ":"
            << rtsp.bound_port() << "/thermal and rtsp://" << host << ":" << rtsp.bound_port()
            << "/temperature; the page on port " << web.bound_port() << ": http://" << host << ":"
            << web.bound_port() << "/" << std::endl;

  g_unix_signal_add(SIGINT, on_signal, loop);
  g_unix_signal_add(SIGTERM, on_signal, loop);
  g_main_loop_run(loop);
  camera.stop();
  camera_ptr = nullptr;
  g_main_loop_unref(loop);
  return exit_code;
}
