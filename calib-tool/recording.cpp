// Decoding a recording: one pipeline per segment (filesrc ! matroskademux ! avdec_ffv1 !
// appsink), so that a segment cut short by a crash gives its whole frames and a bad one is named.
#include "recording.h"

#include <gst/app/gstappsink.h>
#include <gst/gst.h>
#include <gst/video/video.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>

#include "pyrocam/core/error.h"
#include "pyrocam/core/recording_comment.h"
#include "pyrocam/core/temperature_codes.h"

namespace pyrocam::cli {
namespace {

namespace fs = std::filesystem;

// How long one segment may go without a frame or the end before it counts as stuck.
constexpr GstClockTime kStallTimeout = 30 * GST_SECOND;

void ensure_gst() {
  static const bool ready = [] {
    gst_init(nullptr, nullptr);
    return true;
  }();
  (void)ready;
}

// Unrefs a GStreamer object when it goes.
struct Unref {
  void operator()(gpointer p) const {
    if (p) gst_object_unref(p);
  }
};
using ElementPtr = std::unique_ptr<GstElement, Unref>;

std::string take_error(GstMessage* msg) {
  GError* err = nullptr;
  gchar* debug = nullptr;
  gst_message_parse_error(msg, &err, &debug);
  std::string text = err ? err->message : "unknown error";
  g_clear_error(&err);
  g_free(debug);
  return text;
}

// The tags that reach the appsink (stream tags through the decoder).
GstPadProbeReturn keep_tags(GstPad*, GstPadProbeInfo* info, gpointer data) {
  GstEvent* event = GST_PAD_PROBE_INFO_EVENT(info);
  if (GST_EVENT_TYPE(event) == GST_EVENT_TAG) {
    GstTagList* tags = nullptr;
    gst_event_parse_tag(event, &tags);
    auto* d = static_cast<RecordingDescription*>(data);
    gchar* v = nullptr;
    if (gst_tag_list_get_string(tags, GST_TAG_COMMENT, &v)) {
      d->comment = v;
      d->fields = parse_recording_comment(d->comment);
    }
    g_free(v);
    v = nullptr;
    if (gst_tag_list_get_string(tags, GST_TAG_TITLE, &v)) d->title = v;
    g_free(v);
  }
  return GST_PAD_PROBE_OK;
}

// The frame's codes (rows without their padding) as a CV_16U matrix of its own.
cv::Mat codes_of(GstSample* sample, const fs::path& file) {
  GstVideoInfo info;
  GstCaps* caps = gst_sample_get_caps(sample);
  if (!caps || !gst_video_info_from_caps(&info, caps) ||
      (GST_VIDEO_INFO_FORMAT(&info) != GST_VIDEO_FORMAT_GRAY16_LE &&
       GST_VIDEO_INFO_FORMAT(&info) != GST_VIDEO_FORMAT_GRAY8))
    throw InputError(file.string() +
                     ": not a pyrocam recording (frames are not 16- or 8-bit gray)");
  const bool wide = GST_VIDEO_INFO_FORMAT(&info) == GST_VIDEO_FORMAT_GRAY16_LE;
  GstVideoFrame frame;
  if (!gst_video_frame_map(&frame, &info, gst_sample_get_buffer(sample), GST_MAP_READ))
    throw InputError(file.string() + ": a decoded frame is smaller than its caps say");
  const int w = GST_VIDEO_FRAME_WIDTH(&frame), h = GST_VIDEO_FRAME_HEIGHT(&frame);
  cv::Mat out(h, w, wide ? CV_16U : CV_8U);
  for (int y = 0; y < h; ++y)
    std::memcpy(out.ptr(y),
                static_cast<const guint8*>(GST_VIDEO_FRAME_PLANE_DATA(&frame, 0)) +
                    static_cast<std::ptrdiff_t>(y) * GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0),
                static_cast<std::size_t>(w) * (wide ? 2 : 1));
  gst_video_frame_unmap(&frame);
  return out;
}

// An empty file, or one that starts as Matroska does (the EBML magic): what a recording's last
// segment is when the recording was cut off while writing it.
bool empty_or_matroska(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  char magic[4] = {};
  in.read(magic, sizeof magic);
  return in.gcount() == 0 || (in.gcount() == 4 && std::memcmp(magic, "\x1A\x45\xDF\xA3", 4) == 0);
}

}  // namespace

