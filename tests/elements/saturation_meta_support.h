// Attaches a PyrocamSaturationMeta to a buffer as darksub would, for the tests of the elements
// that read it. By the meta's registered name: the tests do not link the plugin, which
// registers it when it loads.
#pragma once

#include <gst/gst.h>
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "pyrocam-meta.h"

namespace pyrocam::test {

// `samples` saturated samples in `box` of a frame_width x frame_height mosaic.
inline void add_saturation_meta(GstBuffer* buffer, guint64 samples, const cv::Rect& box,
                                int frame_width, int frame_height) {
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
}

}  // namespace pyrocam::test
