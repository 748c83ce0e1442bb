#include "pyrocam-common.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "pyrocam/core/recording_comment.h"
#include "pyrocam/runtime/bracket_fusion.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/uncertainty.h"

namespace pyrocam::gst {

bool parse_raw_caps(GstCaps* caps, RawFormat* out) {
  if (!caps || gst_caps_get_size(caps) < 1) return false;
  const GstStructure* s = gst_caps_get_structure(caps, 0);
  RawFormat f;
  if (gst_structure_has_name(s, PYROCAM_BAYER_MEDIA_TYPE)) {
    const char* format = gst_structure_get_string(s, "format");
    if (!format || !gst_structure_get_int(s, "width", &f.width) ||
        !gst_structure_get_int(s, "height", &f.height))
      return false;
    f.bayer_caps = true;
    f.pattern = format;
    f.bytes_per_sample = 1;
    gst_video_info_init(&f.info);
  } else if (gst_structure_has_name(s, PYROCAM_VIDEO_MEDIA_TYPE)) {
    if (!gst_video_info_from_caps(&f.info, caps)) return false;
    const GstVideoFormat vf = GST_VIDEO_INFO_FORMAT(&f.info);
    if (vf != GST_VIDEO_FORMAT_GRAY8 && vf != GST_VIDEO_FORMAT_GRAY16_LE) return false;
    f.bytes_per_sample = vf == GST_VIDEO_FORMAT_GRAY8 ? 1 : 2;
    f.width = GST_VIDEO_INFO_WIDTH(&f.info);
    f.height = GST_VIDEO_INFO_HEIGHT(&f.info);
  } else {
    return false;
  }
  if (f.width < 1 || f.height < 1) return false;
  *out = f;
  return true;
}

gsize raw_frame_size(const RawFormat& f) {
  if (!f.bayer_caps) return GST_VIDEO_INFO_SIZE(&f.info);
  return static_cast<gsize>(GST_ROUND_UP_4(f.width)) * static_cast<gsize>(f.height);
}

MosaicLayout layout_for_pattern(const std::string& pattern) {
  if (pattern == PYROCAM_SNAPSHOT_PATTERN_NAME) {
    std::vector<int> map(25);
    for (int i = 0; i < 25; ++i) map[static_cast<std::size_t>(i)] = i;
    return MosaicLayout::snapshot(5, 5, map);
  }
  return MosaicLayout::bayer(pattern);
}

std::string band_map_text(const MosaicLayout& layout) {
  std::string text;
  for (std::size_t i = 0; i < layout.band_map.size(); ++i)
    text += (i ? "," : "") + std::to_string(layout.band_map[i]);
  return text;
}

MosaicLayout layout_for_band_map(const std::string& text) {
  std::vector<int> map;
  std::vector<bool> seen(25, false);
  std::size_t start = 0;
  while (start <= text.size() && map.size() <= 25) {
    const std::size_t end = std::min(text.find(',', start), text.size());
    const std::string item = text.substr(start, end - start);
    char* stop = nullptr;
    const long v = std::strtol(item.c_str(), &stop, 10);
    if (item.empty() || !stop || *stop || v < 0 || v > 24 || seen[static_cast<std::size_t>(v)])
      throw InputError("band-map '" + text +
                       "' is not 25 comma-separated band indices, each 0..24 once");
    seen[static_cast<std::size_t>(v)] = true;
    map.push_back(static_cast<int>(v));
    start = end + 1;
  }
  if (map.size() != 25)
    throw InputError("band-map '" + text +
                     "' is not 25 comma-separated band indices, each 0..24 once");
  return MosaicLayout::snapshot(5, 5, map);
}

void MappedImage::reset() {
  if (video_frame_) gst_video_frame_unmap(&frame_);
  if (buffer_) gst_buffer_unmap(buffer_, &map_);
  video_frame_ = false;
  buffer_ = nullptr;
  image_ = cv::Mat();
}

void MappedImage::map_raw(GstBuffer* buffer, const RawFormat& f) {
  reset();
  const int type = f.bytes_per_sample == 1 ? CV_8U : CV_16U;
  if (!f.bayer_caps) {
    if (!gst_video_frame_map(&frame_, const_cast<GstVideoInfo*>(&f.info), buffer, GST_MAP_READ))
      throw InputError("cannot map a " + std::to_string(gst_buffer_get_size(buffer)) +
                       "-byte buffer as a " + std::to_string(f.width) + "x" +
                       std::to_string(f.height) + " gray frame");
    video_frame_ = true;
    image_ = cv::Mat(f.height, f.width, type, GST_VIDEO_FRAME_PLANE_DATA(&frame_, 0),
                     static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&frame_, 0)));
    return;
  }
  if (!gst_buffer_map(buffer, &map_, GST_MAP_READ)) throw InputError("cannot map the buffer");
  buffer_ = buffer;
  const gsize tight = static_cast<gsize>(f.width) * static_cast<gsize>(f.height);
  std::size_t stride;
  if (map_.size >= raw_frame_size(f))
    stride = static_cast<std::size_t>(GST_ROUND_UP_4(f.width));
  else if (map_.size == tight)  // cameras that do not pad rows
    stride = static_cast<std::size_t>(f.width);
  else
    throw InputError("a " + std::to_string(map_.size) + "-byte buffer is too small for a " +
                     std::to_string(f.width) + "x" + std::to_string(f.height) + " Bayer frame");
  image_ = cv::Mat(f.height, f.width, type, map_.data, stride);
}

