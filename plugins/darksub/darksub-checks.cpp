/* darksub's check of the dark it subtracts. */
#include <cstdio>
#include <optional>
#include <string>

#include "darksub-private.h"
#include "pyrocam/runtime/darksub.h"

#define GST_CAT_DEFAULT gst_dark_sub_debug

namespace pyrocam::gst::darksub {

double saturation_in_use(const Settings& settings, int caps_level, int bit_depth) {
  return settings.saturation_level >= 0 ? settings.saturation_level
         : caps_level >= 0              ? caps_level
                                        : pyrocam::default_saturation_level(bit_depth);
}

bool saturation_above_dark(GstElement* element, const Settings& settings, double saturation) {
  if (!settings.location.empty() || settings.dark_level < 0 || saturation > settings.dark_level)
    return true;
  char text[96];
  std::snprintf(text, sizeof text, "saturation-level %g DN is at or below dark-level %g DN",
                saturation, settings.dark_level);
  PYROCAM_POST_ERROR(element, ErrorKind::kSettings,
                     std::string(text) + ": every pixel would be marked saturated",
                     "saturation level not above the dark level");
  return false;
}

void watch_dark_level(GstElement* element, DarkLevelWatch& watch, const cv::Mat& signal, int period,
                      int bit_depth, const std::string& dark_frame, double dark_level) {
  if (watch.warned) return;
  const std::optional<pyrocam::DarkLevelVerdict> v = watch.check.add(signal, period, bit_depth);
  if (!v) return;
  GST_DEBUG_OBJECT(element, "darkest samples centred at %.1f..%.1f DN after the dark", v->least_dn,
                   v->most_dn);
  if (v->offset_dn == 0) return;
  watch.warned = true;
  char level[48];
  std::snprintf(level, sizeof level, "dark-level %g DN", dark_level);
  const std::string message =
      pyrocam::dark_level_message(*v, dark_frame.empty() ? level : dark_frame, "the frame's");
  GST_ELEMENT_WARNING(element, STREAM, FORMAT,
                      ("%s: %s. Measure it: emit capture-dark with the lens capped, or give a "
                       "dark frame of this exposure (location)",
                       GST_OBJECT_NAME(element), message.c_str()),
                      ("dark level check: places' centres %.2f..%.2f DN", v->least_dn, v->most_dn));
}

}  // namespace pyrocam::gst::darksub
