/* darksub's GObject properties. */
#include <cstdio>
#include <string>

#include "darksub-private.h"
#include "pyrocam/runtime/darksub.h"

#define GST_CAT_DEFAULT gst_dark_sub_debug

namespace pyrocam::gst::darksub {
namespace {

enum {
  PROP_0,
  PROP_LOCATION,
  PROP_DARK_LEVEL,
  PROP_SATURATION_LEVEL,
  PROP_CAPTURE_FRAMES,
  PROP_PATTERN,
  PROP_BIT_DEPTH,
};

}  // namespace

void install_properties(GObjectClass* gobject_class) {
  const auto ready = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                              GST_PARAM_MUTABLE_READY);
  const auto playing = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING | GST_PARAM_CONTROLLABLE);
  g_object_class_install_property(
      gobject_class, PROP_LOCATION,
      g_param_spec_string("location", "Dark frame file",
                          "Dark frame image (PGM, PNG or TIFF of the frame's size and sample "
                          "depth: 8 bit for 8-bit input, 16 bit for GRAY16_LE) "
                          "taken at the same exposure with the lens covered; empty: none",
                          nullptr, ready));
  g_object_class_install_property(
      gobject_class, PROP_DARK_LEVEL,
      g_param_spec_double("dark-level", "Constant dark level",
                          "Dark level in DN subtracted from every pixel when there is no dark "
                          "frame (0..65535); -1: a dark frame is required",
                          -1.0, 65535.0, DEFAULT_DARK_LEVEL, playing));
  g_object_class_install_property(
      gobject_class, PROP_SATURATION_LEVEL,
      g_param_spec_double("saturation-level", "Saturation level",
                          "Raw value in DN (before dark subtraction) at and above which a "
                          "pixel is marked saturated (+INF) (0..65535); -1: the caps' "
                          "saturation-level (pyrocamsrc: the camera profile's inference "
                          "threshold), else 220/255 of the full scale of the bit depth (220 for "
                          "8 bit)",
                          -1.0, 65535.0, DEFAULT_SATURATION_LEVEL, playing));
  g_object_class_install_property(
      gobject_class, PROP_CAPTURE_FRAMES,
      g_param_spec_int("capture-frames", "Dark capture frames",
                       "Number of frames capture-dark averages into a dark frame (1..1000)", 1,
                       1000, DEFAULT_CAPTURE_FRAMES,
                       static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING)));
  g_object_class_install_property(
      gobject_class, PROP_PATTERN,
      g_param_spec_enum("pattern", "Mosaic pattern",
                        "Mosaic layout of the input. auto: from the caps (the format of "
                        "video/x-bayer, the pattern field of GRAY8/GRAY16_LE); gray input "
                        "without a pattern field must be told one. A pattern that differs from "
                        "the caps' is refused (CORE NEGOTIATION)",
                        GST_TYPE_DARK_SUB_PATTERN, DEFAULT_PATTERN, ready));
  g_object_class_install_property(
      gobject_class, PROP_BIT_DEPTH,
      g_param_spec_int("bit-depth", "Bit depth",
                       "Significant bits of the input samples, e.g. 12 for a 12-bit camera "
                       "carried as GRAY16_LE (0..16; at most 8 for GRAY8 and video/x-bayer, "
                       "which are refused otherwise; 0: the full sample size, 8 or 16)",
                       0, 16, DEFAULT_BIT_DEPTH, ready));
}

