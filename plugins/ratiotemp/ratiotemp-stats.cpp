/* ratiotemp's statistics message: frame and region statistics of the temperatures. */
#include <algorithm>
#include <cmath>

#include "pyrocam/runtime/above_range.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/region_stats.h"
#include "ratiotemp-private.h"

#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pyrocam::gst::ratiotemp {
namespace {

constexpr const char* STATS_MESSAGE = "pyrocam-temperature-stats";
static_assert(pyrocam::kSystematicTableSamples <= PYROCAM_UNCERTAINTY_META_SAMPLES);

void set_stats_fields(GstStructure* s, const std::string& prefix, const RegionStats& r) {
  gst_structure_set(s, (prefix + "pixels").c_str(), G_TYPE_UINT64, static_cast<guint64>(r.pixels),
                    (prefix + "valid").c_str(), G_TYPE_UINT64, static_cast<guint64>(r.valid),
                    (prefix + "valid-fraction").c_str(), G_TYPE_DOUBLE, r.valid_fraction, nullptr);
  if (r.valid == 0) return;
  gst_structure_set(s, (prefix + "min-c").c_str(), G_TYPE_DOUBLE, r.min_c,
                    (prefix + "max-c").c_str(), G_TYPE_DOUBLE, r.max_c, (prefix + "mean-c").c_str(),
                    G_TYPE_DOUBLE, r.mean_c, (prefix + "median-c").c_str(), G_TYPE_DOUBLE,
                    r.median_c, nullptr);
}

// Peak fields with the window centre in frame pixels (`offset`: the region's corner), and the
// expanded systematic uncertainty of a reading at the peak where known.
void set_peak_fields(GstStructure* s, const std::string& prefix, const RegionPeak& p,
                     cv::Point offset, const pyrocam::SystematicUncertaintyTable* systematic) {
  if (!p.found()) return;
  gst_structure_set(s, (prefix + "peak-c").c_str(), G_TYPE_DOUBLE, p.c, (prefix + "peak-x").c_str(),
                    G_TYPE_INT, p.x + offset.x, (prefix + "peak-y").c_str(), G_TYPE_INT,
                    p.y + offset.y, nullptr);
  const double u = systematic ? systematic->at(p.c) : NAN;
  if (std::isfinite(u))
    gst_structure_set(s, (prefix + "peak-u-sys-c").c_str(), G_TYPE_DOUBLE, u, nullptr);
}

RegionPeak peak_of(const cv::Mat& t, const Settings& settings) {
  return peak_fits(settings, t.cols, t.rows)
             ? region_peak(t, static_cast<int>(settings.peak_window))
             : RegionPeak();
}

}  // namespace

cv::Mat saturated_mask(const State& st, const cv::Mat& fused_mosaic) {
  if (!st.fused) return pyrocam::saturated_band_mask(st.planes);
  // The fused path demosaics with matched kernels: a square of reach samples.
  const int side = static_cast<int>(std::lround(std::sqrt(
      pyrocam::demosaic_sample_reach(st.mosaic_layout, pyrocam::DemosaicMethod::kMatched))));
  return pyrocam::saturated_sample_mask(fused_mosaic, side / 2);
}

