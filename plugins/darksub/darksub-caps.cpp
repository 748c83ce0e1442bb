/* darksub's caps: what it makes of raw input and what raw input gives a mosaic. */
#include <cmath>

#include "darksub-private.h"
#include "pyrocam-caps.h"
#include "pyrocam/runtime/darksub.h"

#define GST_CAT_DEFAULT gst_dark_sub_debug

namespace pyrocam::gst::darksub {

const char* pattern_name(GstDarkSubPattern p) {
  switch (p) {
    case GST_DARK_SUB_PATTERN_RGGB:
      return "rggb";
    case GST_DARK_SUB_PATTERN_BGGR:
      return "bggr";
    case GST_DARK_SUB_PATTERN_GRBG:
      return "grbg";
    case GST_DARK_SUB_PATTERN_GBRG:
      return "gbrg";
    case GST_DARK_SUB_PATTERN_5X5:
      return PYROCAM_SNAPSHOT_PATTERN_NAME;
    case GST_DARK_SUB_PATTERN_AUTO:
      return nullptr;
  }
  return nullptr;
}

namespace {

/* Gray input: the caps' pattern wins (set_caps refuses a property that disagrees); without one
 * the property's, and with neither any pattern: set_caps refuses it. The bit depth: the caps',
 * else the property's, else the sample size (for GRAY8: `shallow`). */
void set_gray_layout(const GstStructure* s, const Settings& settings, int shallow,
                     GstStructure* out) {
  const GValue* caps_pattern = gst_structure_get_value(s, PYROCAM_FIELD_PATTERN);
  const char* property_pattern = pattern_name(settings.pattern);
  copy_fields(s, out, {PYROCAM_FIELD_BAND_MAP});
  if (caps_pattern) {
    gst_structure_set_value(out, "pattern", caps_pattern);
  } else if (property_pattern) {
    gst_structure_set(out, "pattern", G_TYPE_STRING, property_pattern, nullptr);
  } else {
    set_list_field(out, "pattern", PYROCAM_PATTERNS);
  }
  const char* format = gst_structure_get_string(s, "format");
  if (format && g_str_equal(format, "GRAY8")) {
    gst_structure_set(out, "bit-depth", G_TYPE_INT, shallow, nullptr);
  } else if (format && g_str_equal(format, "GRAY16_LE")) {
    const int caps_bits = structure_int(s, PYROCAM_FIELD_BIT_DEPTH, 0);
    gst_structure_set(out, "bit-depth", G_TYPE_INT,
                      caps_bits > 0            ? caps_bits
                      : settings.bit_depth > 0 ? settings.bit_depth
                                               : 16,
                      nullptr);
  } else {
    GValue list = G_VALUE_INIT, v = G_VALUE_INIT;
    gst_value_list_init(&list, 2);
    g_value_init(&v, G_TYPE_INT);
    g_value_set_int(&v, shallow);
    gst_value_list_append_value(&list, &v);
    const int deep = settings.bit_depth > 0 ? settings.bit_depth : 16;
    if (deep != shallow) {
      g_value_set_int(&v, deep);
      gst_value_list_append_value(&list, &v);
    }
    gst_structure_take_value(out, "bit-depth", &list);
    g_value_unset(&v);
  }
}

/* The raw level at and above which pixels are marked +INF, when it is known here. */
void set_saturation_level(const GstStructure* s, const Settings& settings, GstStructure* out) {
  int bits = 0;
  const int caps_level = structure_int(s, PYROCAM_FIELD_SATURATION_LEVEL, -1);
  if (settings.saturation_level >= 0)
    gst_structure_set(out, PYROCAM_FIELD_SATURATION_LEVEL, G_TYPE_INT,
                      static_cast<int>(std::ceil(settings.saturation_level)), nullptr);
  else if (caps_level >= 0)
    gst_structure_set(out, PYROCAM_FIELD_SATURATION_LEVEL, G_TYPE_INT, caps_level, nullptr);
  else if (gst_structure_get_int(out, "bit-depth", &bits) && bits >= 1 && bits <= 16)
    gst_structure_set(out, PYROCAM_FIELD_SATURATION_LEVEL, G_TYPE_INT,
                      static_cast<int>(std::ceil(pyrocam::default_saturation_level(bits))),
                      nullptr);
}

}  // namespace

GstStructure* mosaic_structure(const GstStructure* s, const Settings& settings) {
  /* Bit depth of 8-bit input: the property when it fits (set_caps refuses one that does not). */
  const int shallow = settings.bit_depth > 0 && settings.bit_depth <= 8 ? settings.bit_depth : 8;
  GstStructure* out =
      gst_structure_new(PYROCAM_MOSAIC_MEDIA_TYPE, "format", G_TYPE_STRING, "F32LE", nullptr);
  copy_dimensions(s, out);
  if (gst_structure_has_name(s, PYROCAM_BAYER_MEDIA_TYPE)) {
    const GValue* format = gst_structure_get_value(s, "format");
    if (format)
      gst_structure_set_value(out, "pattern", format);
    else
      gst_structure_set(out, "pattern", G_TYPE_STRING, "rggb", nullptr);
    gst_structure_set(out, "bit-depth", G_TYPE_INT, shallow, nullptr);
  } else {
    set_gray_layout(s, settings, shallow, out);
  }
  set_saturation_level(s, settings, out);
  return out;
}

GstCaps* raw_caps(const GstStructure* s) {
  const GValue* pattern = gst_structure_get_value(s, "pattern");
  GstCaps* bayer = gst_caps_from_string(PYROCAM_RAW_BAYER_CAPS);
  GstStructure* b = gst_caps_get_structure(bayer, 0);
  if (pattern) {
    GValue all = G_VALUE_INIT, common = G_VALUE_INIT;
    g_value_init(&all, GST_TYPE_LIST);
    gst_value_deserialize(&all, PYROCAM_BAYER_FORMATS);
    if (gst_value_intersect(&common, pattern, &all)) {
      gst_structure_take_value(b, "format", &common);
    } else {
      gst_caps_remove_structure(bayer, 0);
      b = nullptr;
    }
    g_value_unset(&all);
  }
  if (b) copy_dimensions(s, b);
  GstCaps* gray = gst_caps_from_string(PYROCAM_RAW_GRAY_CAPS);
  copy_dimensions(s, gst_caps_get_structure(gray, 0));
  return gst_caps_merge(bayer, gray);
}

}  // namespace pyrocam::gst::darksub
