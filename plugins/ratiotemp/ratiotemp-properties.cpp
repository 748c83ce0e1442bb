/* ratiotemp's GObject properties. */
#include <cmath>

#include "pyrocam-common.h"
#include "ratiotemp-private.h"

#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pyrocam::gst::ratiotemp {
namespace {

enum {
  PROP_0,
  PROP_MODEL,
  PROP_METHOD,
  PROP_OUTPUT,
  PROP_STATS_INTERVAL,
  PROP_REGION,
  PROP_ALLOW_PARTIAL,
  PROP_MISFIT_PROBABILITY,
  PROP_PEAK_WINDOW,
  PROP_E_SLOPE,
  PROP_E_SLOPE_UNCERTAINTY,
  PROP_PARTIAL_BANDS,
  PROP_TABLE_CACHE,
  PROP_REGION_TRACKS_PEAK,
  PROP_BLUR_CORRECTION,
  PROP_BRIGHTNESS_RADIUS,
};

}  // namespace

pyrocam::MethodRequest to_library(GstRatioTempMethod m) {
  switch (m) {
    case GST_RATIO_TEMP_METHOD_MLP:
      return pyrocam::MethodRequest::kMlp;
    case GST_RATIO_TEMP_METHOD_LUT:
      return pyrocam::MethodRequest::kLut;
    case GST_RATIO_TEMP_METHOD_LIKELIHOOD:
      return pyrocam::MethodRequest::kLikelihood;
    default:
      return pyrocam::MethodRequest::kAuto;
  }
}

