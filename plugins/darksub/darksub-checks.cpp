/* darksub's check of the dark it subtracts. */
#include <cmath>
#include <cstdio>

#include "darksub-private.h"

#define GST_CAT_DEFAULT gst_dark_sub_debug

namespace pyrocam::gst::darksub {

void watch_dark_level(GstElement* element, DarkLevelWatch& watch, const cv::Mat& signal, int period,
                      int bit_depth, const std::string& dark_frame, double dark_level) {
  // Until a first verdict every frame, then every 8th (0.1 ms of CPU a 2048x2048 frame).
  const unsigned frame = watch.frame++;
  if (watch.warned || (watch.decided && frame % 8 != 0)) return;
  pyrocam::add_dark_level_samples(signal, period, period, frame / (watch.decided ? 8 : 1),
                                  watch.samples);
  const pyrocam::DarkLevelVerdict v = pyrocam::dark_level_verdict(watch.samples, bit_depth);
  if (!v.decided) return;
  watch.decided = true;
  GST_DEBUG_OBJECT(element, "darkest samples centred at %.1f..%.1f DN after the dark", v.least_dn,
                   v.most_dn);
  if (v.offset_dn == 0) return;
  watch.warned = true;
  char level[48];
  std::snprintf(level, sizeof level, "dark-level %g DN", dark_level);
  const std::string dark_used = dark_frame.empty() ? level : dark_frame;
  GST_ELEMENT_WARNING(
      element, STREAM, FORMAT,
      ("%s: after the dark (%s) the frame's darkest parts read %+.0f DN (%.0f..%.0f) in every "
       "band alike, where a cold background reads 0: the dark is about %.0f DN too %s for this "
       "camera, and the temperatures would look right and be wrong. Measure it: emit "
       "capture-dark with the lens capped, or give a dark frame of this exposure (location)",
       GST_OBJECT_NAME(element), dark_used.c_str(), v.offset_dn, v.least_dn, v.most_dn,
       std::abs(v.offset_dn), v.offset_dn > 0 ? "low" : "high"),
      ("dark level check: places' centres %.2f..%.2f DN", v.least_dn, v.most_dn));
}

}  // namespace pyrocam::gst::darksub