GstStructure* stats_structure(const cv::Mat& temperature_c, const cv::Mat& saturated,
                              const std::vector<cv::Point>& above_range, const Settings& settings,
                              const GstSegment* segment, GstClockTime pts, Method method,
                              const pyrocam::SystematicUncertaintyTable* systematic) {
  GstClockTime stream_time = GST_CLOCK_TIME_NONE, running_time = GST_CLOCK_TIME_NONE;
  if (GST_CLOCK_TIME_IS_VALID(pts) && segment->format == GST_FORMAT_TIME) {
    stream_time = gst_segment_to_stream_time(segment, GST_FORMAT_TIME, pts);
    running_time = gst_segment_to_running_time(segment, GST_FORMAT_TIME, pts);
  }
  // The statistics first: nothing to free should they throw.
  const RegionStats whole = region_stats(temperature_c);
  const RegionPeak whole_peak = peak_of(temperature_c, settings);
  const bool with_region = !settings.region_text.empty() && settings.region_valid;
  cv::Rect r;
  RegionStats region;
  RegionPeak part_peak;
  if (with_region) {
    cv::Rect wanted(settings.region.x, settings.region.y, settings.region.width,
                    settings.region.height);
    if (settings.region_tracks_peak && whole_peak.found()) {
      // Centred on the peak and moved, not cut, to stay in the frame where it fits.
      wanted.x = std::clamp(whole_peak.x - wanted.width / 2, 0,
                            std::max(temperature_c.cols - wanted.width, 0));
      wanted.y = std::clamp(whole_peak.y - wanted.height / 2, 0,
                            std::max(temperature_c.rows - wanted.height, 0));
    }
    r = wanted & cv::Rect(0, 0, temperature_c.cols, temperature_c.rows);
    if (!r.empty()) {
      region = region_stats(temperature_c(r));
      part_peak = peak_of(temperature_c(r), settings);
    }
  }
  const bool with_saturated = !saturated.empty();
  const std::size_t saturated_pixels =
      with_saturated ? pyrocam::count_without_reading(temperature_c, saturated) : 0;
  const std::size_t region_saturated =
      with_saturated && with_region && !r.empty()
          ? pyrocam::count_without_reading(temperature_c(r), saturated(r))
          : 0;
  const std::size_t region_above_range =
      with_region && !r.empty() ? static_cast<std::size_t>(std::count_if(
                                      above_range.begin(), above_range.end(),
                                      [&r](const cv::Point& p) { return r.contains(p); }))
                                : 0;
  GstStructure* s = gst_structure_new(
      STATS_MESSAGE, "timestamp", G_TYPE_UINT64, static_cast<guint64>(pts), "stream-time",
      G_TYPE_UINT64, static_cast<guint64>(stream_time), "running-time", G_TYPE_UINT64,
      static_cast<guint64>(running_time), "method", G_TYPE_STRING, method_name(method).c_str(),
      "width", G_TYPE_INT, temperature_c.cols, "height", G_TYPE_INT, temperature_c.rows, nullptr);
  set_stats_fields(s, "", whole);
  if (with_saturated)
    gst_structure_set(s, "saturated", G_TYPE_UINT64, static_cast<guint64>(saturated_pixels),
                      nullptr);
  gst_structure_set(s, "above-range", G_TYPE_UINT64, static_cast<guint64>(above_range.size()),
                    nullptr);
  set_peak_fields(s, "", whole_peak, cv::Point(), systematic);
  if (with_region) {
    gst_structure_set(s, "region-x", G_TYPE_INT, r.x, "region-y", G_TYPE_INT, r.y, "region-width",
                      G_TYPE_INT, r.width, "region-height", G_TYPE_INT, r.height,
                      "region-tracks-peak", G_TYPE_BOOLEAN,
                      settings.region_tracks_peak && whole_peak.found(), nullptr);
    set_stats_fields(s, "region-", region);
    if (with_saturated)
      gst_structure_set(s, "region-saturated", G_TYPE_UINT64,
                        static_cast<guint64>(region_saturated), nullptr);
    gst_structure_set(s, "region-above-range", G_TYPE_UINT64,
                      static_cast<guint64>(region_above_range), nullptr);
    set_peak_fields(s, "region-", part_peak, r.tl(), systematic);
  }
  return s;
}

