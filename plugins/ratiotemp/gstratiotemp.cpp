/**
 * SECTION:element-ratiotemp
 * @title: ratiotemp
 *
 * Turns band planes (video/x-pyrocam-bands from demosaic25, see pyrocam-caps.h) into a temperature
 * image with the thermal model that `pyrocam-calib calibrate` wrote (#GstRatioTemp:model). The
 * output is video/x-raw, format=GRAY16_LE, of the same width, height and framerate: one value per
 * pixel in units of 0.1 K (14732 = 1473.2 K = 1200.05 degC) and 0 for "no reading", so
 * temperatures can be recorded losslessly (e.g. avenc_ffv1 ! matroskamux). Linked to demosaic25
 * demosaicking a Bayer mosaic with method matched, it asks for the bands as their mosaic
 * (video/x-pyrocam-bands with the memory:PyrocamMosaic feature, the fused path) and demosaics it
 * here, 16 rows at a time while they are in the cache, skipping columns without light: the planes'
 * readings (but for the dim-edge check's ring, read from the mosaic, and the curvature check)
 * without the float planes crossing memory.
 *
 * A pixel has no reading (0) when the estimate falls outside the model's temperature range, or
 * when a band is saturated (+INF), without a reading (NaN) or below the model's dim threshold
 * (profile `inference_dim_dn`, 20 DN for the shipped profiles) and #GstRatioTemp:partial-bands
 * does not read it from the rest. With partial-bands=safe (the default) the likelihood fit reads
 * such a pixel from the bands left when two of them have a ratio monotonic over the model's
 * whole range (decided from the model's locus when the element starts) and the noise alone
 * leaves the reading within 50 degC at 1500 degC, a limit growing as the square of the absolute
 * temperature (82 degC at 2000; one standard deviation, from the fit's chi2 curvature): two
 * bands whose ratio turns over pin such fits near the turning point, and a few bands near the
 * noise read hundreds of degrees off; readings that look right and are not. The
 * shipped 5x5 camera has 198 such pairs of 300, so a pixel with a few dim bands reads; the
 * shipped colour camera has none (each of its ratios turns over somewhere in 500..3500 degC),
 * so its pixels still need all three bands. partial-bands=any (or the older
 * #GstRatioTemp:allow-partial) reads from any two; the fit gives no reading when they fit two
 * temperatures about equally well. With the lut or mlp method the pixels they cannot read go to
 * the likelihood fit under the same rule. Where every band must read (the colour camera, or
 * partial-bands=off), a band within 6 standard deviations of its noise above the dim threshold
 * reads only where a ring of its samples around the pixel, outside its demosaicking footprint,
 * has a half whose mean is 2 of them above it: the pixel's own noise does not decide, so a
 * surface at the threshold reads on none of its pixels rather than on those its noise lifted
 * (which read tens of degrees off). A band value near the saturation level is judged the same
 * way, on every path: it counts as saturated where such a ring's half lies within 2 standard
 * deviations of the level (saturated samples counted at it), so that the pixels that keep the
 * band are not those whose noise pulled it down (the sink caps' saturation-level; frames whose
 * PyrocamSaturationMeta counts no saturated sample are not checked).
 *
 * On the fused path a pixel whose field curves too fast for the kernels (a hot spot a few pixels
 * across: half its temperature's Laplacian over 100 degC) has no reading. blur-correction (default
 * off; fused path) subtracts their bias on steep gradients (+180 degC at 150 degC/px, 1400 degC).
 *
 * With #GstRatioTemp:brightness-radius r (default 0, off; on a Bayer mosaic the fused path only)
 * each pixel reads from its own sample: its band's scale (exposure, emissivity, calibration) is
 * the mean over a (4r + 1)-pixel square window of what the ratio readings imply, and the sample
 * gives the temperature at that pixel: the ratio's mean and mask with the noise of one sample,
 * and a melt pool's peak not aliased by the Bayer pattern. On a snapshot (5x5) model's planes
 * each cell reads from all its bands with their scales' means over (2r + 1) x (2r + 1) cells:
 * a third of the fit's spread on plates. It assumes one emissivity over the window; near an
 * emissivity step it reads wrong where the ratio reads right.
 *
 * With #GstRatioTemp:misfit-probability above 0 (e.g. 1e-6; default 0, off) every reading goes
 * through a band-consistency check: the band signals must be those of a graybody within 1 % of
 * the estimated (absolute) temperature, within the sensor noise model plus 2 % of each signal
 * for the model's own error (chi-squared with bands - 2 degrees of freedom: 1 for colour, 23
 * for 5x5); the property is the chance that a true graybody pixel is dropped. Pixels that fail
 * have no reading (0). It drops pixels whose bands come from different temperatures only when
 * the mix leaves the Planckian locus: a colour camera's mixed pixels at a sharp edge often land
 * on the locus at another temperature (a simulated 735 degC plate still reads up to 2294 degC
 * at its edge with the check on), so it is no edge detector for colour cameras.
 *
 * #GstRatioTemp:method chooses the per-pixel estimator:
 * - mlp: the paper's network on the normalised band ratios, the reference. Far too slow for
 *   live video at 100 000 pixels and more; use it for checks and offline work.
 * - lut: a 2-D lookup table of the same network over the colour camera's two ratios (built
 *   when the element starts); ratios off the table fall back to the network. Colour models
 *   only: with a 5x5 model it is refused (RESOURCE SETTINGS). The table is trusted only after a
 *   check against the network on the model's own locus (noise-free graybody signals every
 *   1 degC, brightest band at 150 DN): where it differs by more than 1 degC anywhere, or reads
 *   where the network does not (or the reverse) at more than 1 % of the samples, lut is
 *   refused (RESOURCE SETTINGS, the message says by how much and where).
 * - likelihood: a maximum-likelihood fit of temperature and an unknown scale to the band
 *   signals along the model's Planckian locus, weighted by the sensor noise model.
 * - auto (default): lut for models with two ratios (colour cameras) when the table passes its
 *   check, else likelihood (with a warning on the bus saying why the table was not used).
 * The method can change while playing; the new estimator is built (and checked) in the
 * streaming thread before the next frame. A method that cannot be used is refused with a
 * warning on the bus and the previous one stays.
 *
 * #GstRatioTemp:e-slope (percent per 100 nm, -50 to 50, default 0 = grey; changeable while
 * playing) reads a surface whose emissivity is 1 + slope (wavelength - middle of the filter pass
 * band): ratios cancel a grey emissivity, not a slope. Each band is divided by its factor at the
 * temperature read and read again until the reading settles (2 to 12 estimates per pixel).
 * The emissivity term of the uncertainty is then |dT/d slope| at that slope times
 * #GstRatioTemp:e-slope-uncertainty (default: the model's, 1 %/100 nm).
 *
 * #GstRatioTemp:output uncertainty outputs the expanded uncertainty (k = 2, GUM: signal noise
 * propagated per pixel plus the model's calibration and emissivity terms) instead of the
 * temperature, in the same encoding: 0.1 K per code (a temperature difference, no offset),
 * 0 = no reading, at least 1 where there is a reading. To get both, split the bands with tee
 * into two ratiotemp elements (see below). The uncertainty costs 2 x bands extra estimates
 * per pixel. Frames taken at an analogue gain (the gain_db of their PyrocamExposureMeta, which
 * pyrocamsrc attaches; 0 dB without one) carry that much more shot noise per DN: the noise model
 * behind the likelihood weights, the band-consistency check and the uncertainty follows each
 * frame's gain. Readings by ratio do not depend on it.
 *
 * Every #GstRatioTemp:stats-interval nanoseconds of buffer timestamps (0 = off) the element
 * posts an element message "pyrocam-temperature-stats" with statistics of the frame's
 * temperatures (always the temperatures, whatever the output), computed on the unquantised
 * estimates:
 * - timestamp, stream-time, running-time (guint64, ns): of the frame (GST_CLOCK_TIME_NONE when
 *   unknown);
 * - method (string): the estimator in use (mlp, lut or likelihood);
 * - width, height (int): the frame's size;
 * - pixels, valid (guint64): pixels of the frame, pixels with a reading;
 * - valid-fraction (double): valid / pixels;
 * - min-c, max-c, mean-c, median-c (double, degC): of the pixels with a reading; absent when
 *   there are none. Prefer the median for a region's temperature: noise biases the mean of
 *   per-pixel temperatures upward;
 * - saturated (guint64): pixels without a reading where light saturated a band (a band +INF or
 *   NaN; fused: within the matched kernels' reach of such a sample). Non-zero: the scene's
 *   hottest part may be there, and peak-c and max-c are lower bounds; a warning says so the
 *   first time, and again after statistics without any;
 * - above-range (guint64): pixels without a reading because they are hotter than the model's
 *   range (the likelihood fit along the model's locus extended to 6000 degC reads them above
 *   its end by 3 standard deviations of their noise, their bands fit a graybody there, and so
 *   do most of their 3x3 neighbours; at most 65536 pixels are checked a frame). Non-zero: the
 * scene's hottest part is there, peak-c and max-c are lower bounds, and a warning says so as for
 * saturated. Every output frame carries them as a PyrocamAboveRangeMeta, which thermalcolormap's
 * peak readout and thermalalarm read;
 * - peak-c (double, degC), peak-x, peak-y (int, output pixels): the object's peak, robust to
 *   the wild mixed pixels at sharp edges that make max-c: the largest median of the
 *   #GstRatioTemp:peak-window square windows with at least half their pixels read, and that
 *   window's centre; absent when no window qualifies, with peak-window 0, or when the window
 *   does not fit in the frame (a warning once if peak-window was set). About 75 ms of one
 *   core per 2048x2048 frame at window 5, on the frames that post statistics only;
 * - peak-u-sys-c (double, degC): k times the systematic uncertainty of a reading at peak-c (no
 *   noise), from the table every temperature frame carries as a PyrocamUncertaintyMeta;
 * - with #GstRatioTemp:region set: region-x, region-y, region-width, region-height (int, the
 *   region clipped to the frame) and region-pixels, region-valid, region-valid-fraction,
 *   region-min-c, region-max-c, region-mean-c, region-median-c, region-saturated,
 *   region-above-range, region-peak-c, -x, -y, -u-sys-c, as above for the region
 * (windows inside the region; the position still in frame pixels; no peak for a region narrower
 * than the window).
 *
 * A message is posted for the first frame, then for the first frame whose timestamp is at
 * least the interval after the last posted one (after a flush or a new segment, the next
 * frame). Frames without a timestamp count by the framerate; without either, every frame
 * posts.
 *
 * Recordings describe themselves: before the first frame, and again when a setting that changes
 * the readings or upstream's tags change, the element pushes stream tags downstream: title (the
 * encoding in words) and comment "pyrocam-recording; quantity=temperature; unit=0.1 K;
 * no-reading=0; model=FILE; model-fingerprint=HEX; profile=NAME; method=lut; e-slope=0 %/100 nm;
 * partial-bands=safe; misfit-probability=0; blur-correction=off; brightness-radius=0;
 * demosaic=matched" (demosaic25's method, where the caps say it; quantity=expanded-uncertainty
 * with output=uncertainty; "; exposure=N us" when upstream tags carry capturing-shutter-speed),
 * with which `pyrocam-calib measure --recording` measures a raw recording again. The fingerprint
 * is the model file's checksum_fnv1a64. Matroska keeps the title and comment (it drops most
 * other tags), in every splitmuxsink segment.
 *
 * Errors: no model set: RESOURCE SETTINGS; a missing model file: RESOURCE NOT_FOUND; a
 * truncated, edited, unparsable or other-version model: RESOURCE READ (the message names the
 * file); input whose band count or layout (bayer, 5x5) differs from the model's: CORE
 * NEGOTIATION naming both; an invalid region at start: RESOURCE SETTINGS (while playing: a
 * warning, and no region statistics until a valid one is set).
 *
 * The 5x5 bands must be in the model's band order: bands whose band-map caps field (set by
 * demosaic25) differs from the model profile's band map are refused (CORE NEGOTIATION). A
 * camera that does not say its band map gets row * 5 + column unless demosaic25 is given the
 * camera's profile.
 *
 * ## Example launch lines
 * |[
 * gst-launch-1.0 pyrocamsrc ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=cam.json ! \
 *     thermalcolormap scale-bar=true ! videoconvert ! autovideosink
 * ]| Live colour camera, region statistics every 0.5 s (gst-launch-1.0 -m prints them):
 * |[
 * gst-launch-1.0 -m aravissrc ! video/x-bayer,format=rggb ! darksub location=dark.pgm ! \
 *     demosaic25 ! ratiotemp model=cam.json region=100,80,64,48 stats-interval=500000000 ! \
 *     thermalcolormap ! videoconvert ! autovideosink
 * ]| Temperature and uncertainty recorded losslessly side by side:
 * |[
 * gst-launch-1.0 pyrocamsrc num-buffers=100 ! darksub dark-level=50 ! demosaic25 ! tee name=b \
 *     b. ! queue ! ratiotemp model=cam.json ! avenc_ffv1 ! matroskamux ! filesink location=t.mkv \
 *     b. ! queue ! ratiotemp model=cam.json output=uncertainty ! avenc_ffv1 ! matroskamux ! \
 *     filesink location=u.mkv
 * ]|
 */
