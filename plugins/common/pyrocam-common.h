/* Helpers shared by the pyrocam elements: buffer <-> library image views, caps field access,
 * the object lock, buffer pools, controlled properties, and the mapping of library exceptions
 * to bus errors. */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>
#include <gst/video/video.h>

#include <initializer_list>
#include <opencv2/core.hpp>
#include <string>
#include <utility>
#include <vector>

#include "pyrocam-caps.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/mosaic.h"

namespace pyrocam::gst {

/* What a raw mosaic caps structure says (video/x-bayer or video/x-raw GRAY8/GRAY16_LE). */
struct RawFormat {
  bool bayer_caps = false;  // video/x-bayer: pattern from the caps
  std::string pattern;      // lower case: rggb.. from x-bayer caps; empty for gray video
  int bytes_per_sample = 1;
  int width = 0, height = 0;
  GstVideoInfo info;  // valid for video/x-raw only
};
/* Parses fixed raw mosaic caps; false if they are not such caps. */
bool parse_raw_caps(GstCaps* caps, RawFormat* out);
/* Bytes of one raw frame as the caps describe it (with the row padding). */
gsize raw_frame_size(const RawFormat& format);

/* The layout of a pattern name: a Bayer pattern or "5x5" (identity band map). Throws
 * InputError for anything else. */
MosaicLayout layout_for_pattern(const std::string& pattern);

/* A 5x5 layout's band map as the caps' band-map field gives it: the band indices of the cell,
 * row-major, comma-separated ("0,1,...,24"). */
std::string band_map_text(const MosaicLayout& layout);
/* The 5x5 layout of a band-map field. Throws InputError naming the text unless it holds 25
 * band indices, each 0..24 once. */
MosaicLayout layout_for_band_map(const std::string& text);

/* A mapped buffer seen as an image; unmaps when it goes. */
class MappedImage {
 public:
  MappedImage() = default;
  ~MappedImage() { reset(); }
  MappedImage(const MappedImage&) = delete;
  MappedImage& operator=(const MappedImage&) = delete;
  /* Raw mosaic buffer (read). Throws InputError if the buffer is too small. */
  void map_raw(GstBuffer* buffer, const RawFormat& format);
  /* Tightly packed float32 image of width x height x planes (read or write). Throws InputError
   * if the buffer is too small. */
  void map_float(GstBuffer* buffer, int width, int height, int planes, GstMapFlags flags);
  const cv::Mat& image() const { return image_; }
  cv::Mat& image() { return image_; }
  /* Plane `index` of a planar float image mapped with map_float. */
  cv::Mat plane(int index, int width, int height) const;
  void reset();

 private:
  GstBuffer* buffer_ = nullptr;
  GstMapInfo map_{};
  GstVideoFrame frame_{};
  bool video_frame_ = false;
  cv::Mat image_;
};

/* Holds an object's GST_OBJECT_LOCK for the scope it lives in, so that no return (or
 * exception) path can leave the object locked. */
class ObjectLock {
 public:
  explicit ObjectLock(gpointer object) : object_(GST_OBJECT(object)) { GST_OBJECT_LOCK(object_); }
  ~ObjectLock() { GST_OBJECT_UNLOCK(object_); }
  ObjectLock(const ObjectLock&) = delete;
  ObjectLock& operator=(const ObjectLock&) = delete;

