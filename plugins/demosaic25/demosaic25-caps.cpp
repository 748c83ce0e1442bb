/* demosaic25's caps: a mosaic's caps become band planes' (and the fused path's mosaic) and
 * back. */
#include <algorithm>

#include "demosaic25-private.h"

#define GST_CAT_DEFAULT gst_demosaic25_debug

namespace pyrocam::gst::demosaic25 {
namespace {

namespace pg = pyrocam::gst;

/* A dimension scaled by 1/divisor (forward) or by divisor (backward, any remainder allowed). */
void scale_dimension(const GstStructure* from, GstStructure* to, const char* field, int divisor,
                     bool forward) {
  const GValue* v = gst_structure_get_value(from, field);
  if (v && G_VALUE_HOLDS_INT(v)) {
    const int n = g_value_get_int(v);
    if (divisor == 1)
      gst_structure_set(to, field, G_TYPE_INT, n, nullptr);
    else if (forward)
      gst_structure_set(to, field, G_TYPE_INT, std::max(1, n / divisor), nullptr);
    else if (n <= G_MAXINT / divisor - 1)
      gst_structure_set(to, field, GST_TYPE_INT_RANGE, n * divisor, n * divisor + divisor - 1,
                        nullptr);
    else
      gst_structure_set(to, field, GST_TYPE_INT_RANGE, 1, G_MAXINT, nullptr);
  } else {
    gst_structure_set(to, field, GST_TYPE_INT_RANGE, 1, G_MAXINT, nullptr);
  }
}

}  // namespace

GstCaps* transform_caps(GstBaseTransform* trans, GstPadDirection direction, GstCaps* caps,
                        GstCaps* filter) {
  GstDemosaic25* self = GST_DEMOSAIC25(trans);
  const Settings settings = copy_settings(self);
  const int bayer_divisor = settings.method == GST_DEMOSAIC25_METHOD_BIN2X2 ? 2 : 1;
  const std::string profile_band_map = pg::locked_copy(self, self->state->profile_band_map);
  const bool forward = direction == GST_PAD_SINK;
  const bool fusable = fused_path_allowed(settings);
  GstCaps* result = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    const GstStructure* s = gst_caps_get_structure(caps, i);
    // Fused bands come from a Bayer mosaic demosaicked with matched, without the check.
    if (!forward && pg::is_fused_bands(caps, i) && !fusable) continue;
    /* Which layouts this structure allows. */
    bool bayer = true, snapshot = true;
    const char* fixed = gst_structure_get_string(s, forward ? "pattern" : "layout");
    if (fixed) {
      snapshot = is_snapshot(fixed);
      bayer = !snapshot;
    }
    for (int pass = 0; pass < 2; ++pass) {
      const bool snap = pass == 1;
      if ((snap && !snapshot) || (!snap && !bayer)) continue;
      const int divisor = snap ? 5 : bayer_divisor;
      GstStructure* out;
      if (forward) {
        out = gst_structure_new(PYROCAM_BANDS_MEDIA_TYPE, "format", G_TYPE_STRING, "F32LE", "bands",
                                G_TYPE_INT, snap ? 25 : 3, "layout", G_TYPE_STRING,
                                snap ? PYROCAM_SNAPSHOT_PATTERN_NAME : "bayer", nullptr);
        if (snap) {
          /* The band order of the planes: the profile's, else the input's, else row * 5 +
           * column (set_caps refuses a profile and an input that disagree). */
          const char* in_map = gst_structure_get_string(s, PYROCAM_FIELD_BAND_MAP);
          std::string map = profile_band_map.empty() ? (in_map ? in_map : "") : profile_band_map;
          if (map.empty())
            map = pg::band_map_text(pg::layout_for_pattern(PYROCAM_SNAPSHOT_PATTERN_NAME));
          gst_structure_set(out, PYROCAM_FIELD_BAND_MAP, G_TYPE_STRING, map.c_str(), nullptr);
        }
      } else {
        out = gst_structure_new(PYROCAM_MOSAIC_MEDIA_TYPE, "format", G_TYPE_STRING, "F32LE",
                                "bit-depth", GST_TYPE_INT_RANGE, 1, 16, nullptr);
        if (snap) {
          gst_structure_set(out, "pattern", G_TYPE_STRING, PYROCAM_SNAPSHOT_PATTERN_NAME, nullptr);
        } else {
          pg::set_list_field(out, "pattern", PYROCAM_BAYER_FORMATS);
        }
      }
      if (forward) {
        pg::copy_fields(s, out, {PYROCAM_FIELD_SATURATION_LEVEL});
        // How the planes were made, for the noise of their values (ratiotemp's uncertainty).
        gst_structure_set(out, PYROCAM_FIELD_DEMOSAIC, G_TYPE_STRING, method_name(settings.method),
                          nullptr);
        if (!snap)
          if (const char* p = gst_structure_get_string(s, "pattern"))
            gst_structure_set(out, "pattern", G_TYPE_STRING, p, nullptr);
      }
      if (!forward && pg::is_fused_bands(caps, i)) pg::copy_fields(s, out, {"pattern"});
      scale_dimension(s, out, "width", divisor, forward);
      scale_dimension(s, out, "height", divisor, forward);
      pg::copy_fields(s, out, {"framerate"});
      // The planes as their mosaic, after the planes themselves: ratiotemp asks for it first,
      // any other element (or a sink taking anything) gets the planes.
      GstStructure* fused = forward && !snap && fusable ? gst_structure_copy(out) : nullptr;
      result = gst_caps_merge_structure(result, out);
      if (fused) {
        if (const char* p = gst_structure_get_string(s, "pattern"))
          gst_structure_set(fused, "pattern", G_TYPE_STRING, p, nullptr);
        else
          pg::set_list_field(fused, "pattern", PYROCAM_BAYER_FORMATS);
        result = gst_caps_merge_structure_full(
            result, fused, gst_caps_features_new(PYROCAM_CAPS_FEATURE_MOSAIC, nullptr));
      }
    }
  }
  if (filter) {
    GstCaps* tmp = gst_caps_intersect_full(filter, result, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(result);
    result = tmp;
  }
  GST_DEBUG_OBJECT(self, "transformed %" GST_PTR_FORMAT " to %" GST_PTR_FORMAT, caps, result);
  return result;
}

gboolean transform_size(GstBaseTransform* /*trans*/, GstPadDirection direction, GstCaps* /*caps*/,
                        gsize /*size*/, GstCaps* othercaps, gsize* othersize) {
  const GstStructure* s = gst_caps_get_structure(othercaps, 0);
  const gsize w = static_cast<gsize>(pg::structure_int(s, "width", 0));
  const gsize h = static_cast<gsize>(pg::structure_int(s, "height", 0));
  const gsize planes =
      direction == GST_PAD_SINK ? static_cast<gsize>(pg::structure_int(s, "bands", 0)) : 1;
  *othersize = w * h * planes * sizeof(float);
  return *othersize > 0;
}

}  // namespace pyrocam::gst::demosaic25