/* The negotiation, the estimator switching and the streaming; the properties
 * (ratiotemp-properties.cpp), the caps' transforms and the output frame (ratiotemp-caps.cpp)
 * and the statistics message (ratiotemp-stats.cpp) are beside it. */
#include "gstratiotemp.h"

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/runtime/region_stats.h"
#include "ratiotemp-private.h"

GST_DEBUG_CATEGORY(gst_ratio_temp_debug);
#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pg = pyrocam::gst;
namespace rt = pyrocam::gst::ratiotemp;
using rt::Settings;

using rt::State;

G_DEFINE_TYPE(GstRatioTemp, gst_ratio_temp, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(ratiotemp, "ratiotemp", GST_RANK_NONE, GST_TYPE_RATIO_TEMP);

static GstStaticPadTemplate sink_template =
    GST_STATIC_PAD_TEMPLATE("sink", GST_PAD_SINK, GST_PAD_ALWAYS,
                            GST_STATIC_CAPS(PYROCAM_FUSED_BANDS_CAPS "; " PYROCAM_BANDS_CAPS));
static GstStaticPadTemplate src_template = GST_STATIC_PAD_TEMPLATE(
    "src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_TEMPERATURE_CAPS));

static Settings copy_settings(GstRatioTemp* self) { return pg::locked_copy(self, *self->settings); }

static void reset_state(GstRatioTemp* self) {
  delete self->state;  // estimators first, then the model
  self->state = new State();
}

static gboolean gst_ratio_temp_set_caps(GstBaseTransform* trans, GstCaps* incaps,
                                        GstCaps* outcaps) {
  GstRatioTemp* self = GST_RATIO_TEMP(trans);
  State& st = *self->state;
  st.configured = false;
  if (!st.model) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "No thermal model loaded",
                       "set_caps called before start");
    return FALSE;
  }
  const GstStructure* in = gst_caps_get_structure(incaps, 0);
  const char* layout = gst_structure_get_string(in, "layout");
  st.width = pg::structure_int(in, "width", 0);
  st.height = pg::structure_int(in, "height", 0);
  st.bands = pg::structure_int(in, "bands", 0);
  if (!gst_video_info_from_caps(&st.out_info, outcaps) ||
      GST_VIDEO_INFO_WIDTH(&st.out_info) != st.width ||
      GST_VIDEO_INFO_HEIGHT(&st.out_info) != st.height || !layout || st.width < 1 ||
      st.height < 1) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "Unsupported band or output format",
                       "cannot parse the caps, or their sizes differ");
    return FALSE;
  }
  const pyrocam::ThermalModel& model = *st.model;
  const rt::Mismatch mismatch = rt::model_mismatch(in, model, st.model_path);
  if (!mismatch.message.empty()) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, mismatch.message, mismatch.debug);
    return FALSE;
  }
  st.planes.assign(static_cast<std::size_t>(st.bands), cv::Mat());
  st.fused = pg::is_fused_bands(incaps);
  st.snapshot = !st.fused && model.profile().mosaic.kind == pyrocam::MosaicLayout::Kind::kSnapshot;
  rt::reset_corrections(st);  // made again for this stream
  if (st.fused &&
      !PYROCAM_GUARDED(self, pg::ErrorKind::kNegotiation, "Unsupported band format", [&] {
        const char* pattern = gst_structure_get_string(in, "pattern");
        double level = NAN;
        gst_structure_get_double(in, PYROCAM_FIELD_NO_SIGNAL_LEVEL, &level);
        if (!pattern || !std::isfinite(level))
          throw pyrocam::InputError("fused bands (" PYROCAM_CAPS_FEATURE_MOSAIC
                                    ") need a pattern and a no-signal-level");
        st.mosaic_layout = pg::layout_for_pattern(pattern);
        st.no_signal_dn = static_cast<float>(level);
      }))
    return FALSE;
  st.demosaic_noise =
      st.fused ? pyrocam::DemosaicNoise{} : rt::demosaic_noise_of(GST_ELEMENT(self), in, model);
  st.demosaic = pg::structure_string(in, PYROCAM_FIELD_DEMOSAIC);  // fused caps have it too
  st.saturation_level_dn = pg::structure_int(in, PYROCAM_FIELD_SATURATION_LEVEL, -1);
  st.configured = true;
  GST_INFO_OBJECT(self, "%d bands of %dx%d (%s) -> GRAY16_LE%s", st.bands, st.width, st.height,
                  layout, st.fused ? " (fused: demosaicked here, a strip at a time)" : "");
  return TRUE;
}

