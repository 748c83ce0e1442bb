/* ratiotemp's steps after the per-pixel estimate: the curvature check, the blur correction and
 * the ratio-scaled brightness readings, from the mosaic of the fused path (a snapshot model's
 * brightness readings from its band planes). */
#include "ratiotemp-private.h"

#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pyrocam::gst::ratiotemp {

Corrections corrections_for_frame(GstRatioTemp* self, const Settings& settings, State& st) {
  Corrections c;
  if (st.fused) {
    if (!st.curvature) st.curvature.emplace(*st.model, st.mosaic_layout);  // the stream's phase
    c.curvature = &*st.curvature;
  }
  if (settings.blur_correction && st.fused) {
    // The correction's table is made the first time it is asked for on the fused path.
    if (!st.blur) st.blur.emplace(*st.model, pyrocam::DemosaicMethod::kMatched);
    c.blur = &*st.blur;
  }
  if (settings.blur_correction && !st.fused && !st.blur_warned) {
    st.blur_warned = true;
    GST_ELEMENT_WARNING(self, STREAM, FORMAT,
                        ("blur-correction needs demosaic25 with method matched or auto on a Bayer "
                         "mosaic linked to ratiotemp (the fused path); these planes are read "
                         "without it"),
                        ("the sink caps are not the fused bands"));
  }
  const int radius = static_cast<int>(settings.brightness_radius);
  if (radius > 0 && st.fused) {
    if (!st.brightness || st.brightness->window_radius() != radius)
      st.brightness.emplace(*st.model, radius, st.mosaic_layout);  // the stream's phase
    c.brightness = &*st.brightness;
  }
  if (radius > 0 && st.snapshot) {
    if (!st.snapshot_brightness || st.snapshot_brightness->window_radius() != radius)
      st.snapshot_brightness.emplace(*st.model, radius);
    c.snapshot_brightness = &*st.snapshot_brightness;
    c.planes = &st.planes;
  }
  if (radius > 0 && !st.fused && !st.snapshot && !st.brightness_warned) {
    st.brightness_warned = true;
    GST_ELEMENT_WARNING(self, STREAM, FORMAT,
                        ("brightness-radius %d needs demosaic25 with method matched or auto on "
                         "a Bayer mosaic linked to ratiotemp (the fused path); these planes are "
                         "read by their ratios alone",
                         radius),
                        ("the sink caps are not the fused bands"));
  }
  return c;
}

void reset_corrections(State& st) {
  st.curvature.reset();
  st.blur.reset();
  st.brightness.reset();
  st.snapshot_brightness.reset();
}

void estimate_codes(pyrocam::PlaneEstimator& estimator, const State& st,
                    const pyrocam::PlaneEstimator::MatchedMosaic& mosaic, const Corrections& c,
                    cv::Mat& codes) {
  if (!st.fused) {
    estimator.estimate_codes(st.planes, codes);
    correct_codes(c, mosaic.mosaic, codes);
    return;
  }
  struct Unset {  // the check is this call's
    pyrocam::PlaneEstimator& estimator;
    ~Unset() { estimator.set_curvature_check(nullptr); }
  } unset{estimator};
  estimator.set_curvature_check(c.curvature);
  estimator.estimate_codes(mosaic, codes);
  Corrections rest = c;
  rest.curvature = nullptr;  // done
  correct_codes(rest, mosaic.mosaic, codes);
}

void correct_codes(const Corrections& c, const cv::Mat& mosaic, cv::Mat& codes) {
  if (c.curvature) c.curvature->apply_codes(mosaic, codes);
  if (c.blur) c.blur->apply_codes(codes);
  if (c.brightness) c.brightness->apply_codes(mosaic, codes);
  if (c.snapshot_brightness) c.snapshot_brightness->apply_codes(*c.planes, codes);
}

void correct_temperature(const Corrections& c, const cv::Mat& mosaic, cv::Mat& temperature_c) {
  if (c.curvature) c.curvature->apply(mosaic, temperature_c);
  if (c.blur) c.blur->apply(temperature_c);
  if (c.brightness) c.brightness->apply(mosaic, temperature_c);
  if (c.snapshot_brightness) c.snapshot_brightness->apply(*c.planes, temperature_c);
}

}  // namespace pyrocam::gst::ratiotemp
