/* The pyrocam plugin: registers the elements, nothing more. */
#include <gst/gst.h>

#include "autoexposure/gstautoexposure.h"
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
  return ok;
}

GST_PLUGIN_DEFINE(GST_VERSION_MAJOR, GST_VERSION_MINOR, pyrocam,
                  "Calibrated thermal imaging with colour and snapshot-mosaic cameras", plugin_init,
                  PYROCAM_PLUGIN_VERSION, "MIT/X11", "pyrocam", PYROCAM_ORIGIN)
