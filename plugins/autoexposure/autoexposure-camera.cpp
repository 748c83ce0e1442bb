/* autoexposure: finding the camera whose exposure it sets, and the controller's settings from
 * the camera's property ranges. */
#include <algorithm>
#include <sstream>
#include <string>

#include "autoexposure-private.h"
#include "pyrocam/core/error.h"

#define GST_CAT_DEFAULT gst_auto_exposure_debug

namespace pyrocam::gst::autoexposure {
namespace {

/* The camera whose exposure is set: the named element, or the first element upstream without a
 * sink pad (through queues, capsfilters and tees). */
GstElement* find_camera(GstAutoExposure* self, const std::string& name) {
  if (!name.empty()) {
    GstObject* top = GST_OBJECT(self);
    while (GST_OBJECT_PARENT(top)) top = GST_OBJECT_PARENT(top);
    return GST_IS_BIN(top) ? gst_bin_get_by_name_recurse_up(GST_BIN(top), name.c_str()) : nullptr;
  }
  GstElement* element = GST_ELEMENT(gst_object_ref(self));
  for (int hops = 0; hops < 64; ++hops) {
    GstPad* sink = gst_element_get_static_pad(element, "sink");
    if (!sink && element != GST_ELEMENT(self)) return element;
    GstPad* peer = sink ? gst_pad_get_peer(sink) : nullptr;
    if (sink) gst_object_unref(sink);
    gst_object_unref(element);
    if (!peer) return nullptr;
    element = gst_pad_get_parent_element(peer);
    gst_object_unref(peer);
    if (!element) return nullptr;
  }
  gst_object_unref(element);
  return nullptr;
}

}  // namespace

void look_up_camera(GstAutoExposure* self, const Settings& settings) {
  State& st = *self->state;
  st.camera_looked_up = true;
  GstElement* camera = find_camera(self, settings.camera);
  if (!camera) {
    GST_ELEMENT_WARNING(
        self, RESOURCE, SETTINGS,
        ("No camera found %s: exposure control is off",
         settings.camera.empty() ? "upstream" : ("named " + settings.camera).c_str()),
        ("find_camera returned nothing"));
    return;
  }
  GParamSpec* spec = g_object_class_find_property(G_OBJECT_GET_CLASS(camera), "exposure");
  if (!spec || G_PARAM_SPEC_VALUE_TYPE(spec) != G_TYPE_DOUBLE ||
      !(spec->flags & G_PARAM_WRITABLE)) {
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("Camera %s has no exposure property (a writable number of "
                         "microseconds): exposure control is off",
                         GST_OBJECT_NAME(camera)),
                        ("element type %s", G_OBJECT_TYPE_NAME(camera)));
    gst_object_unref(camera);
    return;
  }
  st.property_min_us = G_PARAM_SPEC_DOUBLE(spec)->minimum;
  st.property_max_us = G_PARAM_SPEC_DOUBLE(spec)->maximum;
  GParamSpec* gain = g_object_class_find_property(G_OBJECT_GET_CLASS(camera), "gain");
  st.has_gain = gain && G_PARAM_SPEC_VALUE_TYPE(gain) == G_TYPE_DOUBLE &&
                (gain->flags & G_PARAM_WRITABLE) && (gain->flags & G_PARAM_READABLE);
  if (st.has_gain) {
    st.gain_property_min_db = G_PARAM_SPEC_DOUBLE(gain)->minimum;
    st.gain_property_max_db = G_PARAM_SPEC_DOUBLE(gain)->maximum;
  }
  st.camera = camera;
  GST_INFO_OBJECT(self, "controlling the exposure of %s (%s gain property)",
                  GST_OBJECT_NAME(camera), st.has_gain ? "with a" : "without");
}

// Microseconds as a user wrote them (1e+07, 1500).
static std::string us_text(double us) {
  std::ostringstream text;
  text << us;
  return text.str();
}

pyrocam::ExposureControlSettings controller_settings(GstAutoExposure* self,
                                                     const Settings& settings) {
  State& st = *self->state;
  pyrocam::ExposureControlSettings c;
  c.target = settings.target;
  c.dark_dn = settings.dark_level;
  c.saturation_dn = st.saturation_dn;
  // The camera property's range too: a value outside it would not be set at all.
  c.min_exposure_us = std::max({settings.min_exposure_us, st.property_min_us, 1e-3});
  c.max_exposure_us = std::min(settings.max_exposure_us, st.property_max_us);
  if (settings.min_exposure_us > settings.max_exposure_us)
    throw pyrocam::InputError("min-exposure " + us_text(settings.min_exposure_us) +
                              " us is above max-exposure " + us_text(settings.max_exposure_us) +
                              " us");
  if (c.min_exposure_us > c.max_exposure_us)
    throw pyrocam::InputError("min-exposure .. max-exposure (" + us_text(settings.min_exposure_us) +
                              " .. " + us_text(settings.max_exposure_us) +
                              " us) is outside camera " + GST_OBJECT_NAME(st.camera) +
                              "'s exposure range (" + us_text(st.property_min_us) + " .. " +
                              us_text(st.property_max_us) + " us)");
  c.max_step = settings.max_step;
  c.tolerance = settings.tolerance;
  c.latency_frames = static_cast<int>(settings.latency);
  // Gain 0 dB must be settable for the exposure-first rule; else exposure control only.
  const bool gain_usable = st.has_gain && st.gain_property_min_db <= 0;
  if (settings.max_gain_db > 0 && !gain_usable && !st.warned_no_gain) {
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                        ("Camera %s has no gain property (a writable number of dB from 0): "
                         "max-gain is ignored, only the exposure is controlled",
                         GST_OBJECT_NAME(st.camera)),
                        ("element type %s", G_OBJECT_TYPE_NAME(st.camera)));
    st.warned_no_gain = true;
  }
  c.max_gain_db = gain_usable ? std::min(settings.max_gain_db, st.gain_property_max_db) : 0.0;
  return c;
}

}  // namespace pyrocam::gst::autoexposure