void MappedImage::map_float(GstBuffer* buffer, int width, int height, int planes,
                            GstMapFlags flags) {
  reset();
  if (!gst_buffer_map(buffer, &map_, flags)) throw InputError("cannot map the buffer");
  buffer_ = buffer;
  const gsize needed = static_cast<gsize>(width) * static_cast<gsize>(height) *
                       static_cast<gsize>(planes) * sizeof(float);
  if (map_.size < needed)
    throw InputError("a " + std::to_string(map_.size) + "-byte buffer is too small for " +
                     std::to_string(planes) + " float plane(s) of " + std::to_string(width) + "x" +
                     std::to_string(height));
  image_ = cv::Mat(height * planes, width, CV_32F, map_.data);
}

cv::Mat MappedImage::plane(int index, int width, int height) const {
  return cv::Mat(height, width, CV_32F,
                 const_cast<float*>(image_.ptr<float>(0)) + static_cast<std::size_t>(index) *
                                                                static_cast<std::size_t>(width) *
                                                                static_cast<std::size_t>(height));
}

void ensure_buffer_pool(GstQuery* query, gsize size) {
  if (size == 0 || gst_query_get_n_allocation_pools(query) > 0) return;
  GstCaps* caps = nullptr;
  gst_query_parse_allocation(query, &caps, nullptr);
  GstBufferPool* pool = gst_buffer_pool_new();
  GstStructure* config = gst_buffer_pool_get_config(pool);
  gst_buffer_pool_config_set_params(config, caps, static_cast<guint>(size), 2, 0);
  if (gst_buffer_pool_set_config(pool, config))
    gst_query_add_allocation_pool(query, pool, static_cast<guint>(size), 2, 0);
  gst_object_unref(pool);
}

bool is_fused_bands(const GstCaps* caps, guint index) {
  if (!caps || index >= gst_caps_get_size(caps)) return false;
  const GstCapsFeatures* features = gst_caps_get_features(caps, index);
  return gst_structure_has_name(gst_caps_get_structure(caps, index), PYROCAM_BANDS_MEDIA_TYPE) &&
         features && !gst_caps_features_is_any(features) &&
         gst_caps_features_contains(features, PYROCAM_CAPS_FEATURE_MOSAIC);
}

bool temperature_frame_fits(GstBaseTransform* trans, const GstVideoInfo& info, GstBuffer* buffer) {
  GstVideoFrame frame;
  if (gst_video_frame_map(&frame, const_cast<GstVideoInfo*>(&info), buffer, GST_MAP_READ)) {
    gst_video_frame_unmap(&frame);
    return true;
  }
  PYROCAM_POST_ERROR(trans, ErrorKind::kFormat,
                     "A temperature buffer of " + std::to_string(gst_buffer_get_size(buffer)) +
                         " bytes does not hold a " + std::to_string(GST_VIDEO_INFO_WIDTH(&info)) +
                         "x" + std::to_string(GST_VIDEO_INFO_HEIGHT(&info)) +
                         " GRAY16_LE frame of " + std::to_string(GST_VIDEO_INFO_SIZE(&info)) +
                         " bytes",
                     "gst_video_frame_map failed on the input buffer");
  return false;
}