std::vector<fs::path> recording_segments(const fs::path& where, const std::string& prefix) {
  std::error_code ec;
  if (fs::is_regular_file(where, ec)) return {where};
  if (!fs::is_directory(where, ec))
    throw InputError(where.string() + ": no such recording (neither a folder nor a file)");
  std::vector<fs::path> out;
  for (const auto& entry : fs::directory_iterator(where, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) == 0 && entry.path().extension() == ".mkv") out.push_back(entry);
  }
  if (ec) throw InputError(where.string() + ": cannot list the folder: " + ec.message());
  if (out.empty())
    throw InputError(where.string() + ": not a recording (no " + prefix + "NNNNN.mkv segments)");
  // By number where record.sh numbered them (temperature-100000 after temperature-99999, which
  // text order put first: a recording of more than 100000 segments was refused as having a gap),
  // the others by name after them.
  const auto number = [&prefix](const fs::path& p) -> long {
    const std::string digits = p.stem().string().substr(prefix.size());
    const bool numbered = !digits.empty() && digits.size() <= 9 &&
                          std::all_of(digits.begin(), digits.end(),
                                      [](unsigned char c) { return std::isdigit(c) != 0; });
    return numbered ? std::stol(digits) : -1;
  };
  std::sort(out.begin(), out.end(), [&number](const fs::path& a, const fs::path& b) {
    const long na = number(a), nb = number(b);
    if ((na < 0) != (nb < 0)) return na >= 0;
    return na != nb ? na < nb : a < b;
  });
  // Segments restart at time 0, each placed after the one before: without one, the frames after
  // it would read as earlier than they were.
  long expected = -1;
  for (const fs::path& p : out) {
    const long n = number(p);
    if (n < 0) continue;  // not record.sh's numbering: as it comes
    if (expected >= 0 && n != expected) {
      char name[64];
      std::snprintf(name, sizeof name, "%s%05ld.mkv", prefix.c_str(), expected);
      throw InputError(where.string() + ": " + name + " is missing (the segments jump to " +
                       p.filename().string() +
                       "): the frames after it cannot be placed in time; give the segments "
                       "before it, or after it, one by one");
    }
    expected = n + 1;
  }
  return out;
}

