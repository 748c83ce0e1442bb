/* autoexposure's parts shared by its source files: the property values, the streaming state
 * and the element struct (gstautoexposure.cpp: properties and streaming; autoexposure-camera.cpp:
 * finding the camera and the controller's settings from its property ranges). */
#pragma once

#include <gst/gst.h>

#include <memory>
#include <string>
#include <vector>

#include "gstautoexposure.h"
#include "pyrocam-common.h"
#include "pyrocam/runtime/exposure_control.h"

GST_DEBUG_CATEGORY_EXTERN(gst_auto_exposure_debug);

namespace pyrocam::gst::autoexposure {

namespace pg = pyrocam::gst;

constexpr double DEFAULT_TARGET = 0.7;
// The brightest raw value: a melt pool's core is a few pixels, and matched demosaicking gives no
// reading within two pixels of a saturated sample, so a level that let even a few samples
// saturate left the core without a reading (the 50th brightest did in 298 of 300 frames of the
// simulated pool).
constexpr guint DEFAULT_HOT_PIXELS = 1;
constexpr double DEFAULT_DARK_LEVEL = 0;
constexpr double DEFAULT_MIN_EXPOSURE =
    1e-3;  // the simulated cameras need well below 1 us when hot
constexpr double DEFAULT_MAX_EXPOSURE = 1e6;
constexpr double DEFAULT_MAX_STEP = 8;
constexpr double DEFAULT_TOLERANCE = 0.1;
constexpr guint DEFAULT_LATENCY = 3;
constexpr double DEFAULT_MAX_GAIN = 0;  // dB: the gain is left as it is
constexpr double MAX_MAX_GAIN = 48;
// Where control starts when the camera reports no exposure (aravissrc before one is set), us.
constexpr double DEFAULT_START_EXPOSURE = 1000;

struct Settings {
  double target = DEFAULT_TARGET;
  guint hot_pixels = DEFAULT_HOT_PIXELS;
  double dark_level = DEFAULT_DARK_LEVEL;
  double min_exposure_us = DEFAULT_MIN_EXPOSURE, max_exposure_us = DEFAULT_MAX_EXPOSURE;
  double max_step = DEFAULT_MAX_STEP;
  double tolerance = DEFAULT_TOLERANCE;
  guint latency = DEFAULT_LATENCY;
  double max_gain_db = DEFAULT_MAX_GAIN;
  std::string camera;           // element name; empty: the first source upstream
  std::string bracket_text;     // as set
  std::vector<double> bracket;  // parsed factors; empty: no bracketing
  bool bracket_valid = true;    // else start() refuses to run
  guint serial = 0;             // bumped by every change
};

struct State {
  pg::RawFormat format;
  double saturation_dn = 255;
  GstElement* camera = nullptr;  // owned reference; null: not looked for yet or none
  bool camera_looked_up = false;
  double property_min_us = 0, property_max_us = G_MAXDOUBLE;
  bool has_gain = false;  // the camera has a writable double `gain` property
  double gain_property_min_db = 0, gain_property_max_db = G_MAXDOUBLE;
  bool warned_no_gain = false;
  std::unique_ptr<pyrocam::ExposureController> controller;
  std::unique_ptr<pyrocam::SettingInEffect> in_effect;  // for frames without their own meta
  std::unique_ptr<pyrocam::CameraBracket> bracket;      // with a bracket property
  pyrocam::ExposureSetting base;  // bracketing: what the first factor multiplies
  bool warned_bracket_limit = false;
  bool warned_no_exposure = false;
  guint serial = G_MAXUINT;
  bool warned_limit = false;
  bool warned_hot_pixels = false;  // hot-pixels larger than the frame
  ~State() {
    if (camera) gst_object_unref(camera);
  }
};

/* Finds the camera (the element named settings.camera, else the first source upstream) and
 * reads its exposure and gain properties' ranges into the state; warns when there is none. */
void look_up_camera(GstAutoExposure* self, const Settings& settings);

/* The controller's settings from the properties and the camera's property ranges; throws
 * pyrocam::InputError, naming both, where they do not overlap. */
pyrocam::ExposureControlSettings controller_settings(GstAutoExposure* self,
                                                     const Settings& settings);

}  // namespace pyrocam::gst::autoexposure

struct _GstAutoExposure {
  GstBaseTransform parent;
  pyrocam::gst::autoexposure::Settings* settings;
  pyrocam::gst::autoexposure::State* state;
};