static gboolean gst_ratio_temp_start(GstBaseTransform* trans) {
  pg::forget_posted_errors(GST_ELEMENT(trans));
  GstRatioTemp* self = GST_RATIO_TEMP(trans);
  const Settings settings = copy_settings(self);
  reset_state(self);
  State& st = *self->state;
  if (settings.model.empty()) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "No thermal model: set model to the file written by pyrocam-calib "
                       "calibrate",
                       "the model property is empty");
    return FALSE;
  }
  std::error_code ec;
  if (!std::filesystem::is_regular_file(settings.model, ec)) {
    const bool folder = std::filesystem::is_directory(settings.model, ec);
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNotFound,
                       "Thermal model file " + settings.model +
                           (folder ? " is a folder, not a model file" : " not found"),
                       "model does not name a regular file");
    return FALSE;
  }
  if (!settings.refused.empty()) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings, settings.refused,
                       "a property value was refused");
    return FALSE;
  }
  if (!settings.region_valid) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "region '" + settings.region_text +
                           "' is not x,y,width,height (non-negative integers, width and height "
                           "at least 1)",
                       "the region property did not parse");
    return FALSE;
  }
  bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kRead, "Could not read the thermal model", [&] {
    st.model = std::make_shared<const pyrocam::ThermalModel>(pyrocam::load_model(settings.model));
  });
  if (!ok) return FALSE;
  st.model_path = settings.model;
  st.estimators = std::make_unique<pyrocam::EstimatorSelector>(st.model);
  rt::set_table_files(*st.estimators, *st.model, settings);
  const pyrocam::EstimatorSelector::Choice choice =
      st.estimators->select(rt::to_library(settings.method));
  st.method = choice.method;
  if (!choice.problem.empty()) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings,
                       "Method " + pyrocam::method_name(st.method) + " cannot be used with model " +
                           settings.model + ": " + choice.problem,
                       "estimator construction or its check failed in start");
    return FALSE;
  }
  const bool lut = st.method == pyrocam::Method::kLut;
  rt::report_table_files(self, *st.estimators, settings.model, lut || !choice.fallback.empty(), lut,
                         settings.table_cache_set && settings.table_cache.empty());
  if (!choice.fallback.empty())
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("method auto uses likelihood, not lut, for model %s: %s",
                         settings.model.c_str(), choice.fallback.c_str()),
                        ("lookup table refused in start"));
  rt::warn_when_network_folds(self, st);
  st.method_request = settings.method;
  st.region_serial_seen = settings.region_serial;
  st.estimators->estimator(st.method).take_fit_audit();  // its check's tables, on their thread
  GST_INFO_OBJECT(self, "model %s (%s, %d bands, %g..%g degC), method %s", settings.model.c_str(),
                  st.model->profile().name.c_str(), st.model->profile().band_count(),
                  st.model->min_temperature_c, st.model->max_temperature_c,
                  pyrocam::method_name(st.method).c_str());
  return TRUE;
}

