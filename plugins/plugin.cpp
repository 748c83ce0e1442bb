/* The pyrocam plugin: registers the elements and their buffer metas. */
#include <gst/gst.h>

#include "autoexposure/gstautoexposure.h"
#include "common/pyrocam-meta.h"
#include "darksub/gstdarksub.h"
#include "demosaic25/gstdemosaic25.h"
#include "mosaicfuse/gstmosaicfuse.h"
#include "pyrocamsrc/gstpyrocamsrc.h"
#include "ratiotemp/gstratiotemp.h"
#include "thermalalarm/gstthermalalarm.h"
#include "thermalcolormap/gstthermalcolormap.h"
#include "thermalfuse/gstthermalfuse.h"
#include "thermaloverlay/gstthermaloverlay.h"

static gboolean plugin_init(GstPlugin* plugin) {
  gboolean ok = FALSE;
  ok |= GST_ELEMENT_REGISTER(pyrocamsrc, plugin);
  ok |= GST_ELEMENT_REGISTER(darksub, plugin);
  ok |= GST_ELEMENT_REGISTER(demosaic25, plugin);
  ok |= GST_ELEMENT_REGISTER(ratiotemp, plugin);
  ok |= GST_ELEMENT_REGISTER(thermalcolormap, plugin);
  ok |= GST_ELEMENT_REGISTER(thermalalarm, plugin);
  ok |= GST_ELEMENT_REGISTER(thermaloverlay, plugin);
  ok |= GST_ELEMENT_REGISTER(thermalfuse, plugin);
  ok |= GST_ELEMENT_REGISTER(mosaicfuse, plugin);
  ok |= GST_ELEMENT_REGISTER(autoexposure, plugin);
  // Now rather than with the first buffer that carries one, so that an application can look
  // them up by name (gst_meta_get_info) and attach them to frames of its own.
  pyrocam_exposure_meta_get_info();
  pyrocam_saturation_meta_get_info();
  pyrocam_above_range_meta_get_info();
  pyrocam_uncertainty_meta_get_info();
  return ok;
}

GST_PLUGIN_DEFINE(GST_VERSION_MAJOR, GST_VERSION_MINOR, pyrocam,
                  "Calibrated thermal imaging with colour and snapshot-mosaic cameras", plugin_init,
                  PYROCAM_PLUGIN_VERSION, "MIT/X11", "pyrocam", PYROCAM_ORIGIN)