 private:
  GstObject* object_;
};

/* A copy of `value` taken under the object's lock (the elements' per-buffer settings). */
template <typename T>
T locked_copy(gpointer object, const T& value) {
  ObjectLock lock(object);
  return value;
}

/* When downstream offers no buffer pool, adds one of `size`-byte buffers, so that large frames
 * are not allocated (and page-faulted) anew each time. Nothing for size 0. */
void ensure_buffer_pool(GstQuery* query, gsize size);

/* Bytes of one frame as fixed caps describe it: x-pyrocam-mosaic (one float32 plane),
 * x-pyrocam-bands (`bands` float32 planes; with the memory:PyrocamMosaic feature the mosaic's
 * one) or video/x-raw (GstVideoInfo, with its strides); 0 when the caps do not say. */
gsize frame_size_of_caps(GstCaps* caps);

/* Whether structure `index` of the caps is the band planes as their mosaic (the fused path,
 * PYROCAM_CAPS_FEATURE_MOSAIC). */
bool is_fused_bands(const GstCaps* caps, guint index = 0);

/* Whether a temperature buffer (GRAY16_LE codes, negotiated as `info`) holds a whole frame; if
 * not, posts a STREAM FORMAT error naming both sizes. GstVideoFilter answered such a buffer with
 * a CORE NOT_IMPLEMENTED warning ("please file a bug") and dropped it. */
bool temperature_frame_fits(GstBaseTransform* trans, const GstVideoInfo& info, GstBuffer* buffer);

/* GstBaseTransform::decide_allocation of the pyrocam filters, which derive from GstBaseTransform
 * directly: a pool of output frames (ensure_buffer_pool) when downstream offers none, then
 * GstBaseTransform's own choice. */
gboolean decide_allocation(GstBaseTransform* trans, GstQuery* query);

/* GstBaseTransform::before_transform of elements with GST_PARAM_CONTROLLABLE properties: brings
 * those a control binding drives to their values at the buffer's stream time (as videobalance
 * does), so that a controller changes them frame by frame. Buffers without a timestamp keep the
 * current values. */
void sync_controlled_properties(GstBaseTransform* trans, GstBuffer* buffer);

/* A rectangle of frame pixels, as the elements' region properties give it. */
struct Region {
  int x = 0, y = 0, width = 0, height = 0;
};
/* "x,y,width,height" (non-negative integers, width and height at least 1); false otherwise. */
bool parse_region(const std::string& text, Region* out);

/* Integer field of a structure when fixed, else `fallback`. */
int structure_int(const GstStructure* s, const char* field, int fallback);
/* String field of a structure, else empty. */
std::string structure_string(const GstStructure* s, const char* field);

/* Copies those of `fields` that `from` has onto `to`; absent ones are left as they are. */
void copy_fields(const GstStructure* from, GstStructure* to,
                 std::initializer_list<const char*> fields);
/* The fields that size a video frame: width, height, framerate. */
void copy_dimensions(const GstStructure* from, GstStructure* to);
/* Sets `field` to the list `list_text` serialises, e.g. PYROCAM_BAYER_FORMATS. */
void set_list_field(GstStructure* s, const char* field, const char* list_text);

/* The `frames` property of the exposure-bracket fusions (thermalfuse, mosaicfuse). */
GParamSpec* bracket_frames_param(guint default_frames);
/* The STREAM FORMAT warning of a bracket fusion that passed a frame without
 * PyrocamExposureMeta on unfused: once, when `warned` is false (it is then set). */
void warn_frame_without_exposure(GstElement* element, bool& warned);

/* A property set while the element runs that can change only in NULL or READY: a RESOURCE
 * SETTINGS warning on the bus naming the element and the property (the value stays), so that an
 * application learns it, not only the debug log. Call without the object's lock held. */
void warn_not_changeable_while_running(GstElement* element, const char* property);
/* For the elements that take a stream's codes as temperatures (thermalcolormap, thermalalarm):
 * whether `event` is a tag event whose comment says the stream holds another quantity
 * (`quantity=expanded-uncertainty`: ratiotemp output=uncertainty, or a recording of it played
 * back), whose codes would read as temperatures near -273 degC. Then a STREAM FORMAT error is
 * posted, naming the element and the quantity, and the caller drops the event and returns
 * FALSE. */
bool refuses_other_quantity(GstElement* element, GstEvent* event);
/* Whether a bracket fusion's frame came earlier than the one before it (its PTS is before
 * `last_pts`, which is then set to it): frames out of time order would be fused as if the
 * earlier were the later, so the fusion starts anew with this frame, with one STREAM FORMAT
 * warning (when `warned` is false; it is then set). Frames without a PTS are in order. */
bool frame_out_of_time_order(GstElement* element, GstBuffer* buffer, GstClockTime& last_pts,
                             bool& warned);

/* Whether saturation may hide a reading in `within` of a frame of temperature codes (CV_16U,
 * 0 = no reading): a pixel without a reading where `meta` puts saturated samples (its tiles
 * that hold any, within its rectangle, scaled from the meta's frame and widened by the reach of
 * demosaic25's kernels: 2 pixels on a frame of the mosaic's size, matched Bayer; 1 macro-pixel
 * on a smaller one, matched 5x5 cells). A saturated
 * band does not always take the reading (the likelihood fit reads a 5x5 pixel from the bands
 * that are left), and then nothing is hidden. */
bool saturation_hides_readings(const PyrocamSaturationMeta* meta, const cv::Mat& codes,
                               const cv::Rect& within);

/* Where a PyrocamAboveRangeMeta puts pixels hotter than the model's range, in pixels of a frame
 * of `size`: its tiles that hold any, each cut to the meta's rectangle and scaled from its frame
 * to `size`. Empty without a meta or with none. */
std::vector<cv::Rect> above_range_rects(const PyrocamAboveRangeMeta* meta, cv::Size size);
/* The largest group of those tiles that touch (corners too), as one rectangle in pixels of a
 * frame of `size`: where a marker goes when several spots are hotter than the range. Empty
 * without any. */
cv::Rect largest_above_range_spot(const PyrocamAboveRangeMeta* meta, cv::Size size);
/* Whether `within` meets one of them. */
bool above_range_within(const PyrocamAboveRangeMeta* meta, cv::Size size, const cv::Rect& within);

/* The expanded systematic uncertainty of a reading at t_c, degC, from the buffer's
 * PyrocamUncertaintyMeta (interpolated); NaN without one or outside its temperatures. */
double systematic_u_at(GstBuffer* buffer, double t_c);

/* How a failure is reported on the bus (STYLE.md: errors carry a domain, a user message and a
 * debug message). */
enum class ErrorKind {
  kNotFound,     // RESOURCE NOT_FOUND: a file that is not there
  kRead,         // RESOURCE READ: a file that cannot be read or parsed
  kSettings,     // RESOURCE SETTINGS: a bad property value
  kFormat,       // STREAM FORMAT: shape, size or band mismatch in the data
  kNegotiation,  // CORE NEGOTIATION: caps that cannot work
  kNumeric,      // LIBRARY FAILED: numeric or other library failure
};
/* How a camera profile that failed to load is reported: NOT_FOUND when it names a file (a path
 * or a .json name) that is not there, else READ. */
ErrorKind profile_error_kind(const std::string& name_or_path);

/* Posts an error message, once: an error the element already posted with the same user message
 * since forget_posted_errors() is logged only (GstBaseTransform tries set_caps again with caps it
 * refused, which put the same message on the bus twice or more). */
void post_error(GstElement* element, ErrorKind kind, const std::string& user,
                const std::string& debug, const char* function, int line);
/* Called in start(): a new run posts its errors again. */
void forget_posted_errors(GstElement* element);
#define PYROCAM_POST_ERROR(element, kind, user, debug) \
  ::pyrocam::gst::post_error(GST_ELEMENT(element), kind, user, debug, GST_FUNCTION, __LINE__)

/* Runs fn, which may throw; no exception leaves. An InputError is posted as `input_kind` with
 * `what` as the user message's start, any other exception as LIBRARY FAILED. Returns whether fn
 * completed. */
template <typename Fn>
bool guarded(GstElement* element, ErrorKind input_kind, const std::string& what, Fn&& fn,
             const char* function = "", int line = 0) {
  try {
    std::forward<Fn>(fn)();
    return true;
  } catch (const pyrocam::InputError& e) {
    post_error(element, input_kind, what + ": " + e.what(),
               std::string("InputError in ") + function, function, line);
  } catch (const cv::Exception& e) {
    post_error(element, ErrorKind::kNumeric, what + ": OpenCV failed",
               std::string("cv::Exception in ") + function + ": " + e.what(), function, line);
  } catch (const std::exception& e) {
    post_error(element, ErrorKind::kNumeric, what + ": " + e.what(),
               std::string("std::exception in ") + function, function, line);
  }
  return false;
}
#define PYROCAM_GUARDED(element, kind, what, ...) \
  ::pyrocam::gst::guarded(GST_ELEMENT(element), kind, what, __VA_ARGS__, GST_FUNCTION, __LINE__)

}  // namespace pyrocam::gst