void install_properties(GObjectClass* gobject_class) {
  const auto ready = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                              GST_PARAM_MUTABLE_READY);
  const auto playing = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING);
  g_object_class_install_property(
      gobject_class, PROP_MODEL,
      g_param_spec_string("model", "Thermal model file",
                          "Thermal model (JSON) written by pyrocam-calib calibrate for this "
                          "camera; required",
                          nullptr, ready));
  g_object_class_install_property(
      gobject_class, PROP_REGION_TRACKS_PEAK,
      g_param_spec_boolean(
          "region-tracks-peak", "Region tracks the peak",
          "Centre the statistics region (its size from region) on the frame's peak (peak-c's "
          "window) each time statistics are posted, moved to stay inside the frame, so that the "
          "region's statistics follow a moving hot spot; a frame without a peak keeps region's "
          "own place. Needs region and a peak-window",
          FALSE, playing));
  g_object_class_install_property(
      gobject_class, PROP_TABLE_CACHE,
      g_param_spec_string(
          "table-cache", "Lookup-table cache folder",
          "Folder where the lookup table's filled blocks are kept between runs, a file per model "
          "(lut-FINGERPRINT.bin, written at stop with the verdict of the table's check against "
          "the network, read at start, where that verdict spares the check), so that a model's "
          "next run does not fill them again while frames wait; empty: no cache. Unset "
          "(default): $XDG_CACHE_HOME/pyrocam, else ~/.cache/pyrocam",
          nullptr, ready));
  g_object_class_install_property(
      gobject_class, PROP_METHOD,
      g_param_spec_enum("method", "Estimator",
                        "Per-pixel temperature estimator: mlp (the paper's network, the "
                        "reference, slow), lut (lookup table of the network, colour models "
                        "only, checked against the network at start), likelihood (fit along the "
                        "Planckian locus), auto (lut for colour models when it passes its check, "
                        "likelihood otherwise)",
                        GST_TYPE_RATIO_TEMP_METHOD, DEFAULT_METHOD, playing));
  g_object_class_install_property(
      gobject_class, PROP_OUTPUT,
      g_param_spec_enum("output", "Output",
                        "What the GRAY16_LE pixels hold, in 0.1 K per code with 0 = no "
                        "reading: the temperature (kelvin) or its expanded uncertainty (k = 2)",
                        GST_TYPE_RATIO_TEMP_OUTPUT, DEFAULT_OUTPUT, ready));
  g_object_class_install_property(
      gobject_class, PROP_STATS_INTERVAL,
      g_param_spec_uint64("stats-interval", "Statistics interval",
                          "Nanoseconds of stream time between pyrocam-temperature-stats "
                          "element messages (0..2^64-1; 0 = none; otherwise the first frame "
                          "always posts)",
                          0, G_MAXUINT64, DEFAULT_STATS_INTERVAL, playing));
  g_object_class_install_property(
      gobject_class, PROP_REGION,
      g_param_spec_string("region", "Statistics region",
                          "Region of output pixels for the statistics message, "
                          "\"x,y,width,height\" (clipped to the frame); empty: frame only",
                          nullptr, playing));

  g_object_class_install_property(
      gobject_class, PROP_ALLOW_PARTIAL,
      g_param_spec_boolean("allow-partial", "Allow partial readings",
                           "Read pixels where some bands are saturated, missing or below the "
                           "dim threshold from any two or more of the rest (partial-bands=any, "
                           "which it overrides; kept for older pipelines)",
                           DEFAULT_ALLOW_PARTIAL, playing));
  g_object_class_install_property(
      gobject_class, PROP_PARTIAL_BANDS,
      g_param_spec_enum("partial-bands", "Partial readings",
                        "Pixels where some bands are saturated, missing or below the dim "
                        "threshold: off: no reading; safe: read by the likelihood fit from the "
                        "rest when they include two bands whose ratio is monotonic over the "
                        "model's range (decided from its locus; none for the shipped colour "
                        "camera, most pairs for the 5x5 one) and the noise alone leaves the "
                        "reading within 50 degC at 1500 degC, growing as the square of the "
                        "absolute temperature (one standard deviation); any: from any two",
                        GST_TYPE_RATIO_TEMP_PARTIAL, DEFAULT_PARTIAL_BANDS, playing));
  g_object_class_install_property(
      gobject_class, PROP_MISFIT_PROBABILITY,
      g_param_spec_double("misfit-probability", "Band-consistency false-rejection probability",
                          "Band-consistency check: no reading where the bands fit no graybody "
                          "within 1 % of the estimated temperature; the chance (0 to 0.5, "
                          "unitless, e.g. 1e-6) that a true graybody pixel is dropped; 0 = no "
                          "check",
                          0.0, MAX_MISFIT_PROBABILITY, DEFAULT_MISFIT_PROBABILITY, playing));
  g_object_class_install_property(
      gobject_class, PROP_BLUR_CORRECTION,
      g_param_spec_boolean(
          "blur-correction", "Blur correction",
          "Subtract matched demosaicking's bias on steep gradients: a footprint's mean signal is "
          "that of a hotter surface than its mean temperature (+180 degC at 150 degC a pixel near "
          "1400 degC); the gradient is taken from the readings. Only on the fused path "
          "(demosaic25 method matched or auto on a Bayer mosaic, linked to this element); "
          "elsewhere a warning and no correction",
          DEFAULT_BLUR_CORRECTION, playing));
  g_object_class_install_property(
      gobject_class, PROP_BRIGHTNESS_RADIUS,
      g_param_spec_uint(
          "brightness-radius", "Brightness window radius",
          "Read each pixel from its own brightness, its bands' scales the mean of what the "
          "ratio readings imply over a window. Bayer: each pixel from its own sample, the "
          "window (4 r + 1) x (4 r + 1) pixels, r in 2 x 2 Bayer cells (2: 9 x 9 pixels), only "
          "on the fused path (demosaic25 method matched or auto on a Bayer mosaic, linked to "
          "this element; elsewhere a warning and the ratio readings). Snapshot (5x5) band "
          "planes: each cell from all its bands, the window (2 r + 1) x (2 r + 1) cells. r from "
          "1 to 8; 0 (default) = the ratio readings as they are. Assumes one emissivity over "
          "the window: within r cells of an emissivity step readings move by up to the step's "
          "log ratio in temperature (about 100 degC at 2000 degC for a factor 2)",
          0, MAX_BRIGHTNESS_RADIUS, DEFAULT_BRIGHTNESS_RADIUS, playing));
  g_object_class_install_property(
      gobject_class, PROP_PEAK_WINDOW,
      g_param_spec_uint("peak-window", "Peak window",
                        "Side (output pixels, odd, 1 to 255) of the square window whose "
                        "largest median the statistics report as peak-c at peak-x, peak-y: "
                        "robust to single wild pixels, unlike max-c; an even value is refused; "
                        "0 = no peak",
                        0, MAX_PEAK_WINDOW, DEFAULT_PEAK_WINDOW, playing));
  g_object_class_install_property(
      gobject_class, PROP_E_SLOPE,
      g_param_spec_double("e-slope", "Emissivity slope",
                          "Spectral emissivity slope of the surface, percent per 100 nm (-50 to "
                          "50): emissivity 1 + e-slope/100 * (wavelength - middle of the filter "
                          "pass band) / 100 nm, positive when it rises with wavelength; the "
                          "readings are corrected for it; 0 = grey (ratios need no correction)",
                          -MAX_E_SLOPE, MAX_E_SLOPE, DEFAULT_E_SLOPE, playing));
  g_object_class_install_property(
      gobject_class, PROP_E_SLOPE_UNCERTAINTY,
      g_param_spec_double("e-slope-uncertainty", "Emissivity slope uncertainty",
                          "Standard uncertainty of e-slope, percent per 100 nm (0 to 100), for "
                          "the emissivity term of output=uncertainty; negative (default -1) = "
                          "the model's (1 %/100 nm for models from pyrocam-calib)",
                          -1.0, 100.0, DEFAULT_E_SLOPE_UNCERTAINTY, playing));
}

