/* ratiotemp's formats: the caps' transforms between band planes and temperatures, the layout
 * name a model expects, the band values' noise the caps' demosaicking leaves, and the output buffer
 * mapped as a GRAY16_LE frame. */
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "ratiotemp-private.h"

#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pyrocam::gst::ratiotemp {

namespace pg = pyrocam::gst;

const char* layout_name(const pyrocam::ThermalModel& model) {
  return model.profile().mosaic.kind == pyrocam::MosaicLayout::Kind::kSnapshot
             ? PYROCAM_SNAPSHOT_PATTERN_NAME
             : "bayer";
}

pyrocam::DemosaicNoise demosaic_noise_of(GstElement* element, const GstStructure* caps,
                                         const pyrocam::ThermalModel& model) {
  const char* made = gst_structure_get_string(caps, PYROCAM_FIELD_DEMOSAIC);
  if (!made) return {};
  const char* pattern = gst_structure_get_string(caps, "pattern");
  const pyrocam::MosaicLayout& layout = model.profile().mosaic;
  try {
    const pyrocam::DemosaicMethod method = pyrocam::parse_demosaic_method(made);
    if (layout.kind == pyrocam::MosaicLayout::Kind::kSnapshot)
      return pyrocam::demosaic_noise(layout, method);
    if (pattern) return pyrocam::demosaic_noise(pg::layout_for_pattern(pattern), method);
  } catch (const pyrocam::InputError& e) {
    // Not a reason to refuse the planes: their uncertainty then takes one sample's noise.
    GST_WARNING_OBJECT(element, "demosaic=%s, pattern=%s in the caps: %s", made,
                       pattern ? pattern : "(none)", e.what());
  }
  return {};
}

MappedFrame::MappedFrame(GstBuffer* buffer, GstVideoInfo* info) {
  if (!gst_video_frame_map(&frame, info, buffer, GST_MAP_WRITE))
    throw pyrocam::InputError("cannot map a " + std::to_string(gst_buffer_get_size(buffer)) +
                              "-byte buffer as a " + std::to_string(GST_VIDEO_INFO_WIDTH(info)) +
                              "x" + std::to_string(GST_VIDEO_INFO_HEIGHT(info)) +
                              " GRAY16_LE frame");
  image = cv::Mat(GST_VIDEO_FRAME_HEIGHT(&frame), GST_VIDEO_FRAME_WIDTH(&frame), CV_16U,
                  GST_VIDEO_FRAME_PLANE_DATA(&frame, 0),
                  static_cast<std::size_t>(GST_VIDEO_FRAME_PLANE_STRIDE(&frame, 0)));
}

MappedFrame::~MappedFrame() { gst_video_frame_unmap(&frame); }

GstCaps* transform_caps(GstBaseTransform* trans, GstPadDirection direction, GstCaps* caps,
                        GstCaps* filter) {
  /* The band count and layout are not restricted to the model's here: set_caps checks them and
   * names both in its error, which a failed negotiation would not. Towards the sink: the fused
   * bands first (demosaic25 then hands on the mosaic and the planes never cross memory), then
   * the planes. */
  const bool to_sink = direction == GST_PAD_SRC;
  GstCaps* templ = gst_caps_from_string(to_sink ? PYROCAM_FUSED_BANDS_CAPS "; " PYROCAM_BANDS_CAPS
                                                : PYROCAM_TEMPERATURE_CAPS);
  GstCaps* result = gst_caps_new_empty();
  for (guint i = 0; i < gst_caps_get_size(caps); ++i) {
    for (guint t = 0; t < gst_caps_get_size(templ); ++t) {
      GstStructure* out = gst_structure_copy(gst_caps_get_structure(templ, t));
      pg::copy_dimensions(gst_caps_get_structure(caps, i), out);
      result = gst_caps_merge_structure_full(
          result, out, gst_caps_features_copy(gst_caps_get_features(templ, t)));
    }
  }
  gst_caps_unref(templ);
  if (filter) {
    /* This element's order first towards the sink: it prefers the fused bands. */
    GstCaps* tmp = to_sink ? gst_caps_intersect_full(result, filter, GST_CAPS_INTERSECT_FIRST)
                           : gst_caps_intersect_full(filter, result, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(result);
    result = tmp;
  }
  GST_DEBUG_OBJECT(trans, "transformed %" GST_PTR_FORMAT " to %" GST_PTR_FORMAT, caps, result);
  return result;
}

gboolean transform_size(GstBaseTransform* trans, GstPadDirection direction, GstCaps* /*caps*/,
                        gsize /*size*/, GstCaps* othercaps, gsize* othersize) {
  if (direction == GST_PAD_SINK) {
    GstVideoInfo info;
    if (!gst_video_info_from_caps(&info, othercaps)) {
      GST_WARNING_OBJECT(trans, "cannot size %" GST_PTR_FORMAT, othercaps);
      return FALSE;
    }
    *othersize = GST_VIDEO_INFO_SIZE(&info);
    return TRUE;
  }
  *othersize = pg::frame_size_of_caps(othercaps);
  return *othersize > 0;
}

}  // namespace pyrocam::gst::ratiotemp