gsize frame_size_of_caps(GstCaps* caps) {
  if (!caps || gst_caps_get_size(caps) < 1) return 0;
  const GstStructure* s = gst_caps_get_structure(caps, 0);
  if (gst_structure_has_name(s, PYROCAM_VIDEO_MEDIA_TYPE)) {
    GstVideoInfo info;
    return gst_video_info_from_caps(&info, caps) ? GST_VIDEO_INFO_SIZE(&info) : 0;
  }
  const int width = structure_int(s, "width", 0), height = structure_int(s, "height", 0);
  // x-pyrocam-mosaic carries no bands field: one plane; so do fused bands (their mosaic).
  const int planes = is_fused_bands(caps) ? 1
                     : gst_structure_has_name(s, PYROCAM_BANDS_MEDIA_TYPE)
                         ? structure_int(s, "bands", 0)
                     : gst_structure_has_name(s, PYROCAM_MOSAIC_MEDIA_TYPE) ? 1
                                                                            : 0;
  if (width < 1 || height < 1 || planes < 1) return 0;
  return static_cast<gsize>(width) * static_cast<gsize>(height) * static_cast<gsize>(planes) *
         sizeof(float);
}

gboolean decide_allocation(GstBaseTransform* trans, GstQuery* query) {
  GstCaps* caps = nullptr;
  gst_query_parse_allocation(query, &caps, nullptr);
  ensure_buffer_pool(query, frame_size_of_caps(caps));
  // The elements are GstBaseTransform's direct subclasses: its class holds their parent's
  // decide_allocation.
  auto* base = static_cast<GstBaseTransformClass*>(g_type_class_peek(GST_TYPE_BASE_TRANSFORM));
  return base->decide_allocation(trans, query);
}

void sync_controlled_properties(GstBaseTransform* trans, GstBuffer* buffer) {
  if (trans->segment.format != GST_FORMAT_TIME || !GST_BUFFER_PTS_IS_VALID(buffer)) return;
  const GstClockTime stream_time =
      gst_segment_to_stream_time(&trans->segment, GST_FORMAT_TIME, GST_BUFFER_PTS(buffer));
  if (GST_CLOCK_TIME_IS_VALID(stream_time)) gst_object_sync_values(GST_OBJECT(trans), stream_time);
}

int structure_int(const GstStructure* s, const char* field, int fallback) {
  int v;
  return gst_structure_get_int(s, field, &v) ? v : fallback;
}

std::string structure_string(const GstStructure* s, const char* field) {
  const char* v = gst_structure_get_string(s, field);
  return v ? v : "";
}

void copy_fields(const GstStructure* from, GstStructure* to,
                 std::initializer_list<const char*> fields) {
  for (const char* field : fields) {
    const GValue* v = gst_structure_get_value(from, field);
    if (v) gst_structure_set_value(to, field, v);
  }
}

void copy_dimensions(const GstStructure* from, GstStructure* to) {
  copy_fields(from, to, {"width", "height", "framerate"});
}

void set_list_field(GstStructure* s, const char* field, const char* list_text) {
  GValue list = G_VALUE_INIT;
  g_value_init(&list, GST_TYPE_LIST);
  if (!gst_value_deserialize(&list, list_text))
    g_critical("pyrocam: '%s' is not a caps list", list_text);  // a programming error
  gst_structure_take_value(s, field, &list);
}

ErrorKind profile_error_kind(const std::string& name) {
  const bool looks_like_file = name.find('/') != std::string::npos ||
                               (name.size() > 5 && name.compare(name.size() - 5, 5, ".json") == 0);
  std::error_code ec;
  return looks_like_file && !std::filesystem::exists(name, ec) ? ErrorKind::kNotFound
                                                               : ErrorKind::kRead;
}