static gboolean gst_ratio_temp_stop(GstBaseTransform* trans) {
  GstRatioTemp* self = GST_RATIO_TEMP(trans);
  if (self->state->estimators) {
    /* The next run of this model starts with the blocks this one filled. */
    try {
      const std::size_t saved = self->state->estimators->save_table_cache();
      if (saved > 0) GST_INFO_OBJECT(self, "%zu table blocks kept in the cache", saved);
    } catch (const std::exception& e) {
      GST_WARNING_OBJECT(self, "table cache not written: %s", e.what());
    }
  }
  reset_state(self);
  return TRUE;
}

static gboolean gst_ratio_temp_sink_event(GstBaseTransform* trans, GstEvent* event) {
  GstRatioTemp* self = GST_RATIO_TEMP(trans);
  if (GST_EVENT_TYPE(event) == GST_EVENT_TAG) {
    /* Upstream's stream tags go out merged into ours before the next frame: a second stream tag
     * event would replace ours downstream. */
    GstTagList* tags = nullptr;
    gst_event_parse_tag(event, &tags);
    if (gst_tag_list_get_scope(tags) == GST_TAG_SCOPE_STREAM) {
      self->state->upstream_tags.reset(gst_tag_list_copy(tags));
      self->state->pushed_comment.clear();
      gst_event_unref(event);
      return TRUE;
    }
  }
  if (GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP || GST_EVENT_TYPE(event) == GST_EVENT_SEGMENT) {
    self->state->last_stats = GST_CLOCK_TIME_NONE;  // the next frame posts statistics
    if (GST_EVENT_TYPE(event) == GST_EVENT_FLUSH_STOP) self->state->frames = 0;
  }
  return GST_BASE_TRANSFORM_CLASS(gst_ratio_temp_parent_class)->sink_event(trans, event);
}