RecordingDescription read_recording(const std::vector<fs::path>& segments,
                                    const std::function<void(const RecordingFrame&)>& on_frame) {
  ensure_gst();
  RecordingDescription description;
  std::size_t index = 0;
  double end_s = 0;  // the end of the last frame so far, in the recording's time
  int width = 0, height = 0;
  for (const fs::path& file : segments) {
    const bool last = &file == &segments.back();
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      throw InputError(file.string() + ": segment missing or not a file");
    GError* error = nullptr;
    ElementPtr pipeline(gst_parse_launch(
        "filesrc name=src ! matroskademux ! avdec_ffv1 ! appsink name=out sync=false", &error));
    if (!pipeline || error) {
      const std::string why = error ? error->message : "unknown";
      g_clear_error(&error);
      throw InputError(
          "cannot build the decoding pipeline (are gstreamer1.0-plugins-good and "
          "gstreamer1.0-libav installed?): " +
          why);
    }
    ElementPtr src(gst_bin_get_by_name(GST_BIN(pipeline.get()), "src"));
    ElementPtr sink(gst_bin_get_by_name(GST_BIN(pipeline.get()), "out"));
    g_object_set(src.get(), "location", file.c_str(), nullptr);
    GstPad* sinkpad = gst_element_get_static_pad(sink.get(), "sink");
    gst_pad_add_probe(sinkpad, GST_PAD_PROBE_TYPE_EVENT_DOWNSTREAM, keep_tags, &description,
                      nullptr);
    gst_object_unref(sinkpad);
    GstBus* bus = gst_element_get_bus(pipeline.get());
    std::string failure;
    double offset_s = 0;  // added to this segment's timestamps
    std::size_t frames_here = 0;
    gint64 declared_ns = -1;  // the segment's duration as its header says it (closed segments)
    double frame_s = 0, first_s = 0;  // a frame's duration, the first frame's time
    if (gst_element_set_state(pipeline.get(), GST_STATE_PLAYING) == GST_STATE_CHANGE_FAILURE)
      failure = "cannot start decoding";
    GstClockTime waited = 0;  // since the last frame
    while (failure.empty()) {
      constexpr GstClockTime kPoll = 100 * GST_MSECOND;
      GstSample* sample = gst_app_sink_try_pull_sample(GST_APP_SINK(sink.get()), kPoll);
      if (!sample) {
        // An error does not wake the sink: look for one on the bus between polls.
        if (GstMessage* msg = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR)) {
          failure = take_error(msg);
          gst_message_unref(msg);
        } else if (gst_app_sink_is_eos(GST_APP_SINK(sink.get()))) {
          break;
        } else if ((waited += kPoll) >= kStallTimeout) {
          failure = "no frame and no end for " + std::to_string(kStallTimeout / GST_SECOND) + " s";
        }
        continue;
      }
      waited = 0;
      GstBuffer* b = gst_sample_get_buffer(sample);
      const double pts_s = GST_BUFFER_PTS_IS_VALID(b) ? GST_BUFFER_PTS(b) / 1e9 : 0;
      double duration_s = GST_BUFFER_DURATION_IS_VALID(b) ? GST_BUFFER_DURATION(b) / 1e9 : 0;
      GstVideoInfo info;
      if (duration_s == 0 && gst_video_info_from_caps(&info, gst_sample_get_caps(sample)) &&
          GST_VIDEO_INFO_FPS_N(&info) > 0)
        duration_s = static_cast<double>(GST_VIDEO_INFO_FPS_D(&info)) / GST_VIDEO_INFO_FPS_N(&info);
      RecordingFrame f;
      try {
        f.codes = codes_of(sample, file);
        gst_sample_unref(sample);
        if (width == 0) {
          width = f.codes.cols;
          height = f.codes.rows;
        } else if (f.codes.cols != width || f.codes.rows != height) {
          failure = "frames of " + std::to_string(f.codes.cols) + "x" +
                    std::to_string(f.codes.rows) + ", the recording's first were " +
                    std::to_string(width) + "x" + std::to_string(height);
          break;
        }
        // Segments written with offset-to-zero (record.sh) restart at 0: they follow the last,
        // on Matroska's whole milliseconds (the last frame's time was rounded to one).
        if (frames_here == 0 && index > 0 && pts_s < end_s - 1e-6)
          offset_s = std::round(end_s * 1000) / 1000 - pts_s;
        if (frames_here == 0) {
          first_s = pts_s;
          if (!gst_element_query_duration(pipeline.get(), GST_FORMAT_TIME, &declared_ns))
            declared_ns = -1;
        }
        f.tags = &description;
        f.index = index++;
        f.timestamp_s = offset_s + pts_s;
        end_s = std::max(end_s, f.timestamp_s + duration_s);
        frame_s = duration_s;
        ++frames_here;
        on_frame(f);
      } catch (...) {
        if (!f.codes.data) gst_sample_unref(sample);
        gst_element_set_state(pipeline.get(), GST_STATE_NULL);
        gst_object_unref(bus);
        throw;
      }
    }
    gst_element_set_state(pipeline.get(), GST_STATE_NULL);
    gst_object_unref(bus);
    // A closed segment whose frames end before its header's duration was cut short (a copy, a
    // disk): its last frames are missing, and the next segment starts at the duration, not at
    // the last frame read (they restart at 0), so that later frames keep their times.
    const double declared_end_s = offset_s + first_s + static_cast<double>(declared_ns) / 1e9;
    if (!last && frames_here > 0 && declared_ns > 0 &&
        declared_end_s > end_s + 0.5 * frame_s + 2e-3) {
      std::cerr << "warning: " << file.string() << ": its frames end " << end_s - offset_s - first_s
                << " s into its " << declared_ns / 1e9
                << " s: cut short, its last frames are missing; the later segments keep their "
                   "times\n";
      end_s = declared_end_s;
    }
    const std::string problem = !failure.empty()
                                    ? "not a readable recording segment (" + failure + ")"
                                : frames_here == 0 ? "no frames (an empty or truncated segment)"
                                                   : std::string();
    if (problem.empty()) continue;
    // A recording killed (or its machine cut off) as a segment began, or while it was written,
    // leaves its last segment empty or a Matroska file cut short: the segments before it, and
    // the frames of it that decoded, are the recording. Anything else that fails is an error.
    if (last && index > 0 && empty_or_matroska(file)) {
      std::cerr << "warning: " << file.string() << ": " << problem << "; the recording's last "
                << "segment, cut short when it stopped: " << frames_here << " of its frames read\n";
      break;
    }
    throw InputError(file.string() + ": " + problem);
  }
  description.width = width;
  description.height = height;
  return description;
}

}  // namespace pyrocam::cli
