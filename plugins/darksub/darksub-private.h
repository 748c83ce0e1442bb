/* darksub's parts shared by its source files: the property values (darksub-properties.cpp)
 * and the caps it makes of its input and the reverse (darksub-caps.cpp); gstdarksub.cpp has the
 * streaming. */
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "gstdarksub.h"
#include "pyrocam-common.h"
#include "pyrocam/runtime/dark_level_check.h"

GST_DEBUG_CATEGORY_EXTERN(gst_dark_sub_debug);

namespace pyrocam::gst::darksub {

constexpr double DEFAULT_DARK_LEVEL = -1.0;
constexpr double DEFAULT_SATURATION_LEVEL = -1.0;
constexpr int DEFAULT_CAPTURE_FRAMES = 10;
constexpr GstDarkSubPattern DEFAULT_PATTERN = GST_DARK_SUB_PATTERN_AUTO;
constexpr int DEFAULT_BIT_DEPTH = 0;  // from the caps

/* The caps name of a pattern property value; nullptr for auto. */
const char* pattern_name(GstDarkSubPattern p);

/* Property values; read and written under GST_OBJECT_LOCK, copied once per buffer. */
struct Settings {
  std::string location;
  double dark_level = DEFAULT_DARK_LEVEL;
  double saturation_level = DEFAULT_SATURATION_LEVEL;
  int capture_frames = DEFAULT_CAPTURE_FRAMES;
  GstDarkSubPattern pattern = DEFAULT_PATTERN;
  int bit_depth = DEFAULT_BIT_DEPTH;
  guint capture_requests = 0;  // incremented by capture-dark
};

struct State;  // streaming state, gstdarksub.cpp

/* The x-pyrocam-mosaic structure darksub makes of a raw sink structure (pattern, bit depth and
 * saturation level from the caps, else the properties). */
GstStructure* mosaic_structure(const GstStructure* raw, const Settings& settings);
/* The raw caps (Bayer of the pattern, and gray video) that give a mosaic structure. */
GstCaps* raw_caps(const GstStructure* mosaic);

/* dark-level as set while playing (it is controllable) into `in_use`: a level above the
 * full scale of `bit_depth` would leave no reading anywhere and say nothing, so the level in use
 * stays, with a warning once per refused value (`refused`); without one to keep, an error and
 * false. */
bool use_dark_level(GstElement* element, double level, int bit_depth, double& in_use,
                    double& refused);

/* The saturation level in use, raw DN: the property, else the caps' (`caps_level`, -1: none),
 * else the default share of the bit depth's full scale. */
double saturation_in_use(const Settings& settings, int caps_level, int bit_depth);
/* Without a dark frame, a saturation level at or below the dark level marks every pixel
 * saturated (and ratiotemp then asks for a shorter exposure): an error naming both, and false. */
bool saturation_above_dark(GstElement* element, const Settings& settings, double saturation);

/* Whether the dark subtracted is the camera's (pyrocam::DarkLevelWatch): a dark that looks off
 * is warned about once since start, naming the dark frame subtracted (`dark_frame`) or, without
 * one, `dark_level`. */
struct DarkLevelWatch {
  pyrocam::DarkLevelWatch check;
  bool warned = false;
};
void watch_dark_level(GstElement* element, DarkLevelWatch& watch, const cv::Mat& signal, int period,
                      int bit_depth, const std::string& dark_frame, double dark_level);

/* GObject properties: installed by class_init, read and written under the object lock. */
void install_properties(GObjectClass* klass);
void set_property(GObject* object, guint prop_id, const GValue* value, GParamSpec* pspec);
void get_property(GObject* object, guint prop_id, GValue* value, GParamSpec* pspec);

}  // namespace pyrocam::gst::darksub

struct _GstDarkSub {
  GstBaseTransform parent;
  pyrocam::gst::darksub::Settings* settings;
  pyrocam::gst::darksub::State* state;
};