/* Switches to the estimator the method property asks for, building it if needed. A method that
 * cannot be used is refused with one warning per change; the current one stays. */
static void apply_method(GstRatioTemp* self, GstRatioTempMethod request) {
  State& st = *self->state;
  if (request == st.method_request) {
    st.refused = false;
    return;
  }
  if (st.refused && st.refused_request == request) return;
  const pyrocam::EstimatorSelector::Choice choice = st.estimators->select(rt::to_library(request));
  const pyrocam::Method chosen = choice.method;
  const std::string& problem = choice.problem;
  if (problem.empty()) {
    GST_INFO_OBJECT(self, "method %s -> %s%s%s", pyrocam::method_name(st.method).c_str(),
                    pyrocam::method_name(chosen).c_str(),
                    choice.fallback.empty() ? "" : ", not lut: ", choice.fallback.c_str());
    st.method = chosen;
    st.method_request = request;
    st.refused = false;
    rt::warn_when_network_folds(self, st);
    return;
  }
  st.refused = true;
  st.refused_request = request;
  GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                      ("Method %s cannot be used with model %s: %s; keeping %s",
                       pyrocam::method_name(chosen).c_str(), st.model_path.c_str(), problem.c_str(),
                       pyrocam::method_name(st.method).c_str()),
                      ("estimator construction or its check failed while playing"));
}

