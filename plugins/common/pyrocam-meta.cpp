#include "pyrocam-meta.h"

GType pyrocam_exposure_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar* tags[] = {nullptr};  // none: valid whatever a transform does to the frame
  if (g_once_init_enter(&type)) {
    GType t = gst_meta_api_type_register("PyrocamExposureMetaAPI", tags);
    g_once_init_leave(&type, t);
  }
  return type;
}

static gboolean exposure_meta_init(GstMeta* meta, gpointer /*params*/, GstBuffer* /*buffer*/) {
  auto* m = reinterpret_cast<PyrocamExposureMeta*>(meta);
  m->exposure_us = 0;
  m->gain_db = 0;
  return TRUE;
}

static gboolean exposure_meta_transform(GstBuffer* dest, GstMeta* meta, GstBuffer* /*buffer*/,
                                        GQuark /*type*/, gpointer /*data*/) {
  auto* m = reinterpret_cast<PyrocamExposureMeta*>(meta);
  return pyrocam_buffer_add_exposure_meta(dest, m->exposure_us, m->gain_db) != nullptr;
}

const GstMetaInfo* pyrocam_exposure_meta_get_info(void) {
  static const GstMetaInfo* info = nullptr;
  if (g_once_init_enter(&info)) {
    const GstMetaInfo* i = gst_meta_register(PYROCAM_EXPOSURE_META_API_TYPE, "PyrocamExposureMeta",
                                             sizeof(PyrocamExposureMeta), exposure_meta_init,
                                             nullptr, exposure_meta_transform);
    g_once_init_leave(&info, i);
  }
  return info;
}

PyrocamExposureMeta* pyrocam_buffer_add_exposure_meta(GstBuffer* buffer, gdouble exposure_us,
                                                      gdouble gain_db) {
  auto* m = reinterpret_cast<PyrocamExposureMeta*>(
      gst_buffer_add_meta(buffer, pyrocam_exposure_meta_get_info(), nullptr));
  if (m) {
    m->exposure_us = exposure_us;
    m->gain_db = gain_db;
  }
  return m;
}

GType pyrocam_saturation_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar* tags[] = {nullptr};  // none: consumers scale the rectangle themselves
  if (g_once_init_enter(&type)) {
    GType t = gst_meta_api_type_register("PyrocamSaturationMetaAPI", tags);
    g_once_init_leave(&type, t);
  }
  return type;
}

static gboolean saturation_meta_init(GstMeta* meta, gpointer /*params*/, GstBuffer* /*buffer*/) {
  auto* m = reinterpret_cast<PyrocamSaturationMeta*>(meta);
  m->samples = 0;
  m->x = m->y = m->width = m->height = 0;
  m->frame_width = m->frame_height = 0;
  for (guint64& t : m->tiles) t = ~guint64{0};
  return TRUE;
}

static gboolean saturation_meta_transform(GstBuffer* dest, GstMeta* meta, GstBuffer* /*buffer*/,
                                          GQuark /*type*/, gpointer /*data*/) {
  auto* m = reinterpret_cast<PyrocamSaturationMeta*>(meta);
  return pyrocam_buffer_set_saturation_meta(dest, m->samples, m->x, m->y, m->width, m->height,
                                            m->frame_width, m->frame_height, m->tiles) != nullptr;
}

const GstMetaInfo* pyrocam_saturation_meta_get_info(void) {
  static const GstMetaInfo* info = nullptr;
  if (g_once_init_enter(&info)) {
    const GstMetaInfo* i = gst_meta_register(
        PYROCAM_SATURATION_META_API_TYPE, "PyrocamSaturationMeta", sizeof(PyrocamSaturationMeta),
        saturation_meta_init, nullptr, saturation_meta_transform);
    g_once_init_leave(&info, i);
  }
  return info;
}

PyrocamSaturationMeta* pyrocam_buffer_set_saturation_meta(GstBuffer* buffer, guint64 samples,
                                                          gint x, gint y, gint width, gint height,
                                                          gint frame_width, gint frame_height,
                                                          const guint64* tiles) {
  auto* m = pyrocam_buffer_get_saturation_meta(buffer);
  if (!m)
    m = reinterpret_cast<PyrocamSaturationMeta*>(
        gst_buffer_add_meta(buffer, pyrocam_saturation_meta_get_info(), nullptr));
  if (m) {
    m->samples = samples;
    m->x = x;
    m->y = y;
    m->width = width;
    m->height = height;
    m->frame_width = frame_width;
    m->frame_height = frame_height;
    for (int i = 0; i < 64; ++i) m->tiles[i] = tiles ? tiles[i] : ~guint64{0};
  }
  return m;
}

GType pyrocam_above_range_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar* tags[] = {nullptr};  // none: consumers scale the rectangle themselves
  if (g_once_init_enter(&type)) {
    GType t = gst_meta_api_type_register("PyrocamAboveRangeMetaAPI", tags);
    g_once_init_leave(&type, t);
  }
  return type;
}

