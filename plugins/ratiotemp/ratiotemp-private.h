/* ratiotemp's parts shared by its source files: the property values (ratiotemp-properties.cpp),
 * the formats (ratiotemp-caps.cpp), the statistics message (ratiotemp-stats.cpp), the
 * recording's tags (ratiotemp-tags.cpp), the element struct and its streaming state;
 * gstratiotemp.cpp has the negotiation, the estimator switching and the streaming. */
#pragma once

#include <gst/gst.h>
#include <gst/video/video.h>

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "gstratiotemp.h"
#include "pyrocam-common.h"
#include "pyrocam/core/mosaic.h"
#include "pyrocam/runtime/blur_bias.h"
#include "pyrocam/runtime/curvature_check.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/scaled_brightness.h"
#include "pyrocam/runtime/snapshot_brightness.h"
#include "pyrocam/runtime/uncertainty.h"

GST_DEBUG_CATEGORY_EXTERN(gst_ratio_temp_debug);

namespace pyrocam::gst::ratiotemp {

constexpr GstRatioTempMethod DEFAULT_METHOD = GST_RATIO_TEMP_METHOD_AUTO;
constexpr GstRatioTempOutput DEFAULT_OUTPUT = GST_RATIO_TEMP_OUTPUT_TEMPERATURE;
constexpr guint64 DEFAULT_STATS_INTERVAL = GST_SECOND;
constexpr gboolean DEFAULT_ALLOW_PARTIAL = FALSE;
constexpr GstRatioTempPartial DEFAULT_PARTIAL_BANDS = GST_RATIO_TEMP_PARTIAL_SAFE;
constexpr double DEFAULT_MISFIT_PROBABILITY = 0.0;
constexpr gboolean DEFAULT_BLUR_CORRECTION = FALSE;
constexpr guint DEFAULT_BRIGHTNESS_RADIUS = 0;  // off: ratio readings
constexpr guint MAX_BRIGHTNESS_RADIUS = 8;      // pyrocam::ScaledBrightness::kMaxWindowRadius
constexpr double MAX_MISFIT_PROBABILITY = 0.5;
constexpr guint DEFAULT_PEAK_WINDOW = 5;              // pyrocam::kDefaultPeakWindow
constexpr guint MAX_PEAK_WINDOW = 255;                // pyrocam::kMaxPeakWindow
constexpr double DEFAULT_E_SLOPE = 0.0;               // %/100 nm: grey
constexpr double MAX_E_SLOPE = 50.0;                  // pyrocam::kMaxEmissivitySlope, in %/100 nm
constexpr double DEFAULT_E_SLOPE_UNCERTAINTY = -1.0;  // the model's

/* Property values; read and written under GST_OBJECT_LOCK, copied once per buffer. */
struct Settings {
  std::string model;
  std::string refused;  // a property value refused (even peak-window, NaN e-slope): start fails
  GstRatioTempMethod method = DEFAULT_METHOD;
  GstRatioTempOutput output = DEFAULT_OUTPUT;
  guint64 stats_interval = DEFAULT_STATS_INTERVAL;
  gboolean allow_partial = DEFAULT_ALLOW_PARTIAL;  // true: as partial_bands any
  GstRatioTempPartial partial_bands = DEFAULT_PARTIAL_BANDS;
  double misfit_probability = DEFAULT_MISFIT_PROBABILITY;
  gboolean blur_correction = DEFAULT_BLUR_CORRECTION;
  guint brightness_radius = DEFAULT_BRIGHTNESS_RADIUS;  // Bayer cells; 0 = ratio readings
  std::string region_text;                              // as set; empty: no region
  bool region_valid = true;  // region_text is empty or parsed into region
  Region region;
  guint region_serial = 0;                  // bumped by every change of region
  guint peak_window = DEFAULT_PEAK_WINDOW;  // odd, or 0 = no peak
  bool peak_window_set = false;             // set by the user: warn when it does not fit
  double e_slope = DEFAULT_E_SLOPE;         // %/100 nm, never NaN
  double e_slope_uncertainty = DEFAULT_E_SLOPE_UNCERTAINTY;  // %/100 nm; negative: the model's
  bool region_tracks_peak = false;  // the region centred on the frame's peak
  std::string table_cache;          // folder; "" = none
  bool table_cache_set = false;     // else the user's cache folder
};

/* Whether the statistics of a frame (or region) of this size carry a peak. */
inline bool peak_fits(const Settings& settings, int width, int height) {
  const int w = static_cast<int>(settings.peak_window);
  return w > 0 && w <= width && w <= height;
}

/* Streaming state: the model and its estimators are built in start(), the format in set_caps(),
 * all dropped in stop(). The estimators share the model. */
struct State {
  std::shared_ptr<const pyrocam::ThermalModel> model;
  std::string model_path;
  std::unique_ptr<pyrocam::EstimatorSelector> estimators;  // builds and keeps them per method
  pyrocam::Method method = pyrocam::Method::kMlp;          // in use
  GstRatioTempMethod method_request = DEFAULT_METHOD;      // the property value it came from
  GstRatioTempMethod refused_request = DEFAULT_METHOD;     // last property value warned about
  bool refused = false;
  bool configured = false;
  int width = 0, height = 0, bands = 0;
  GstVideoInfo out_info{};
  std::vector<cv::Mat> planes;  // headers onto the input buffer
  // The fused path (demosaic25 linked to this element): the input is the planes' mosaic,
  // demosaicked here a strip at a time with demosaic25's settings from the caps.
  bool fused = false;
  std::string demosaic;  // how the planes are made: the caps' field (the fused path's too)
  pyrocam::MosaicLayout mosaic_layout;
  float no_signal_dn = 0;
  // Plain planes: what their demosaicking did to the band values' noise (the caps' demosaic
  // and pattern fields; none without them), for the uncertainty.
  pyrocam::DemosaicNoise demosaic_noise;
  double saturation_level_dn = -1;                      // darksub's, from the caps; -1: the model's
  std::optional<pyrocam::CurvatureCheck> curvature;     // on the fused path, for its phase
  std::optional<pyrocam::BlurBiasCorrection> blur;      // on the fused path (matched demosaicking)
  bool blur_warned = false;                             // blur-correction asked for off that path
  std::optional<pyrocam::ScaledBrightness> brightness;  // on the fused path (Bayer mosaics)
  bool brightness_warned = false;                       // brightness-radius asked for off that path
  // Plain planes of a snapshot model: brightness-radius reads them (no fused path needed).
  bool snapshot = false;
  std::optional<pyrocam::SnapshotBrightness> snapshot_brightness;
  cv::Mat temperature_c, uncertainty_c;
  cv::Mat saturated_mask;          // on frames with statistics: where light saturated a band
  bool saturation_warned = false;  // since the last statistics without saturated pixels
  // The last frame's pixels hotter than the model's range (pyrocam::above_range_spots), and
  // whether they were warned about (since the last statistics without any).
  std::vector<cv::Point> above_range;
  pyrocam::SystematicUncertaintyTable systematic;  // of the last frame's estimator
  bool above_range_warned = false;
  bool fold_warned = false;  // warn_when_network_folds ran for this model
  GstClockTime last_stats = GST_CLOCK_TIME_NONE;
  guint64 frames = 0;  // since start or the last flush
  guint region_serial_seen = 0;
  std::string peak_warned;       // the last peak-window/frame misfit warned about
  std::string region_warned;     // the last region/frame size seen (warned if outside)
  bool tracking_warned = false;  // region-tracks-peak without a region
  // The readings' fit audit (warn_when_readings_misfit), accumulated until a verdict.
  std::size_t fit_checked = 0, fit_misfit = 0, fit_too_bright = 0;
  bool fit_warned = false, too_bright_warned = false;  // since start
  struct TagListUnref {
    void operator()(GstTagList* t) const { gst_tag_list_unref(t); }
  };
  std::unique_ptr<GstTagList, TagListUnref> upstream_tags;  // the last stream tags from upstream
  std::string pushed_comment;  // the recording comment last pushed downstream; empty: none yet
};

/* The steps after the per-pixel estimate that this frame takes (null: not taken). */
struct Corrections {
  const pyrocam::CurvatureCheck* curvature = nullptr;  // the fused path, always
  const pyrocam::BlurBiasCorrection* blur = nullptr;
  pyrocam::ScaledBrightness* brightness = nullptr;
  pyrocam::SnapshotBrightness* snapshot_brightness = nullptr;  // on a snapshot model's planes
  const std::vector<cv::Mat>* planes = nullptr;                // the frame's, for that step
};
/* The settings' steps that the stream allows: both need the fused path's mosaic. Each is built
 * the first time it is asked for there (and the brightness step again when its radius changes);
 * throws InputError (from the library) if it cannot be. Warns once where the settings ask for a
 * step the stream cannot take. */
Corrections corrections_for_frame(GstRatioTemp* self, const Settings& settings, State& st);
/* Drops the steps built for the last stream (its phase and path). */
void reset_corrections(State& st);
/* The frame's codes, straight from the planes or the fused mosaic, with the corrections; on
 * the fused path the curvature check runs inside the estimate, on each run of codes while its
 * rows are in the cache. */
void estimate_codes(pyrocam::PlaneEstimator& estimator, const State& st,
                    const pyrocam::PlaneEstimator::MatchedMosaic& mosaic, const Corrections& c,
                    cv::Mat& codes);
/* The curvature check, the blur correction, then the brightness readings, on codes or on degC
 * (fused mosaic). */
void correct_codes(const Corrections& c, const cv::Mat& mosaic, cv::Mat& codes);
void correct_temperature(const Corrections& c, const cv::Mat& mosaic, cv::Mat& temperature_c);

/* Where light saturated a band of the input frame (CV_8U, 1 there): from the band planes, or on
 * the fused path from the mosaic, each saturated sample taking the matched kernels' footprint. */
cv::Mat saturated_mask(const State& st, const cv::Mat& fused_mosaic);
/* The "pyrocam-temperature-stats" element message's structure for a frame's temperatures
 * (CV_32F degC, NaN = no reading) at `pts`, with the settings' region when it is valid, and the
 * pixels without a reading inside `saturated` (a CV_8U mask; empty: no such fields) and the
 * pixels hotter than the model's range (`above_range`, points of the frame). Throws
 * (from the library) before it allocates anything. The peak fields are there only where
 * peak_fits(). */
GstStructure* stats_structure(const cv::Mat& temperature_c, const cv::Mat& saturated,
                              const std::vector<cv::Point>& above_range, const Settings& settings,
                              const GstSegment* segment, GstClockTime pts, Method method,
                              const pyrocam::SystematicUncertaintyTable* systematic = nullptr);
/* Posts that structure as an element message, warning once per window and frame size when the
 * user's peak-window does not fit (st.peak_warned: the last misfit warned about), and once when
 * saturated pixels, or pixels hotter than the model's range, appear (again after statistics
 * without any). */
void post_stats(GstRatioTemp* self, const Settings& settings, State& st, GstClockTime pts);

/* The pixels the frame's estimate found hotter than the model's range, kept in st.above_range
 * for the statistics (none on a GAP frame) and attached to `outbuf` as a PyrocamAboveRangeMeta
 * (on every frame, 0 pixels when none); the readings' systematic uncertainty, kept in
 * st.systematic and, on temperature frames, attached as a PyrocamUncertaintyMeta. */
void attach_frame_metas(GstBuffer* outbuf, const Settings& settings, State& st, bool gap);
/* Readings checked against the model's band spectra before a verdict (PlaneEstimator::
 * take_fit_audit: one in every 16th row; a 5x5 frame of 2045x1085 filled by the body
 * gives about 14, a small body's frames add up). With a few percent of a scene's readings misfit
 * (edges, reflections), more than half of 32 is a chance below 1e-12 (binomial). */
inline constexpr std::size_t kFitAuditReadings = 32;
/* Adds the frame's fit audit; once enough readings were checked, warns (once since start) when
 * most of them do not fit the model's band spectra: a mosaic read with the wrong phase or
 * layout, or a model of another camera, whose readings look right and are not. */
void warn_when_readings_misfit(GstRatioTemp* self, State& st,
                               const pyrocam::PlaneEstimator& estimator);

/* What a recording of the output says about itself (ratiotemp-tags.cpp): pushed downstream as
 * the stream's title and comment before the first frame and again when it changes. */
struct RecordingInfo {
  std::string model_file, fingerprint, profile, method;
  bool uncertainty = false;  // output=uncertainty
  double e_slope = 0;        // %/100 nm
  // The other settings that change the readings, so that a raw recording is measured again
  // with them (pyrocam-calib measure --recording): partial-bands (off, safe, any; allow-partial
  // as any), misfit-probability, blur-correction, brightness-radius, and demosaic25's method.
  std::string partial_bands = "safe";
  double misfit_probability = 0;
  bool blur_correction = false;
  unsigned brightness_radius = 0;
  std::string demosaic;     // how the planes were made (the caps' demosaic field); empty: unknown
  double exposure_us = -1;  // from an upstream capturing-shutter-speed tag; negative: unknown
};
/* The comment: pyrocam::kTemperatureRecordingMark, then its fields as "; key=value". */
std::string recording_title(bool uncertainty);
std::string recording_comment(const RecordingInfo& info);
/* Upstream's stream tags (may be null) with our title and comment in place of theirs. */
GstTagList* recording_tags(const RecordingInfo& info, const GstTagList* upstream);
/* The exposure in a capturing-shutter-speed tag, in microseconds; negative when absent. */
double exposure_us_of(const GstTagList* tags);
/* Pushes the stream's tags downstream when what they say has changed (the first frame, a new
 * method or e-slope, new upstream tags), before the frame they describe; pushed_comment: the
 * comment last pushed. */
void push_recording_tags(GstRatioTemp* self, const RecordingInfo& info, const GstTagList* upstream,
                         std::string& pushed_comment);

/* Once a model: where the method in use (the network or its table) reads graybodies hotter than
 * the model's range as temperatures inside it (pyrocam::fold_above_range), a warning saying so,
 * as such surfaces then read wrong instead of not at all. */
void warn_when_network_folds(GstRatioTemp* self, State& st);
/* push_recording_tags with what the element's settings and state say. */
void push_stream_tags(GstRatioTemp* self, const Settings& settings, State& st);
/* The library's request for a method property value (ratiotemp-properties.cpp). */
pyrocam::MethodRequest to_library(GstRatioTempMethod method);

/* Formats (ratiotemp-caps.cpp): the layout caps field a model expects ("bayer" or 5x5), the
 * band values' noise the caps' demosaicking leaves, the
 * caps' transforms (any band count and layout: set_caps checks them against the model and names
 * both in its error), and an output buffer mapped as a GRAY16_LE frame (rows at the video
 * info's stride; throws InputError when it cannot be mapped; unmaps when it goes). */
const char* layout_name(const pyrocam::ThermalModel& model);
/* What in the sink caps does not fit the model (band count and layout, saturation level, which
 * also tells a stream deeper than the model's camera, 5x5 band order): a user message and a
 * debug line, empty when all fit. */
struct Mismatch {
  std::string message, debug;
};
Mismatch model_mismatch(const GstStructure* in, const pyrocam::ThermalModel& model,
                        const std::string& model_path);
/* What the demosaicking the plain band caps name (demosaic, pattern) did to the band values'
 * noise; none where they do not say (a warning where they say something unknown). */
pyrocam::DemosaicNoise demosaic_noise_of(GstElement* element, const GstStructure* caps,
                                         const pyrocam::ThermalModel& model);
GstCaps* transform_caps(GstBaseTransform* trans, GstPadDirection direction, GstCaps* caps,
                        GstCaps* filter);
gboolean transform_size(GstBaseTransform* trans, GstPadDirection direction, GstCaps* caps,
                        gsize size, GstCaps* othercaps, gsize* othersize);
struct MappedFrame {
  MappedFrame(GstBuffer* buffer, GstVideoInfo* info);
  ~MappedFrame();
  MappedFrame(const MappedFrame&) = delete;
  MappedFrame& operator=(const MappedFrame&) = delete;
  GstVideoFrame frame;
  cv::Mat image;
};

/* The lookup table's files (ratiotemp-tables.cpp): the prebuilt table beside the model and the
 * table cache, set on the selector before it builds the table; then, when it built one
 * (`lut_built`), what they gave, as info, or as a warning on the bus for a prebuilt table that
 * could not be used, or, when the table reads the frames (`lut_used`), for a cold start (no
 * prebuilt table, nothing cached; `cache_off`: table-cache="", no cache at all). */
void set_table_files(pyrocam::EstimatorSelector& estimators, const pyrocam::ThermalModel& model,
                     const Settings& settings);
void report_table_files(GstRatioTemp* self, const pyrocam::EstimatorSelector& estimators,
                        const std::string& model_path, bool lut_built, bool lut_used,
                        bool cache_off);

/* GObject properties: installed by class_init, read and written under the object lock. */
void install_properties(GObjectClass* klass);
void set_property(GObject* object, guint prop_id, const GValue* value, GParamSpec* pspec);
void get_property(GObject* object, guint prop_id, GValue* value, GParamSpec* pspec);

}  // namespace pyrocam::gst::ratiotemp

struct _GstRatioTemp {
  GstBaseTransform parent;
  pyrocam::gst::ratiotemp::Settings* settings;
  pyrocam::gst::ratiotemp::State* state;
};