/* Where a frame is in the stream for the statistics interval: its timestamp, else its index
 * over the framerate, else none. */
static GstClockTime frame_position(const State& st, GstBuffer* buffer) {
  if (GST_BUFFER_PTS_IS_VALID(buffer)) return GST_BUFFER_PTS(buffer);
  const int fps_n = GST_VIDEO_INFO_FPS_N(&st.out_info), fps_d = GST_VIDEO_INFO_FPS_D(&st.out_info);
  if (fps_n <= 0 || fps_d <= 0) return GST_CLOCK_TIME_NONE;
  return gst_util_uint64_scale(st.frames, static_cast<guint64>(fps_d) * GST_SECOND,
                               static_cast<guint64>(fps_n));
}

static GstFlowReturn gst_ratio_temp_transform(GstBaseTransform* trans, GstBuffer* inbuf,
                                              GstBuffer* outbuf) {
  GstRatioTemp* self = GST_RATIO_TEMP(trans);
  if (!self->state->configured) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "No format negotiated",
                       "transform called before set_caps");
    return GST_FLOW_NOT_NEGOTIATED;
  }
  const Settings settings = copy_settings(self);
  apply_method(self, settings.method);
  State& st = *self->state;
  if (settings.region_serial != st.region_serial_seen) {
    st.region_serial_seen = settings.region_serial;
    if (!settings.region_valid)
      GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                          ("region '%s' is not x,y,width,height; no region statistics until a "
                           "valid one is set",
                           settings.region_text.c_str()),
                          ("the region property did not parse"));
  }
  const bool uncertainty = settings.output == GST_RATIO_TEMP_OUTPUT_UNCERTAINTY;
  rt::Corrections corrections;
  if (!PYROCAM_GUARDED(self, pg::ErrorKind::kSettings, "Could not set up the corrections",
                       [&] { corrections = rt::corrections_for_frame(self, settings, st); }))
    return GST_FLOW_ERROR;
  // Statistics need the float temperatures; without them (and without uncertainties) the codes
  // come straight from the planes.
  const GstClockTime position = frame_position(st, inbuf);
  // A frame without an image (darksub's frames while it captures a dark: GAP) gives no reading
  // and no statistics: counted, its unread samples would be saturation.
  const bool gap = GST_BUFFER_FLAG_IS_SET(inbuf, GST_BUFFER_FLAG_GAP);
  const bool stats_due =
      !gap && settings.stats_interval > 0 &&
      (!GST_CLOCK_TIME_IS_VALID(position) || !GST_CLOCK_TIME_IS_VALID(st.last_stats) ||
       position < st.last_stats || position - st.last_stats >= settings.stats_interval);
  if (!PYROCAM_GUARDED(self, pg::ErrorKind::kSettings, "e-slope refused", [&] {
        st.estimators->estimator(st.method).set_emissivity_slope(
            settings.e_slope / 100, settings.e_slope_uncertainty / 100);
      }))
    return GST_FLOW_ERROR;  // the property's range leaves only a pass band over 400 nm wide
  const bool ok =
      PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not estimate temperatures", [&] {
        pg::MappedImage in;
        in.map_float(inbuf, st.width, st.height, st.fused ? 1 : st.bands, GST_MAP_READ);
        if (!st.fused)
          for (int b = 0; b < st.bands; ++b)
            st.planes[static_cast<std::size_t>(b)] = in.plane(b, st.width, st.height);
        if (stats_due) st.saturated_mask = rt::saturated_mask(st, in.image());
        const pyrocam::PlaneEstimator::MatchedMosaic mosaic{in.image(), st.mosaic_layout,
                                                            st.no_signal_dn};
        pyrocam::PlaneEstimator& chosen = st.estimators->estimator(st.method);
        // The frame's gain scales its shot noise per DN; rebuilt only when it changes.
        const PyrocamExposureMeta* meta = pyrocam_buffer_get_exposure_meta(inbuf);
        const double gain = meta ? pyrocam::analogue_gain_factor(meta->gain_db) : 1.0;
        chosen.set_analogue_gain(gain);
        if (corrections.snapshot_brightness)
          corrections.snapshot_brightness->set_analogue_gain(gain);
        chosen.set_exposure_us(meta ? meta->exposure_us : 0);  // 0: unknown
        chosen.set_misfit_probability(settings.misfit_probability);
        chosen.set_demosaic_noise(st.demosaic_noise);
        // A frame without a saturated sample dropped nothing: the saturation-edge check is off.
        const PyrocamSaturationMeta* saturation = pyrocam_buffer_get_saturation_meta(inbuf);
        chosen.set_saturation_level(
            saturation && saturation->samples == 0 ? INFINITY : st.saturation_level_dn);
        chosen.set_partial_bands(settings.allow_partial ||
                                         settings.partial_bands == GST_RATIO_TEMP_PARTIAL_ANY
                                     ? pyrocam::TemperatureEstimator::PartialBands::kAny
                                 : settings.partial_bands == GST_RATIO_TEMP_PARTIAL_SAFE
                                     ? pyrocam::TemperatureEstimator::PartialBands::kSafe
                                     : pyrocam::TemperatureEstimator::PartialBands::kOff);
        chosen.set_above_range_check(true);
        const pyrocam::PlaneEstimator& estimator = chosen;
        rt::MappedFrame out(outbuf, &st.out_info);
        if (!uncertainty && !stats_due) {
          // Straight into the output frame (the header wraps it; a copy only if it did not fit).
          cv::Mat codes = out.image;
          rt::estimate_codes(chosen, st, mosaic, corrections, codes);
          if (codes.data != out.image.data) codes.copyTo(out.image);
          return;
        }
        cv::Mat* u = uncertainty ? &st.uncertainty_c : nullptr;
        if (st.fused)
          estimator.estimate(mosaic, st.temperature_c, u);
        else
          estimator.estimate(st.planes, st.temperature_c, u);
        if (uncertainty) {
          rt::correct_temperature(corrections, in.image(), st.temperature_c);
          st.uncertainty_c.setTo(NAN, st.temperature_c != st.temperature_c);
          pyrocam::encode_decikelvin_difference(st.uncertainty_c).copyTo(out.image);
        } else {
          cv::Mat codes = out.image;
          pyrocam::encode_decikelvin(st.temperature_c, codes);
          if (corrections.curvature || corrections.blur || corrections.brightness ||
              corrections.snapshot_brightness) {
            // From the codes, as on frames without statistics: the same output.
            rt::correct_codes(corrections, in.image(), codes);
            st.temperature_c = pyrocam::decode_decikelvin(codes);
          }
          if (codes.data != out.image.data) codes.copyTo(out.image);
        }
      });
  if (!ok) return GST_FLOW_ERROR;
  if (gap) GST_BUFFER_FLAG_SET(outbuf, GST_BUFFER_FLAG_GAP);  // still no image downstream
  if (!PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not describe the frame in metas",
                       [&] { rt::attach_frame_metas(outbuf, settings, st, gap); }))
    return GST_FLOW_ERROR;
  rt::warn_when_readings_misfit(self, st, st.estimators->estimator(st.method));
  if (!PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not describe the stream in tags",
                       [&] { rt::push_stream_tags(self, settings, *self->state); }))
    return GST_FLOW_ERROR;
  if (stats_due) {
    if (!PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not compute temperature statistics",
                         [&] { rt::post_stats(self, settings, st, GST_BUFFER_PTS(inbuf)); }))
      return GST_FLOW_ERROR;
    st.last_stats = position;
  }
  ++st.frames;
  return GST_FLOW_OK;
}