bool use_dark_level(GstElement* element, double level, int bit_depth, double& in_use,
                    double& refused) {
  if (level == in_use) return true;
  const int full_scale = pyrocam::full_scale_dn(bit_depth);
  if (level <= full_scale) {
    in_use = level;
    return true;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%g", level);
  const std::string what = std::string(GST_OBJECT_NAME(element)) + ": dark-level " + text +
                           " is above the " + std::to_string(bit_depth) + "-bit full scale (" +
                           std::to_string(full_scale) + " DN)";
  if (in_use < 0) {
    PYROCAM_POST_ERROR(element, ErrorKind::kSettings, what, "dark-level out of the stream's range");
    return false;
  }
  if (level != refused) {
    refused = level;
    GST_ELEMENT_WARNING(element, RESOURCE, SETTINGS,
                        ("%s: refused, %g DN stays subtracted", what.c_str(), in_use),
                        ("dark-level set while playing out of the stream's range"));
  }
  return true;
}

void set_property(GObject* object, guint prop_id, const GValue* value, GParamSpec* pspec) {
  GstDarkSub* self = GST_DARK_SUB(object);
  const char* refused = nullptr;  // a property refused while running, posted once unlocked
  {
    ObjectLock lock(self);
    Settings& s = *self->settings;
    switch (prop_id) {
      case PROP_LOCATION:
        if (GST_STATE(self) > GST_STATE_READY) {
          refused = "location";
        } else {
          const char* v = g_value_get_string(value);
          s.location = v ? v : "";
        }
        break;
      case PROP_DARK_LEVEL:
        s.dark_level = g_value_get_double(value);
        break;
      case PROP_SATURATION_LEVEL:
        s.saturation_level = g_value_get_double(value);
        break;
      case PROP_CAPTURE_FRAMES:
        s.capture_frames = g_value_get_int(value);
        break;
      case PROP_PATTERN:
        if (GST_STATE(self) > GST_STATE_READY)
          refused = "pattern";
        else
          s.pattern = static_cast<GstDarkSubPattern>(g_value_get_enum(value));
        break;
      case PROP_BIT_DEPTH:
        if (GST_STATE(self) > GST_STATE_READY)
          refused = "bit-depth";
        else
          s.bit_depth = g_value_get_int(value);
        break;
      default:
        G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
        break;
    }
  }
  if (refused) pyrocam::gst::warn_not_changeable_while_running(GST_ELEMENT(self), refused);
  /* The saturation level is in the output caps: renegotiate, so that ratiotemp sees it. */
  if (prop_id == PROP_SATURATION_LEVEL)
    gst_base_transform_reconfigure_src(GST_BASE_TRANSFORM(self));
}

void get_property(GObject* object, guint prop_id, GValue* value, GParamSpec* pspec) {
  GstDarkSub* self = GST_DARK_SUB(object);
  ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_LOCATION:
      g_value_set_string(value, s.location.empty() ? nullptr : s.location.c_str());
      break;
    case PROP_DARK_LEVEL:
      g_value_set_double(value, s.dark_level);
      break;
    case PROP_SATURATION_LEVEL:
      g_value_set_double(value, s.saturation_level);
      break;
    case PROP_CAPTURE_FRAMES:
      g_value_set_int(value, s.capture_frames);
      break;
    case PROP_PATTERN:
      g_value_set_enum(value, s.pattern);
      break;
    case PROP_BIT_DEPTH:
      g_value_set_int(value, s.bit_depth);
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

}  // namespace pyrocam::gst::darksub

GType gst_dark_sub_pattern_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_DARK_SUB_PATTERN_RGGB, "Bayer, R G / G B", "rggb"},
      {GST_DARK_SUB_PATTERN_BGGR, "Bayer, B G / G R", "bggr"},
      {GST_DARK_SUB_PATTERN_GRBG, "Bayer, G R / B G", "grbg"},
      {GST_DARK_SUB_PATTERN_GBRG, "Bayer, G B / R G", "gbrg"},
      {GST_DARK_SUB_PATTERN_5X5, "5x5 snapshot mosaic", "5x5"},
      {GST_DARK_SUB_PATTERN_AUTO, "From the caps (video/x-bayer format, gray video's pattern)",
       "auto"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstDarkSubPattern", values);
    g_once_init_leave(&type, t);
  }
  return type;
}
