/* demosaic25's parts shared by its source files: the property values, the streaming state and
 * the element struct; demosaic25-caps.cpp has the caps' transforms, gstdemosaic25.cpp the
 * negotiation's end (fixate, set_caps), the streaming and the properties. */
#pragma once

#include <gst/base/gstbasetransform.h>
#include <gst/gst.h>

#include <string>
#include <vector>

#include "gstdemosaic25.h"
#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/demosaic.h"

GST_DEBUG_CATEGORY_EXTERN(gst_demosaic25_debug);

namespace pyrocam::gst::demosaic25 {

enum { PROP_0, PROP_METHOD, PROP_PROFILE, PROP_MIXED_PIXELS };

constexpr GstDemosaic25Method DEFAULT_METHOD = GST_DEMOSAIC25_METHOD_AUTO;
// Off by default: it costs under the 15 % of the colour chain a default may cost, but it takes
// most readings of small melt pools at a fixed exposure (their steep sides; docs/elements.md).
constexpr double DEFAULT_MIXED_PIXELS = 0;
// The shipped colour camera, whose noise the mixed-pixel check assumes without a profile.
constexpr const char* kColourCameraProfile = "rgb-reference";

struct Settings {
  GstDemosaic25Method method = DEFAULT_METHOD;
  std::string profile;
  double mixed_pixels = DEFAULT_MIXED_PIXELS;  // relative spread; 0: no check
};

struct State {
  bool have_snapshot_layout = false;  // from the profile, loaded in start()
  pyrocam::MosaicLayout snapshot_layout;
  std::string profile_name, profile_pattern;  // the profile's mosaic as a caps pattern
  std::string profile_band_map;  // band-map text of a 5x5 profile; under the object lock
  bool configured = false;
  pyrocam::MosaicLayout layout;
  pyrocam::DemosaicMethod method = pyrocam::DemosaicMethod::kBilinear;
  int in_width = 0, in_height = 0, out_width = 0, out_height = 0, bands = 0;
  std::vector<cv::Mat> planes;                      // headers onto the output buffer, reused
  std::vector<pyrocam::SignalNoise> profile_noise;  // per band, from the profile; empty: none
  std::vector<pyrocam::SignalNoise> noise;          // per band, for the stream's bit depth
  double profile_dim_dn = -1;                       // the profile's dim threshold; <0: none
  float skip_below_dn = 0;  // the mixed-pixel check leaves footprints dimmer than this alone
  float no_signal_dn = 0;   // method matched: samples below it hold no light
};

inline pyrocam::DemosaicMethod to_library(GstDemosaic25Method m) {
  switch (m) {
    case GST_DEMOSAIC25_METHOD_BIN2X2:
      return pyrocam::DemosaicMethod::kBinCells;
    case GST_DEMOSAIC25_METHOD_MATCHED:
      return pyrocam::DemosaicMethod::kMatched;
    case GST_DEMOSAIC25_METHOD_AUTO:
      return pyrocam::DemosaicMethod::kAuto;
    default:
      return pyrocam::DemosaicMethod::kBilinear;
  }
}

/* The caps' name of the method (auto resolved): the library's (parse_demosaic_method). */
inline const char* method_name(GstDemosaic25Method m) {
  // auto resolves alike on every layout
  return pyrocam::demosaic_method_name(
      pyrocam::resolve_demosaic_method(to_library(m), pyrocam::MosaicLayout{}));
}

inline bool is_snapshot(const char* pattern) {
  return pattern && g_str_equal(pattern, PYROCAM_SNAPSHOT_PATTERN_NAME);
}

/* Whether the settings let demosaic25 hand its planes on as their mosaic (the fused path): a
 * Bayer mosaic with method matched and no mixed-pixel check (the defaults). */
inline bool fused_path_allowed(const Settings& s) {
  return (s.method == GST_DEMOSAIC25_METHOD_MATCHED || s.method == GST_DEMOSAIC25_METHOD_AUTO) &&
         s.mixed_pixels == 0;
}

/* The caps' transforms (demosaic25-caps.cpp): mosaic to band planes and back, with the fused
 * path's caps after the planes where fused_path_allowed; the output size. */
GstCaps* transform_caps(GstBaseTransform* trans, GstPadDirection direction, GstCaps* caps,
                        GstCaps* filter);
gboolean transform_size(GstBaseTransform* trans, GstPadDirection direction, GstCaps* caps,
                        gsize size, GstCaps* othercaps, gsize* othersize);

}  // namespace pyrocam::gst::demosaic25

struct _GstDemosaic25 {
  GstBaseTransform parent;
  pyrocam::gst::demosaic25::Settings* settings;
  pyrocam::gst::demosaic25::State* state;
};

namespace pyrocam::gst::demosaic25 {
/* The properties, copied under the object lock. */
inline Settings copy_settings(GstDemosaic25* self) { return locked_copy(self, *self->settings); }
}  // namespace pyrocam::gst::demosaic25