void set_property(GObject* object, guint prop_id, const GValue* value, GParamSpec* pspec) {
  GstRatioTemp* self = GST_RATIO_TEMP(object);
  const char* refused_while_running = nullptr;  // posted once the lock is released
  std::string refused_value;                    // the same
  {
    ObjectLock lock(self);
    Settings& s = *self->settings;
    const bool running = GST_STATE(self) > GST_STATE_READY;
    // A value that cannot be used: while running a warning, the value in use staying; before,
    // start() fails with it.
    const auto refuse = [&](const std::string& why, const std::string& kept) {
      if (running)
        refused_value = why + "; the value in use stays " + kept;
      else
        s.refused = why;
      GST_WARNING_OBJECT(self, "%s", why.c_str());
    };
    switch (prop_id) {
      case PROP_MODEL:
        if (running) {
          refused_while_running = "model";
        } else {
          const char* v = g_value_get_string(value);
          s.model = v ? v : "";
        }
        break;
      case PROP_REGION_TRACKS_PEAK:
        s.region_tracks_peak = g_value_get_boolean(value);
        break;
      case PROP_TABLE_CACHE:
        if (running) {
          refused_while_running = "table-cache";
        } else {
          const char* v = g_value_get_string(value);
          s.table_cache_set = v != nullptr;
          s.table_cache = v ? v : "";
        }
        break;
      case PROP_METHOD:
        s.method = static_cast<GstRatioTempMethod>(g_value_get_enum(value));
        break;
      case PROP_OUTPUT:
        if (running)
          refused_while_running = "output";
        else
          s.output = static_cast<GstRatioTempOutput>(g_value_get_enum(value));
        break;
      case PROP_STATS_INTERVAL:
        s.stats_interval = g_value_get_uint64(value);
        break;
      case PROP_ALLOW_PARTIAL:
        s.allow_partial = g_value_get_boolean(value);
        break;
      case PROP_PARTIAL_BANDS:
        s.partial_bands = static_cast<GstRatioTempPartial>(g_value_get_enum(value));
        break;
      case PROP_MISFIT_PROBABILITY:
        s.misfit_probability = g_value_get_double(value);
        break;
      case PROP_BLUR_CORRECTION:
        s.blur_correction = g_value_get_boolean(value);
        break;
      case PROP_BRIGHTNESS_RADIUS:
        s.brightness_radius = g_value_get_uint(value);
        break;
      case PROP_E_SLOPE:
      case PROP_E_SLOPE_UNCERTAINTY: {
        const double v = g_value_get_double(value);  // NaN passes the GParamSpec's range check
        double& to = prop_id == PROP_E_SLOPE ? s.e_slope : s.e_slope_uncertainty;
        if (std::isnan(v)) {
          refuse(std::string(pspec->name) + " NaN refused", std::to_string(to));
        } else {
          to = v;
          if (s.refused.rfind(std::string(pspec->name) + " ", 0) == 0) s.refused.clear();
        }
        break;
      }
      case PROP_PEAK_WINDOW: {
        const guint v = g_value_get_uint(value);
        if (v % 2 == 0 && v != 0) {
          refuse("peak-window " + std::to_string(v) + " is even (a window needs a centre pixel)",
                 std::to_string(s.peak_window));
        } else {
          s.peak_window = v;
          s.peak_window_set = true;
          if (s.refused.rfind("peak-window ", 0) == 0) s.refused.clear();
        }
        break;
      }
      case PROP_REGION: {
        const char* v = g_value_get_string(value);
        s.region_text = v ? v : "";
        s.region = Region();
        s.region_valid = s.region_text.empty() || parse_region(s.region_text, &s.region);
        ++s.region_serial;
        if (!s.region_valid)
          GST_WARNING_OBJECT(self, "region '%s' is not x,y,width,height", s.region_text.c_str());
        break;
      }
      default:
        G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
        break;
    }
  }
  if (refused_while_running)
    pyrocam::gst::warn_not_changeable_while_running(GST_ELEMENT(self), refused_while_running);
  if (!refused_value.empty())
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("%s: %s", GST_OBJECT_NAME(self), refused_value.c_str()),
                        ("property value refused while running"));
}

