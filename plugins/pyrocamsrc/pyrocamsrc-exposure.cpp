/* pyrocamsrc's frame exposures: the property's or the automatic one, times a bracket's step. */
#include <algorithm>

#include "pyrocam/simulation/scenes.h"
#include "pyrocamsrc-private.h"

namespace pyrocam::gst::pyrocamsrc {

double frame_exposure_us(GstElement* element, const Simulator& camera, double exposure_us,
                         double factor, double nominal_c, double emissivity, bool& warned) {
  // The automatic exposure of a cold scene runs to hours (a 300 degC plate: 7500 s): held to
  // the property's range, as a camera holds it to its own.
  const double base =
      exposure_us > 0
          ? exposure_us
          : std::min(kMaxExposureUs,
                     camera.exposure_for(
                         nominal_c, scaled_target_dn(kSceneDefaults.target_dn, camera.profile()),
                         emissivity));
  // A bracket's step beyond it is held to it too. Past it the simulated dark current
  // fills a pixel so far that its full well reads below the saturation level: a 90 s frame's
  // full pixels read as a 1300 degC surface over a 600 degC plate.
  const double asked = factor * base;
  const double exposure = std::min(asked, kMaxExposureUs);
  if (exposure != asked && !warned) {
    warned = true;
    GST_ELEMENT_WARNING(element, RESOURCE, SETTINGS,
                        ("An exposure of %.6g us (%g times %.6g us) is longer than the camera's "
                         "longest, %g us: such frames are taken at %g us, and their exposure "
                         "says so",
                         asked, factor, base, kMaxExposureUs, kMaxExposureUs),
                        ("bracket factor %g", factor));
  }
  return exposure;
}

}  // namespace pyrocam::gst::pyrocamsrc