GParamSpec* bracket_frames_param(guint default_frames) {
  return g_param_spec_uint("frames", "Frames",
                           "Consecutive frames fused: the length of the camera's exposure cycle "
                           "(1..16; 1: none, frames pass unchanged)",
                           1, pyrocam::kMaxBracketFrames, default_frames,
                           static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                    GST_PARAM_MUTABLE_PLAYING));
}

void warn_not_changeable_while_running(GstElement* element, const char* property) {
  GST_ELEMENT_WARNING(element, RESOURCE, SETTINGS,
                      ("%s: %s can change only in the NULL or READY state; the change is "
                       "ignored and the current value stays",
                       GST_OBJECT_NAME(element), property),
                      ("%s set while running", property));
}

bool refuses_other_quantity(GstElement* element, GstEvent* event) {
  if (GST_EVENT_TYPE(event) != GST_EVENT_TAG) return false;
  GstTagList* tags = nullptr;
  gst_event_parse_tag(event, &tags);
  gchar* comment = nullptr;
  std::string quantity;
  if (gst_tag_list_get_string(tags, GST_TAG_COMMENT, &comment)) {
    const auto fields = parse_recording_comment(comment);
    const auto q = fields.find("quantity");
    if (q != fields.end()) quantity = q->second;
  }
  g_free(comment);
  if (quantity.empty() || quantity == "temperature") return false;
  PYROCAM_POST_ERROR(element, ErrorKind::kFormat,
                     std::string(GST_OBJECT_NAME(element)) + ": the stream holds " + quantity +
                         " (its tags say so), not temperatures: its codes would read as degC",
                     "tag comment quantity=" + quantity);
  return true;
}

void warn_frame_without_exposure(GstElement* element, bool& warned) {
  if (warned) return;
  warned = true;
  GST_ELEMENT_WARNING(element, STREAM, FORMAT,
                      ("A frame without its exposure: passed on unfused (frames of unknown "
                       "exposure cannot be ranked; the source must attach "
                       "PyrocamExposureMeta, as pyrocamsrc does, or autoexposure once a camera's "
                       "exposure has held for its latency)"),
                      ("no PyrocamExposureMeta on the buffer"));
}

bool frame_out_of_time_order(GstElement* element, GstBuffer* buffer, GstClockTime& last_pts,
                             bool& warned) {
  const GstClockTime pts = GST_BUFFER_PTS(buffer);
  if (!GST_CLOCK_TIME_IS_VALID(pts)) return false;
  const bool backwards = GST_CLOCK_TIME_IS_VALID(last_pts) && pts < last_pts;
  if (backwards && !warned) {
    warned = true;
    GST_ELEMENT_WARNING(
        element, STREAM, FORMAT,
        ("Frames out of time order: a frame at %" GST_TIME_FORMAT " after one at %" GST_TIME_FORMAT
         "; the bracket fusion starts anew from it (it fuses only frames in the "
         "order they were taken)",
         GST_TIME_ARGS(pts), GST_TIME_ARGS(last_pts)),
        ("buffer PTS went backwards"));
  }
  last_pts = pts;
  return backwards;
}

static GQuark posted_error_quark() {
  static const GQuark quark = g_quark_from_static_string("pyrocam-posted-error");
  return quark;
}

void forget_posted_errors(GstElement* element) {
  GST_OBJECT_LOCK(element);
  g_object_set_qdata_full(G_OBJECT(element), posted_error_quark(), nullptr, nullptr);
  GST_OBJECT_UNLOCK(element);
}

