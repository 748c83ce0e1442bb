/* pyrocamsrc: a simulated thermal-imaging camera (raw mosaics of test scenes). */
#pragma once

#include <gst/base/gstpushsrc.h>
#include <gst/gst.h>

G_BEGIN_DECLS

#define GST_TYPE_PYROCAM_SRC (gst_pyrocam_src_get_type())
G_DECLARE_FINAL_TYPE(GstPyrocamSrc, gst_pyrocam_src, GST, PYROCAM_SRC, GstPushSrc)

typedef enum {
  GST_PYROCAM_SRC_SCENE_PLATE,
  GST_PYROCAM_SRC_SCENE_FILAMENT,
  GST_PYROCAM_SRC_SCENE_MELT_POOL,
} GstPyrocamSrcScene;
#define GST_TYPE_PYROCAM_SRC_SCENE (gst_pyrocam_src_scene_get_type())
GType gst_pyrocam_src_scene_get_type(void);

typedef enum {
  GST_PYROCAM_SRC_UNIT_DATASHEET,
  GST_PYROCAM_SRC_UNIT_TYPICAL,
  GST_PYROCAM_SRC_UNIT_HOSTILE,
  GST_PYROCAM_SRC_UNIT_FOREIGN,
} GstPyrocamSrcUnit;
#define GST_TYPE_PYROCAM_SRC_UNIT (gst_pyrocam_src_unit_get_type())
GType gst_pyrocam_src_unit_get_type(void);

GST_ELEMENT_REGISTER_DECLARE(pyrocamsrc);

G_END_DECLS