static void gst_ratio_temp_finalize(GObject* object) {
  GstRatioTemp* self = GST_RATIO_TEMP(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_ratio_temp_parent_class)->finalize(object);
}

static void gst_ratio_temp_class_init(GstRatioTempClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_ratio_temp_debug, "ratiotemp", 0,
                          "pyrocam band planes to temperature");

  gobject_class->set_property = rt::set_property;
  gobject_class->get_property = rt::get_property;
  gobject_class->finalize = gst_ratio_temp_finalize;

  rt::install_properties(gobject_class);

  gst_element_class_set_static_metadata(
      element_class, "Band planes to temperature", "Filter/Converter/Video",
      "Estimates per-pixel temperatures (GRAY16_LE, 0.1 K, 0 = no reading) from band planes "
      "with a calibrated thermal model",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  trans_class->transform_caps = GST_DEBUG_FUNCPTR(rt::transform_caps);
  trans_class->transform_size = GST_DEBUG_FUNCPTR(rt::transform_size);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_ratio_temp_set_caps);
  trans_class->decide_allocation = GST_DEBUG_FUNCPTR(pg::decide_allocation);
  trans_class->start = GST_DEBUG_FUNCPTR(gst_ratio_temp_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_ratio_temp_stop);
  trans_class->sink_event = GST_DEBUG_FUNCPTR(gst_ratio_temp_sink_event);
  trans_class->transform = GST_DEBUG_FUNCPTR(gst_ratio_temp_transform);
  trans_class->passthrough_on_same_caps = FALSE;

  gst_type_mark_as_plugin_api(GST_TYPE_RATIO_TEMP_METHOD, static_cast<GstPluginAPIFlags>(0));
  gst_type_mark_as_plugin_api(GST_TYPE_RATIO_TEMP_OUTPUT, static_cast<GstPluginAPIFlags>(0));
  gst_type_mark_as_plugin_api(GST_TYPE_RATIO_TEMP_PARTIAL, static_cast<GstPluginAPIFlags>(0));
}

static void gst_ratio_temp_init(GstRatioTemp* self) {
  self->settings = new Settings();
  self->state = new State();
}