void get_property(GObject* object, guint prop_id, GValue* value, GParamSpec* pspec) {
  GstRatioTemp* self = GST_RATIO_TEMP(object);
  ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_MODEL:
      g_value_set_string(value, s.model.empty() ? nullptr : s.model.c_str());
      break;
    case PROP_REGION_TRACKS_PEAK:
      g_value_set_boolean(value, s.region_tracks_peak);
      break;
    case PROP_TABLE_CACHE:
      g_value_set_string(value, s.table_cache_set ? s.table_cache.c_str() : nullptr);
      break;
    case PROP_METHOD:
      g_value_set_enum(value, s.method);
      break;
    case PROP_OUTPUT:
      g_value_set_enum(value, s.output);
      break;
    case PROP_STATS_INTERVAL:
      g_value_set_uint64(value, s.stats_interval);
      break;
    case PROP_ALLOW_PARTIAL:
      g_value_set_boolean(value, s.allow_partial);
      break;
    case PROP_PARTIAL_BANDS:
      g_value_set_enum(value, s.partial_bands);
      break;
    case PROP_MISFIT_PROBABILITY:
      g_value_set_double(value, s.misfit_probability);
      break;
    case PROP_BLUR_CORRECTION:
      g_value_set_boolean(value, s.blur_correction);
      break;
    case PROP_BRIGHTNESS_RADIUS:
      g_value_set_uint(value, s.brightness_radius);
      break;
    case PROP_PEAK_WINDOW:
      g_value_set_uint(value, s.peak_window);
      break;
    case PROP_E_SLOPE:
      g_value_set_double(value, s.e_slope);
      break;
    case PROP_E_SLOPE_UNCERTAINTY:
      g_value_set_double(value, s.e_slope_uncertainty);
      break;
    case PROP_REGION:
      g_value_set_string(value, s.region_text.empty() ? nullptr : s.region_text.c_str());
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

}  // namespace pyrocam::gst::ratiotemp

GType gst_ratio_temp_method_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_RATIO_TEMP_METHOD_AUTO,
       "lut for two-ratio (colour) models when it passes its check, likelihood otherwise", "auto"},
      {GST_RATIO_TEMP_METHOD_MLP, "The paper's network on band ratios (reference, slow)", "mlp"},
      {GST_RATIO_TEMP_METHOD_LUT, "2-D lookup table of the network (colour models only)", "lut"},
      {GST_RATIO_TEMP_METHOD_LIKELIHOOD, "Maximum-likelihood fit along the Planckian locus",
       "likelihood"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstRatioTempMethod", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

GType gst_ratio_temp_partial_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_RATIO_TEMP_PARTIAL_OFF, "No reading unless every band reads", "off"},
      {GST_RATIO_TEMP_PARTIAL_SAFE, "From the bands left when a monotonic pair is among them",
       "safe"},
      {GST_RATIO_TEMP_PARTIAL_ANY, "From any two bands left", "any"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstRatioTempPartial", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

GType gst_ratio_temp_output_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_RATIO_TEMP_OUTPUT_TEMPERATURE, "Temperature, 0.1 K per code", "temperature"},
      {GST_RATIO_TEMP_OUTPUT_UNCERTAINTY,
       "Expanded uncertainty (k = 2) of the temperature, 0.1 K per code", "uncertainty"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstRatioTempOutput", values);
    g_once_init_leave(&type, t);
  }
  return type;
}
