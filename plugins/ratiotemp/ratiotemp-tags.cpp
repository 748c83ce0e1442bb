/* ratiotemp's tags: what a recording of its output says about itself. Matroska keeps a stream's
 * title and comment (matroskamux drops extended-comment, description and custom tags), so the
 * facts go into the comment as "key=value" fields. */
#include <gst/gst.h>

#include <filesystem>
#include <utility>

#include "pyrocam/core/recording_comment.h"
#include "ratiotemp-private.h"

#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pyrocam::gst::ratiotemp {
namespace {

// GST_TAG_CAPTURING_SHUTTER_SPEED (libgsttag, which the plugin does not link): a fraction, s.
constexpr const char* CAPTURING_SHUTTER_SPEED = "capturing-shutter-speed";

std::string clean(std::string value) { return recording_comment_value(std::move(value)); }
std::string number(double v) { return recording_comment_number(v); }

}  // namespace

std::string recording_title(bool uncertainty) {
  return uncertainty ? "pyrocam expanded uncertainty (k = 2): 0.1 K per code, 0 = no reading"
                     : "pyrocam temperature: 0.1 K per code (degC = code / 10 - 273.15), "
                       "0 = no reading";
}

std::string recording_comment(const RecordingInfo& info) {
  std::string c = std::string(kTemperatureRecordingMark) +
                  "; quantity=" + (info.uncertainty ? "expanded-uncertainty" : "temperature") +
                  "; unit=0.1 K; no-reading=0";
  c += "; model=" + clean(std::filesystem::path(info.model_file).filename().string());
  c += "; model-fingerprint=" + clean(info.fingerprint);
  c += "; profile=" + clean(info.profile);
  c += "; method=" + clean(info.method);
  c += "; e-slope=" + number(info.e_slope) + " %/100 nm";
  c += "; partial-bands=" + clean(info.partial_bands);
  c += "; misfit-probability=" + number(info.misfit_probability);
  c += std::string("; blur-correction=") + (info.blur_correction ? "on" : "off");
  c += "; brightness-radius=" + std::to_string(info.brightness_radius);
  if (!info.demosaic.empty()) c += "; demosaic=" + clean(info.demosaic);
  if (info.exposure_us > 0) c += "; exposure=" + number(info.exposure_us) + " us";
  return c;
}

double exposure_us_of(const GstTagList* tags) {
  gint n = 0, d = 0;
  const GValue* v = tags ? gst_tag_list_get_value_index(tags, CAPTURING_SHUTTER_SPEED, 0) : nullptr;
  if (!v || !GST_VALUE_HOLDS_FRACTION(v)) return -1;
  n = gst_value_get_fraction_numerator(v);
  d = gst_value_get_fraction_denominator(v);
  return n > 0 && d > 0 ? 1e6 * n / d : -1;
}

GstTagList* recording_tags(const RecordingInfo& info, const GstTagList* upstream) {
  GstTagList* tags = upstream ? gst_tag_list_copy(upstream) : gst_tag_list_new_empty();
  gst_tag_list_set_scope(tags, GST_TAG_SCOPE_STREAM);
  gst_tag_list_add(tags, GST_TAG_MERGE_REPLACE, GST_TAG_TITLE,
                   recording_title(info.uncertainty).c_str(), GST_TAG_COMMENT,
                   recording_comment(info).c_str(), nullptr);
  return tags;
}

void push_recording_tags(GstRatioTemp* self, const RecordingInfo& info, const GstTagList* upstream,
                         std::string& pushed_comment) {
  std::string comment = recording_comment(info);
  if (comment == pushed_comment) return;
  GST_INFO_OBJECT(self, "tags: %s", comment.c_str());
  pushed_comment = std::move(comment);
  gst_pad_push_event(GST_BASE_TRANSFORM_SRC_PAD(self),
                     gst_event_new_tag(recording_tags(info, upstream)));
}

void push_stream_tags(GstRatioTemp* self, const Settings& settings, State& st) {
  RecordingInfo info;
  info.model_file = st.model_path;
  info.fingerprint = st.model->fingerprint;
  info.profile = st.model->profile().name;
  info.method = pyrocam::method_name(st.method);
  info.uncertainty = settings.output == GST_RATIO_TEMP_OUTPUT_UNCERTAINTY;
  info.e_slope = settings.e_slope;
  info.partial_bands = settings.allow_partial                                  ? "any"
                       : settings.partial_bands == GST_RATIO_TEMP_PARTIAL_ANY  ? "any"
                       : settings.partial_bands == GST_RATIO_TEMP_PARTIAL_SAFE ? "safe"
                                                                               : "off";
  info.misfit_probability = settings.misfit_probability;
  // What was applied: both need the fused path (brightness readings, on a Bayer mosaic), and are
  // left out (with a warning) without it.
  info.blur_correction = settings.blur_correction && st.fused;
  info.brightness_radius = st.fused || st.snapshot ? settings.brightness_radius : 0;
  info.demosaic = st.demosaic;
  info.exposure_us = exposure_us_of(st.upstream_tags.get());
  push_recording_tags(self, info, st.upstream_tags.get(), st.pushed_comment);
}

}  // namespace pyrocam::gst::ratiotemp
