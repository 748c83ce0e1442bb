/* ratiotemp's formats: the caps' transforms between band planes and temperatures, the layout
 * name a model expects, the band values' noise the caps' demosaicking leaves, and the output buffer
 * mapped as a GRAY16_LE frame. */
#include <cmath>
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

Mismatch model_mismatch(const GstStructure* in, const pyrocam::ThermalModel& model,
                        const std::string& model_path) {
  const pyrocam::CameraProfile& profile = model.profile();
  const std::string which = "model " + model_path + " (" + profile.name + ")";
  const int bands = pg::structure_int(in, "bands", 0);
  const char* layout = gst_structure_get_string(in, "layout");
  const std::string model_layout = layout_name(model);
  if (bands != profile.band_count() || !layout || model_layout != layout)
    return {"Model " + model_path + " (" + profile.name + ") is for " +
                std::to_string(profile.band_count()) + " bands of a " + model_layout +
                " mosaic, the stream has " + std::to_string(bands) + " bands of a " +
                (layout ? layout : "(no layout)") + " mosaic",
            "band count or layout of the sink caps differs from the model's"};
  // Pixels the model's camera calls saturated must come marked: darksub's level must not be
  // above the model profile's inference saturation threshold.
  const int level = pg::structure_int(in, PYROCAM_FIELD_SATURATION_LEVEL, -1);
  const double model_level = profile.thresholds.inference_saturation_dn;
  const int model_full_scale = (1 << profile.bit_depth) - 1;
  if (level > model_full_scale)  // the band planes do not say their depth; this does
    return {"darksub marks pixels saturated from " + std::to_string(level) + " DN, beyond the " +
                std::to_string(model_full_scale) + " DN full scale of the " +
                std::to_string(profile.bit_depth) + "-bit camera of " + which +
                ": the stream is deeper than the model's camera; calibrate a model at the depth "
                "the camera streams, or set the camera to the model's",
            "saturation-level of the sink caps beyond the model profile's full scale"};
  if (level > std::ceil(model_level))
    return {"darksub marks pixels saturated from " + std::to_string(level) + " DN, above the " +
                std::to_string(std::lround(model_level)) + " DN of " + which +
                ": set darksub saturation-level=" + std::to_string(std::lround(model_level)),
            "saturation-level of the sink caps above the model profile's threshold"};
  // 5x5: the planes must be in the model's band order.
  const char* band_map = gst_structure_get_string(in, PYROCAM_FIELD_BAND_MAP);
  if (band_map && profile.mosaic.kind == pyrocam::MosaicLayout::Kind::kSnapshot &&
      pg::band_map_text(profile.mosaic) != band_map)
    return {"Model " + model_path + " (" + profile.name + ") expects the 5x5 bands in the order " +
                pg::band_map_text(profile.mosaic) + ", the stream's planes are in the order " +
                band_map + ": give demosaic25 the camera's profile",
            "band-map of the sink caps differs from the model profile's"};
  return {};
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