void post_error(GstElement* element, ErrorKind kind, const std::string& user,
                const std::string& debug, const char* function, int line) {
  GST_OBJECT_LOCK(element);
  const auto* posted =
      static_cast<const char*>(g_object_get_qdata(G_OBJECT(element), posted_error_quark()));
  const bool repeated = posted != nullptr && user == posted;
  // Without a bus (an element not yet in a pipeline) the message goes nowhere: not posted.
  if (!repeated && GST_ELEMENT_BUS(element) != nullptr)
    g_object_set_qdata_full(G_OBJECT(element), posted_error_quark(), g_strdup(user.c_str()),
                            g_free);
  GST_OBJECT_UNLOCK(element);
  if (repeated) {
    GST_DEBUG_OBJECT(element, "error already posted: %s", user.c_str());
    return;
  }
  GQuark domain = GST_RESOURCE_ERROR;
  gint code = GST_RESOURCE_ERROR_FAILED;
  switch (kind) {
    case ErrorKind::kNotFound:
      code = GST_RESOURCE_ERROR_NOT_FOUND;
      break;
    case ErrorKind::kRead:
      code = GST_RESOURCE_ERROR_READ;
      break;
    case ErrorKind::kSettings:
      code = GST_RESOURCE_ERROR_SETTINGS;
      break;
    case ErrorKind::kFormat:
      domain = GST_STREAM_ERROR;
      code = GST_STREAM_ERROR_FORMAT;
      break;
    case ErrorKind::kNegotiation:
      domain = GST_CORE_ERROR;
      code = GST_CORE_ERROR_NEGOTIATION;
      break;
    case ErrorKind::kNumeric:
      domain = GST_LIBRARY_ERROR;
      code = GST_LIBRARY_ERROR_FAILED;
      break;
  }
  gst_element_message_full(element, GST_MESSAGE_ERROR, domain, code, g_strdup(user.c_str()),
                           g_strdup(debug.c_str()), __FILE__, function, line);
}

bool parse_region(const std::string& text, Region* out) {
  gchar** parts = g_strsplit(text.c_str(), ",", -1);
  bool ok = g_strv_length(parts) == 4;
  gint64 v[4] = {0, 0, 0, 0};
  for (int i = 0; ok && i < 4; ++i)
    ok = g_ascii_string_to_signed(g_strstrip(parts[i]), 10, 0, G_MAXINT, &v[i], nullptr) &&
         (i < 2 || v[i] >= 1);
  g_strfreev(parts);
  if (ok)
    *out = {static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[2]),
            static_cast<int>(v[3])};
  return ok;
}

namespace {

// Sample rectangle `r` of the meta's frame in pixels of a width x height frame, grown by the
// demosaicking kernels' reach, within the frame.
cv::Rect scaled_reach(const PyrocamSaturationMeta& meta, const cv::Rect& r, int width, int height) {
  const int reach = width < meta.frame_width ? 1 : 2;
  const auto down = [](gint v, int to, gint from) {
    return static_cast<int>(static_cast<gint64>(v) * to / from);
  };
  const auto up = [](gint v, int to, gint from) {
    return static_cast<int>((static_cast<gint64>(v) * to + from - 1) / from);
  };
  const cv::Rect s(cv::Point(down(r.x, width, meta.frame_width) - reach,
                             down(r.y, height, meta.frame_height) - reach),
                   cv::Point(up(r.x + r.width, width, meta.frame_width) + reach,
                             up(r.y + r.height, height, meta.frame_height) + reach));
  return s & cv::Rect(0, 0, width, height);
}

bool meta_known(const PyrocamSaturationMeta* meta) {
  return meta && meta->samples > 0 && meta->width > 0 && meta->height > 0 &&
         meta->frame_width > 0 && meta->frame_height > 0;
}

}  // namespace

bool saturation_hides_readings(const PyrocamSaturationMeta* meta, const cv::Mat& codes,
                               const cv::Rect& within) {
  if (!meta_known(meta)) return false;
  const cv::Rect bounds(meta->x, meta->y, meta->width, meta->height);
  // Tile by tile: far-apart saturated spots do not hide the readings between them.
  for (int i = 0; i < pyrocam::kSaturationTiles; ++i) {
    for (int j = 0; j < pyrocam::kSaturationTiles; ++j) {
      if (!(meta->tiles[i] >> j & 1u)) continue;
      const cv::Rect tile =
          pyrocam::saturation_tile_rect(i, j, meta->frame_width, meta->frame_height) & bounds;
      if (tile.empty()) continue;
      const cv::Rect r = scaled_reach(*meta, tile, codes.cols, codes.rows) & within;
      if (!r.empty() && cv::countNonZero(codes(r)) < r.area()) return true;
    }
  }
  return false;
}