void post_stats(GstRatioTemp* self, const Settings& settings, State& st, GstClockTime pts) {
  const cv::Mat& temperature_c = st.temperature_c;
  std::string& peak_warned = st.peak_warned;
  const int w = temperature_c.cols, h = temperature_c.rows;
  if (settings.peak_window_set && settings.peak_window > 0 && !peak_fits(settings, w, h)) {
    // Once per window and frame size; the default window stays quiet on tiny frames.
    const std::string misfit =
        std::to_string(settings.peak_window) + "/" + std::to_string(w) + "x" + std::to_string(h);
    if (misfit != peak_warned)
      GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                          ("%s: peak-window %u is larger than the %dx%d frame; no peak in the "
                           "statistics",
                           GST_OBJECT_NAME(self), settings.peak_window, w, h),
                          ("the window must fit in the frame"));
    peak_warned = misfit;
  }
  if (settings.region_tracks_peak && settings.region_text.empty() && !st.tracking_warned)
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("%s: region-tracks-peak needs a region (its size): no region is "
                         "tracked",
                         GST_OBJECT_NAME(self)),
                        ("region-tracks-peak without region"));
  st.tracking_warned = settings.region_tracks_peak && settings.region_text.empty();
  if (!settings.region_text.empty() && settings.region_valid && !settings.region_tracks_peak) {
    // Once per region and frame size: a 5x5 camera's frames are the sensor's fifth.
    const cv::Rect wanted(settings.region.x, settings.region.y, settings.region.width,
                          settings.region.height);
    const std::string outside =
        settings.region_text + "/" + std::to_string(w) + "x" + std::to_string(h);
    if ((wanted & cv::Rect(0, 0, w, h)).empty() && outside != st.region_warned)
      GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                          ("%s: region %s lies outside the %dx%d frame; its statistics are "
                           "empty",
                           GST_OBJECT_NAME(self), settings.region_text.c_str(), w, h),
                          ("the region is in output pixels (a 5x5 camera's are macro-pixels)"));
    st.region_warned = outside;
  }
  GstStructure* s =
      stats_structure(temperature_c, st.saturated_mask, st.above_range, settings,
                      &GST_BASE_TRANSFORM(self)->segment, pts, st.method, &st.systematic);
  guint64 saturated = 0;
  gst_structure_get_uint64(s, "saturated", &saturated);
  gst_element_post_message(GST_ELEMENT(self), gst_message_new_element(GST_OBJECT(self), s));
  // A reading missing because the light was too much looks like a cold spot in the statistics
  // and leaves peak-c at the edge of the saturated part: say so once per appearance.
  if (saturated > 0 && !st.saturation_warned)
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("%s: %" G_GUINT64_FORMAT " pixels have no reading because light "
                         "saturated a band: the hottest part of the scene may be there, and "
                         "peak-c and max-c are then only lower bounds; shorten the exposure (of "
                         "a bracket: its shortest) or put autoexposure in front of darksub",
                         GST_OBJECT_NAME(self), saturated),
                        ("statistics at %" GST_TIME_FORMAT, GST_TIME_ARGS(pts)));
  st.saturation_warned = saturated > 0;
  // Beyond the model's range every estimator gives no reading: such a part too looks cold.
  const std::size_t above = st.above_range.size();
  if (above > 0 && !st.above_range_warned)
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("%s: %zu pixels have no reading because they are hotter than the "
                         "model's range (up to %.0f degC): the hottest part of the scene is "
                         "there, and peak-c and max-c are only lower bounds; calibrate a model "
                         "with a higher --max-temperature",
                         GST_OBJECT_NAME(self), above, st.model->max_temperature_c),
                        ("statistics at %" GST_TIME_FORMAT, GST_TIME_ARGS(pts)));
  st.above_range_warned = above > 0;
}

