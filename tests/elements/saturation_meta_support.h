// Attaches a PyrocamSaturationMeta to a buffer as darksub would (and a PyrocamAboveRangeMeta or a
// PyrocamUncertaintyMeta as ratiotemp would), for the tests of the elements that read them. By the
// meta's registered name: the tests do not link the plugin, which registers it when it loads.
#pragma once

#include <gst/gst.h>
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam-meta.h"

namespace pyrocam::test {

// `samples` saturated samples in `box` of a frame_width x frame_height mosaic; where `spots`
// are given, the meta's tiles hold those samples only (else: not known, the whole box).
inline void add_saturation_meta(GstBuffer* buffer, guint64 samples, const cv::Rect& box,
                                int frame_width, int frame_height,
                                const std::vector<cv::Point>& spots = {}) {
  const GstMetaInfo* info = gst_meta_get_info("PyrocamSaturationMeta");
  ASSERT_NE(info, nullptr) << "the pyrocam plugin did not register PyrocamSaturationMeta";
  auto* m = reinterpret_cast<PyrocamSaturationMeta*>(gst_buffer_add_meta(buffer, info, nullptr));
  ASSERT_NE(m, nullptr);
  m->samples = samples;
  m->x = box.x;
  m->y = box.y;
  m->width = box.width;
  m->height = box.height;
  m->frame_width = frame_width;
  m->frame_height = frame_height;
  if (spots.empty()) return;
  for (guint64& t : m->tiles) t = 0;
  for (const cv::Point& p : spots)
    m->tiles[p.y * 64 / frame_height] |= guint64{1} << (p.x * 64 / frame_width);
}

// `pixels` pixels hotter than a range ending at max_c, filling `box` of a frame_width x
// frame_height temperature frame (the meta's tiles: those the box meets).
inline void add_above_range_meta(GstBuffer* buffer, guint64 pixels, const cv::Rect& box,
                                 int frame_width, int frame_height, double max_c) {
  const GstMetaInfo* info = gst_meta_get_info("PyrocamAboveRangeMeta");
  ASSERT_NE(info, nullptr) << "the pyrocam plugin did not register PyrocamAboveRangeMeta";
  auto* m = reinterpret_cast<PyrocamAboveRangeMeta*>(gst_buffer_add_meta(buffer, info, nullptr));
  ASSERT_NE(m, nullptr);
  m->pixels = pixels;
  m->x = box.x;
  m->y = box.y;
  m->width = box.width;
  m->height = box.height;
  m->frame_width = frame_width;
  m->frame_height = frame_height;
  m->max_temperature_c = max_c;
  for (guint64& t : m->tiles) t = 0;
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x)
      m->tiles[y * 64 / frame_height] |= guint64{1} << (x * 64 / frame_width);
}

// An expanded systematic uncertainty of u0_c at t0_c rising linearly to u1_c at t1_c (two
// samples), with coverage factor 2.
inline void add_uncertainty_meta(GstBuffer* buffer, double t0_c, double u0_c, double t1_c,
                                 double u1_c) {
  const GstMetaInfo* info = gst_meta_get_info("PyrocamUncertaintyMeta");
  ASSERT_NE(info, nullptr) << "the pyrocam plugin did not register PyrocamUncertaintyMeta";
  auto* m = reinterpret_cast<PyrocamUncertaintyMeta*>(gst_buffer_add_meta(buffer, info, nullptr));
  ASSERT_NE(m, nullptr);
  m->coverage_factor = 2;
  m->count = 2;
  m->temperature_c[0] = t0_c;
  m->expanded_u_c[0] = u0_c;
  m->temperature_c[1] = t1_c;
  m->expanded_u_c[1] = u1_c;
}

}  // namespace pyrocam::test