static gboolean above_range_meta_init(GstMeta* meta, gpointer /*params*/, GstBuffer* /*buffer*/) {
  auto* m = reinterpret_cast<PyrocamAboveRangeMeta*>(meta);
  m->pixels = 0;
  m->x = m->y = m->width = m->height = 0;
  m->frame_width = m->frame_height = 0;
  for (guint64& t : m->tiles) t = 0;
  m->max_temperature_c = 0;
  return TRUE;
}

static gboolean above_range_meta_transform(GstBuffer* dest, GstMeta* meta, GstBuffer* /*buffer*/,
                                           GQuark /*type*/, gpointer /*data*/) {
  auto* m = reinterpret_cast<PyrocamAboveRangeMeta*>(meta);
  return pyrocam_buffer_set_above_range_meta(dest, m->pixels, m->x, m->y, m->width, m->height,
                                             m->frame_width, m->frame_height, m->tiles,
                                             m->max_temperature_c) != nullptr;
}

const GstMetaInfo* pyrocam_above_range_meta_get_info(void) {
  static const GstMetaInfo* info = nullptr;
  if (g_once_init_enter(&info)) {
    const GstMetaInfo* i = gst_meta_register(
        PYROCAM_ABOVE_RANGE_META_API_TYPE, "PyrocamAboveRangeMeta", sizeof(PyrocamAboveRangeMeta),
        above_range_meta_init, nullptr, above_range_meta_transform);
    g_once_init_leave(&info, i);
  }
  return info;
}

PyrocamAboveRangeMeta* pyrocam_buffer_set_above_range_meta(GstBuffer* buffer, guint64 pixels,
                                                           gint x, gint y, gint width, gint height,
                                                           gint frame_width, gint frame_height,
                                                           const guint64* tiles,
                                                           gdouble max_temperature_c) {
  auto* m = pyrocam_buffer_get_above_range_meta(buffer);
  if (!m)
    m = reinterpret_cast<PyrocamAboveRangeMeta*>(
        gst_buffer_add_meta(buffer, pyrocam_above_range_meta_get_info(), nullptr));
  if (m) {
    m->pixels = pixels;
    m->x = x;
    m->y = y;
    m->width = width;
    m->height = height;
    m->frame_width = frame_width;
    m->frame_height = frame_height;
    for (int i = 0; i < 64; ++i) m->tiles[i] = tiles[i];
    m->max_temperature_c = max_temperature_c;
  }
  return m;
}

GType pyrocam_uncertainty_meta_api_get_type(void) {
  static GType type = 0;
  static const gchar* tags[] = {nullptr};  // none: per temperature, not per pixel
  if (g_once_init_enter(&type)) {
    GType t = gst_meta_api_type_register("PyrocamUncertaintyMetaAPI", tags);
    g_once_init_leave(&type, t);
  }
  return type;
}

static gboolean uncertainty_meta_init(GstMeta* meta, gpointer /*params*/, GstBuffer* /*buffer*/) {
  auto* m = reinterpret_cast<PyrocamUncertaintyMeta*>(meta);
  m->coverage_factor = 2;
  m->count = 0;
  return TRUE;
}

static gboolean uncertainty_meta_transform(GstBuffer* dest, GstMeta* meta, GstBuffer* /*buffer*/,
                                           GQuark /*type*/, gpointer /*data*/) {
  auto* m = reinterpret_cast<PyrocamUncertaintyMeta*>(meta);
  return pyrocam_buffer_set_uncertainty_meta(dest, m->coverage_factor, m->count, m->temperature_c,
                                             m->expanded_u_c) != nullptr;
}

const GstMetaInfo* pyrocam_uncertainty_meta_get_info(void) {
  static const GstMetaInfo* info = nullptr;
  if (g_once_init_enter(&info)) {
    const GstMetaInfo* i = gst_meta_register(
        PYROCAM_UNCERTAINTY_META_API_TYPE, "PyrocamUncertaintyMeta", sizeof(PyrocamUncertaintyMeta),
        uncertainty_meta_init, nullptr, uncertainty_meta_transform);
    g_once_init_leave(&info, i);
  }
  return info;
}

PyrocamUncertaintyMeta* pyrocam_buffer_set_uncertainty_meta(GstBuffer* buffer,
                                                            gdouble coverage_factor, guint count,
                                                            const gdouble* temperature_c,
                                                            const gdouble* expanded_u_c) {
  auto* m = pyrocam_buffer_get_uncertainty_meta(buffer);
  if (!m)
    m = reinterpret_cast<PyrocamUncertaintyMeta*>(
        gst_buffer_add_meta(buffer, pyrocam_uncertainty_meta_get_info(), nullptr));
  if (m) {
    m->coverage_factor = coverage_factor;
    m->count = count < PYROCAM_UNCERTAINTY_META_SAMPLES ? count : PYROCAM_UNCERTAINTY_META_SAMPLES;
    for (guint i = 0; i < m->count; ++i) {
      m->temperature_c[i] = temperature_c[i];
      m->expanded_u_c[i] = expanded_u_c[i];
    }
  }
  return m;
}