namespace {

bool has_above_range(const PyrocamAboveRangeMeta* meta) {
  return meta && meta->pixels > 0 && meta->width > 0 && meta->height > 0 && meta->frame_width > 0 &&
         meta->frame_height > 0;
}

/* Tile (i, j) of the meta cut to its rectangle and scaled to `size`; empty if outside it. */
cv::Rect above_range_tile(const PyrocamAboveRangeMeta* meta, int i, int j, cv::Size size) {
  const cv::Rect bounds(meta->x, meta->y, meta->width, meta->height);
  const cv::Rect tile =
      pyrocam::saturation_tile_rect(i, j, meta->frame_width, meta->frame_height) & bounds;
  if (tile.empty()) return {};
  const auto down = [](int v, int to, gint from) {
    return static_cast<int>(static_cast<gint64>(v) * to / from);
  };
  const auto up = [](int v, int to, gint from) {
    return static_cast<int>((static_cast<gint64>(v) * to + from - 1) / from);
  };
  const cv::Rect scaled(cv::Point(down(tile.x, size.width, meta->frame_width),
                                  down(tile.y, size.height, meta->frame_height)),
                        cv::Point(up(tile.x + tile.width, size.width, meta->frame_width),
                                  up(tile.y + tile.height, size.height, meta->frame_height)));
  return scaled & cv::Rect(cv::Point(0, 0), size);
}

}  // namespace

std::vector<cv::Rect> above_range_rects(const PyrocamAboveRangeMeta* meta, cv::Size size) {
  std::vector<cv::Rect> rects;
  if (!has_above_range(meta)) return rects;
  for (int i = 0; i < pyrocam::kSaturationTiles; ++i)
    for (int j = 0; j < pyrocam::kSaturationTiles; ++j) {
      if (!(meta->tiles[i] >> j & 1u)) continue;
      const cv::Rect tile = above_range_tile(meta, i, j, size);
      if (!tile.empty()) rects.push_back(tile);
    }
  return rects;
}

cv::Rect largest_above_range_spot(const PyrocamAboveRangeMeta* meta, cv::Size size) {
  if (!has_above_range(meta)) return {};
  constexpr int n = pyrocam::kSaturationTiles;
  std::vector<char> seen(n * n, 0);
  std::vector<std::pair<int, int>> stack;
  cv::Rect largest;
  int largest_tiles = 0;
  for (int i0 = 0; i0 < n; ++i0)
    for (int j0 = 0; j0 < n; ++j0) {
      if (!(meta->tiles[i0] >> j0 & 1u) || seen[i0 * n + j0]) continue;
      // A spot: the tiles that touch, corners too.
      cv::Rect spot;
      int tiles = 0;
      seen[i0 * n + j0] = 1;
      stack.assign(1, {i0, j0});
      while (!stack.empty()) {
        const auto [i, j] = stack.back();
        stack.pop_back();
        spot |= above_range_tile(meta, i, j, size);
        ++tiles;
        for (int di = -1; di <= 1; ++di)
          for (int dj = -1; dj <= 1; ++dj) {
            const int ni = i + di, nj = j + dj;
            if (ni < 0 || nj < 0 || ni >= n || nj >= n || seen[ni * n + nj] ||
                !(meta->tiles[ni] >> nj & 1u))
              continue;
            seen[ni * n + nj] = 1;
            stack.emplace_back(ni, nj);
          }
      }
      if (tiles > largest_tiles && !spot.empty()) largest = spot, largest_tiles = tiles;
    }
  return largest;
}

bool above_range_within(const PyrocamAboveRangeMeta* meta, cv::Size size, const cv::Rect& within) {
  for (const cv::Rect& r : above_range_rects(meta, size))
    if (!(r & within).empty()) return true;
  return false;
}

double systematic_u_at(GstBuffer* buffer, double t_c) {
  const PyrocamUncertaintyMeta* meta = pyrocam_buffer_get_uncertainty_meta(buffer);
  if (!meta) return NAN;
  pyrocam::SystematicUncertaintyTable table;
  table.coverage_factor = meta->coverage_factor;
  // A meta written by other code than pyrocam_buffer_set_uncertainty_meta may count more.
  const guint count = std::min<guint>(meta->count, PYROCAM_UNCERTAINTY_META_SAMPLES);
  table.temperature_c.assign(meta->temperature_c, meta->temperature_c + count);
  table.expanded_u_c.assign(meta->expanded_u_c, meta->expanded_u_c + count);
  return table.at(t_c);
}

}  // namespace pyrocam::gst
