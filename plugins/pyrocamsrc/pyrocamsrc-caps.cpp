/* pyrocamsrc's caps: what a profile's sensor gives, and why a negotiation failed. */
#include <algorithm>
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocamsrc-private.h"

namespace pyrocam::gst::pyrocamsrc {

namespace {

/* The caps' text without the size and rate ranges every structure repeats and the band map, at
 * most 300 bytes. */
std::string caps_summary(const GstCaps* caps) {
  GstCaps* shown = gst_caps_copy(caps);
  for (guint i = 0; i < gst_caps_get_size(shown); ++i)
    gst_structure_remove_fields(gst_caps_get_structure(shown, i), "width", "height", "framerate",
                                PYROCAM_FIELD_BAND_MAP, nullptr);
  shown = gst_caps_simplify(shown);
  gchar* text = gst_caps_to_string(shown);
  std::string summary = text;
  g_free(text);
  gst_caps_unref(shown);
  if (summary.size() > 300) summary = summary.substr(0, 300) + "...";
  return summary;
}

}  // namespace

GstCaps* profile_caps(const CameraProfile& profile) {
  std::string caps;
  std::string pattern = profile.mosaic.pattern;
  for (char& c : pattern) c = static_cast<char>(g_ascii_tolower(c));
  if (profile.mosaic.kind == MosaicLayout::Kind::kBayer && profile.bit_depth == 8) {
    caps = PYROCAM_BAYER_MEDIA_TYPE ", format = (string) " + pattern;
  } else {
    /* The layout and depth travel in the caps (pyrocam-caps.h), so that darksub cannot read
     * the mosaic as another one. */
    if (profile.mosaic.kind == MosaicLayout::Kind::kSnapshot)
      pattern = std::to_string(profile.mosaic.period_width) + "x" +
                std::to_string(profile.mosaic.period_height);
    caps =
        std::string(PYROCAM_VIDEO_MEDIA_TYPE ", format = (string) ") +
        (profile.bit_depth == 8 ? "GRAY8" : "GRAY16_LE") +
        ", " PYROCAM_FIELD_PATTERN " = (string) " + pattern +
        ", " PYROCAM_FIELD_BIT_DEPTH " = (int) " + std::to_string(profile.bit_depth) +
        ", " PYROCAM_FIELD_SATURATION_LEVEL " = (int) " +
        std::to_string(static_cast<int>(std::lround(profile.thresholds.inference_saturation_dn)));
    if (profile.mosaic.kind == MosaicLayout::Kind::kSnapshot)
      caps += ", " PYROCAM_FIELD_BAND_MAP " = (string) \"" + band_map_text(profile.mosaic) + "\"";
  }
  // 0/1 too, so that caps asking for it reach set_caps and its error names it (else only
  // "not-negotiated").
  caps += ", " PYROCAM_SIZE_RANGE ", " PYROCAM_FRAMERATE_RANGE;
  return gst_caps_from_string(caps.c_str());
}

void explain_refused_caps(GstElement* element, GstPad* src_pad, const CameraProfile& profile) {
  GstCaps* ours = profile_caps(profile);
  GstCaps* theirs = gst_pad_peer_query_caps(src_pad, nullptr);
  // Otherwise the caps met and set_caps refused them, with its own error.
  if (theirs && !gst_caps_can_intersect(ours, theirs))
    PYROCAM_POST_ERROR(element, ErrorKind::kNegotiation,
                       std::string(GST_OBJECT_NAME(element)) + ": the camera of profile " +
                           profile.name + " gives " + caps_summary(ours) +
                           ", which downstream does not take (it takes " + caps_summary(theirs) +
                           "); the format follows the profile's sensor",
                       "no common caps with the downstream peer");
  gst_caps_unref(ours);
  if (theirs) gst_caps_unref(theirs);
}

void propose_own_pool(GstQuery* query, gsize frame_size) {
  GstCaps* caps = nullptr;
  gst_query_parse_allocation(query, &caps, nullptr);
  const auto size = static_cast<guint>(frame_size);
  GstBufferPool* pool = gst_buffer_pool_new();
  GstStructure* config = gst_buffer_pool_get_config(pool);
  gst_buffer_pool_config_set_params(config, caps, size, 0, 0);
  gst_buffer_pool_set_config(pool, config);
  if (gst_query_get_n_allocation_pools(query) > 0)
    gst_query_set_nth_allocation_pool(query, 0, pool, size, 0, 0);
  else
    gst_query_add_allocation_pool(query, pool, size, 0, 0);
  gst_object_unref(pool);
}

}  // namespace pyrocam::gst::pyrocamsrc