void attach_frame_metas(GstBuffer* outbuf, const Settings& settings, State& st, bool gap) {
  const pyrocam::PlaneEstimator& estimator = st.estimators->estimator(st.method);
  // A few microseconds: the estimator's terms follow the emissivity slope, set per frame.
  st.systematic = pyrocam::systematic_uncertainty_table(estimator.estimator());
  if (settings.output != GST_RATIO_TEMP_OUTPUT_UNCERTAINTY)
    pyrocam_buffer_set_uncertainty_meta(outbuf, st.systematic.coverage_factor,
                                        static_cast<guint>(st.systematic.temperature_c.size()),
                                        st.systematic.temperature_c.data(),
                                        st.systematic.expanded_u_c.data());
  const std::vector<cv::Point> found = estimator.take_above_range();
  const pyrocam::SaturatedSamples spots = pyrocam::above_range_spots(
      gap ? std::vector<cv::Point>() : found, cv::Size(st.width, st.height), &st.above_range);
  guint64 tiles[pyrocam::kSaturationTiles];
  std::copy(spots.tiles.begin(), spots.tiles.end(), tiles);
  pyrocam_buffer_set_above_range_meta(outbuf, spots.count, spots.bounds.x, spots.bounds.y,
                                      spots.bounds.width, spots.bounds.height, st.width, st.height,
                                      tiles, st.model->max_temperature_c);
}

void warn_when_readings_misfit(GstRatioTemp* self, State& st,
                               const pyrocam::PlaneEstimator& estimator) {
  const pyrocam::PlaneEstimator::FitAudit audit = estimator.take_fit_audit();
  st.fit_checked += audit.checked;
  st.fit_misfit += audit.misfit;
  st.fit_too_bright += audit.too_bright;
  if (st.fit_checked < kFitAuditReadings) return;
  // More than half: a true graybody pixel fails at kFitAuditProbability; edges, reflections and
  // a calibration a few percent off make a few percent at most. And a surface a thousand times
  // brighter than a black body at its reading is no aperture or filter between calibration and
  // use: the readings are far too cold. Bands in the wrong places often do both; one warning.
  const bool misfit = 2 * st.fit_misfit > st.fit_checked;
  const bool too_bright = 2 * st.fit_too_bright > st.fit_checked;
  const char* model_name = st.model->profile().name.c_str();
  if (misfit && !st.fit_warned) {
    GST_ELEMENT_WARNING(
        self, STREAM, FORMAT,
        ("%s: %zu of %zu readings checked do not fit the model's band spectra%s: the "
         "temperatures are likely wrong. Is the mosaic's phase right (a crop at the top or left "
         "by other than whole mosaic periods, or a flip, before darksub shifts it: crop at the "
         "right and bottom)? Is the model (%s) for this camera?",
         GST_OBJECT_NAME(self), st.fit_misfit, st.fit_checked,
         too_bright ? ", and most are over a thousand times as bright as a black body at the "
                      "temperature read"
                    : "",
         model_name),
        ("band-consistency check of a sample of readings at false-rejection probability %g, "
         "model error %g",
         pyrocam::PlaneEstimator::kFitAuditProbability,
         pyrocam::PlaneEstimator::kFitAuditModelError));
    st.fit_warned = true;
    st.too_bright_warned = st.too_bright_warned || too_bright;
  } else if (too_bright && !st.too_bright_warned) {
    const bool bayer = st.model->profile().mosaic.kind == pyrocam::MosaicLayout::Kind::kBayer;
    GST_ELEMENT_WARNING(
        self, STREAM, FORMAT,
        ("%s: %zu of %zu readings checked are over %.0f times as bright as a black body at the "
         "temperature read (at the frames' exposure and gain): the temperatures are far too "
         "cold. %s Is the model (%s) for this camera?",
         GST_OBJECT_NAME(self), st.fit_too_bright, st.fit_checked,
         pyrocam::PlaneEstimator::kImpossibleBrightness,
         bayer ? "Are red and blue traded (a bggr sensor given as rggb, a crop by one row and "
                 "one column, a flip)?"
               : "Is the mosaic's phase right (a crop at the top or left by other than whole "
                 "mosaic periods)?",
         model_name),
        ("brightness against the model's rates (DN/s at emissivity 1) in the fit audit's sample"));
    st.too_bright_warned = true;
  }
  st.fit_checked = st.fit_misfit = st.fit_too_bright = 0;
}

}  // namespace pyrocam::gst::ratiotemp
