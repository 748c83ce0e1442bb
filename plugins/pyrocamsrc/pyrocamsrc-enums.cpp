/* pyrocamsrc's enumerations (scene, unit), registered as GTypes. */
#include "gstpyrocamsrc.h"

GType gst_pyrocam_src_scene_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_PYROCAM_SRC_SCENE_PLATE, "Plate at temperature filling the central 60 %", "plate"},
      {GST_PYROCAM_SRC_SCENE_FILAMENT, "Vertical filament at temperature", "filament"},
      {GST_PYROCAM_SRC_SCENE_MELT_POOL, "Melt pool (1500-2500 degC) crossing the frame",
       "melt-pool"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstPyrocamSrcScene", values);
    g_once_init_leave(&type, t);
  }
  return type;
}

GType gst_pyrocam_src_unit_get_type(void) {
  static GType type = 0;
  static const GEnumValue values[] = {
      {GST_PYROCAM_SRC_UNIT_DATASHEET, "Exactly the profile's datasheet QE", "datasheet"},
      {GST_PYROCAM_SRC_UNIT_TYPICAL, "A real unit's deviation from the datasheet (seeded)",
       "typical"},
      {GST_PYROCAM_SRC_UNIT_HOSTILE,
       "Typical plus moved filter edges, narrow leaks, a sloping ND glass and band shape "
       "changes (seeded)",
       "hostile"},
      {GST_PYROCAM_SRC_UNIT_FOREIGN,
       "Typical plus a moved and softened filter, weak blocking, a bent lens transmission and "
       "stretched, reshaped bands (seeded)",
       "foreign"},
      {0, nullptr, nullptr},
  };
  if (g_once_init_enter(&type)) {
    GType t = g_enum_register_static("GstPyrocamSrcUnit", values);
    g_once_init_leave(&type, t);
  }
  return type;
}
