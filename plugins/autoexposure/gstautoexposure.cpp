/**
 * SECTION:element-autoexposure
 * @title: autoexposure
 *
 * Automatic exposure for thermal reading. Placed right after the camera (raw mosaic: Bayer,
 * GRAY8 or GRAY16_LE, passed through unchanged), it measures the hottest region of each frame
 * (the #GstAutoExposure:hot-pixels-th brightest raw value; by default the brightest, so that
 * no sample of a small hot core saturates; raise it past a camera's defective bright pixels)
 * and sets the camera's `exposure` property (microseconds; pyrocamsrc and aravissrc have one)
 * so that this level sits at #GstAutoExposure:target of the
 * way from #GstAutoExposure:dark-level to the saturation level (the caps' saturation-level,
 * else darksub's default, 220/255 of the full scale). A camera's automatic exposure aims at a
 * pleasing picture; this one keeps the object of interest readable: not saturated (no reading) and
 * well above the dim threshold (a noisy or no reading).
 *
 * Each frame's own exposure comes from its PyrocamExposureMeta (pyrocamsrc attaches it): the
 * new exposure is the frame's times the ratio of target to level, so the frames still taken
 * with the old exposure ask for the same new one and the loop settles in one step whatever the
 * latency, without oscillating. Frames without the meta (aravissrc) are taken with the
 * exposure last set after #GstAutoExposure:latency frames; no change is made meanwhile, and such
 * a frame gets a PyrocamExposureMeta with the camera's exposure and gain (read from its
 * properties as the frame passes) once these have stayed the same for #GstAutoExposure:latency
 * frames (the first setting read counts from the start), so that ratiotemp's noise model
 * follows the gain and thermalfuse can rank the frames; frames within #GstAutoExposure:latency
 * of a change, whose exposure is not known, get none. A
 * saturated level steps down by #GstAutoExposure:max-step at once. Within
 * #GstAutoExposure:tolerance of the target nothing changes.
 *
 * With #GstAutoExposure:max-gain above 0 dB the camera's `gain` property (dB; pyrocamsrc and
 * aravissrc have one) is set too: the exposure alone (gain 0 dB) up to
 * #GstAutoExposure:max-exposure, and only when the exposure is at its longest and the level still
 * below the target, the gain, up to #GstAutoExposure:max-gain. A too bright scene brings the gain
 * back to 0 dB before the exposure shortens. The dead-beat step then works on the brightness,
 * exposure times gain factor, with each frame's own exposure and gain from its meta. A camera
 * without a double `gain` property gets one warning and exposure control only. With max-gain 0
 * (the default) the gain is left as it is.
 *
 * #GstAutoExposure:bracket brackets the exposure with a camera whose frames do not carry it
 * (aravissrc): the camera's exposure cycles through the controlled exposure times each factor,
 * each held for #GstAutoExposure:latency + 1 frames, and only the last frame of each step
 * passes, with its exposure as a PyrocamExposureMeta: the frames before it may have been taken
 * with either exposure, and thermalfuse could not rank them. The first factor's frames are kept
 * at the target; thermalfuse frames=N (N factors) fuses one cycle. The output rate is the
 * camera's divided by latency + 1. Exposures the factors take outside the range are clamped,
 * with a warning. (pyrocamsrc, whose frames carry their exposure, has its own bracket property.)
 *
 * Every change posts an element message "pyrocam-exposure" (exposure-us, previous-us, gain-db,
 * previous-gain-db, level-dn, saturated, clamped, timestamp).
 *
 * The camera is the element named #GstAutoExposure:camera, else the first element upstream
 * that has no sink pad. One without a double `exposure` property gets a warning and no control
 * (frames still pass). Exposures outside #GstAutoExposure:min-exposure..
 * #GstAutoExposure:max-exposure and gains above #GstAutoExposure:max-gain (and the properties'
 * own ranges) are clamped, with a warning once each time the limit is reached.
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 aravissrc exposure=2000 ! video/x-bayer,format=rggb ! \
 *     autoexposure dark-level=12 max-exposure=20000 ! darksub dark-level=12 ! demosaic25 ! \
 *     ratiotemp model=model.json ! fakesink
 * ]| A 2500 degC core and a 1300 degC rim in one output frame, from a GigE camera that takes an
 * exposure change two frames after it is set:
 * |[
 * gst-launch-1.0 aravissrc exposure=2000 ! video/x-bayer,format=rggb ! \
 *     autoexposure dark-level=12 latency=2 bracket=1,8 ! darksub dark-level=12 ! demosaic25 ! \
 *     ratiotemp model=model.json ! thermalfuse frames=2 ! fakesink
 * ]| With gain once the exposure is at 20 ms, up to 12 dB:
 * |[
 * gst-launch-1.0 pyrocamsrc scene=plate temperature=900 exposure=1000 ! \
 *     autoexposure dark-level=50 max-exposure=20000 max-gain=12 ! darksub dark-level=50 ! \
 *     demosaic25 ! ratiotemp model=model.json ! fakesink
 * ]|
 */
#include "gstautoexposure.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "autoexposure-private.h"
#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam-meta.h"
#include "pyrocam/runtime/bracket_fusion.h"
#include "pyrocam/runtime/exposure_control.h"

GST_DEBUG_CATEGORY(gst_auto_exposure_debug);
#define GST_CAT_DEFAULT gst_auto_exposure_debug

namespace pg = pyrocam::gst;
using namespace pyrocam::gst::autoexposure;

namespace {

enum {
  PROP_0,
  PROP_TARGET,
  PROP_HOT_PIXELS,
  PROP_DARK_LEVEL,
  PROP_MIN_EXPOSURE,
  PROP_MAX_EXPOSURE,
  PROP_MAX_STEP,
  PROP_TOLERANCE,
  PROP_LATENCY,
  PROP_CAMERA,
  PROP_MAX_GAIN,
  PROP_BRACKET,
};

constexpr const char* EXPOSURE_MESSAGE = "pyrocam-exposure";

}  // namespace

G_DEFINE_TYPE(GstAutoExposure, gst_auto_exposure, GST_TYPE_BASE_TRANSFORM);
GST_ELEMENT_REGISTER_DEFINE(autoexposure, "autoexposure", GST_RANK_NONE, GST_TYPE_AUTO_EXPOSURE);

static GstStaticPadTemplate sink_template = GST_STATIC_PAD_TEMPLATE(
    "sink", GST_PAD_SINK, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RAW_CAPS));
static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RAW_CAPS));

static gboolean gst_auto_exposure_set_caps(GstBaseTransform* trans, GstCaps* incaps,
                                           GstCaps* /*outcaps*/) {
  GstAutoExposure* self = GST_AUTO_EXPOSURE(trans);
  State& st = *self->state;
  if (!pg::parse_raw_caps(incaps, &st.format)) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "Caps are not a raw mosaic",
                       "parse_raw_caps failed");
    return FALSE;
  }
  const GstStructure* s = gst_caps_get_structure(incaps, 0);
  const int depth = pg::structure_int(s, "bit-depth", 8 * st.format.bytes_per_sample);
  // Without the caps field, darksub's default: 220/255 of the full scale.
  const int full_scale = (1 << depth) - 1;
  st.saturation_dn = pg::structure_int(s, "saturation-level",
                                       static_cast<int>(std::lround(full_scale * 220.0 / 255.0)));
  st.serial = G_MAXUINT;  // the controller is made again with the new saturation level
  return TRUE;
}

/* The element message every change of the exposure (or gain) posts. */
static void post_exposure_message(GstAutoExposure* self, const pyrocam::ExposureCommand& command,
                                  const pyrocam::ExposureSetting& previous,
                                  const pyrocam::HotLevel& level, GstClockTime pts) {
  gst_element_post_message(
      GST_ELEMENT(self),
      gst_message_new_element(
          GST_OBJECT(self),
          gst_structure_new(
              EXPOSURE_MESSAGE, "exposure-us", G_TYPE_DOUBLE, command.exposure_us, "previous-us",
              G_TYPE_DOUBLE, previous.exposure_us, "gain-db", G_TYPE_DOUBLE, command.gain_db,
              "previous-gain-db", G_TYPE_DOUBLE, previous.gain_db, "level-dn", G_TYPE_DOUBLE,
              level.level_dn, "saturated", G_TYPE_BOOLEAN, level.clipped, "clamped", G_TYPE_BOOLEAN,
              command.clamped, "timestamp", G_TYPE_UINT64, static_cast<guint64>(pts), nullptr)));
}

/* Sets the camera's exposure (and, when it is controlled, its gain). */
static void set_camera(GstAutoExposure* self, double exposure_us, std::optional<double> gain_db) {
  State& st = *self->state;
  if (gain_db) {
    const double gain = std::clamp(*gain_db, st.gain_property_min_db, st.gain_property_max_db);
    g_object_set(st.camera, "exposure", exposure_us, "gain", gain, nullptr);
  } else {
    g_object_set(st.camera, "exposure", exposure_us, nullptr);
  }
}

/* The frame's hot level. A hot-pixels larger than the frame would measure its darkest sample, and
 * the exposure would run to its limit for a hot region that is the background: said once. */
static pyrocam::HotLevel measure_hot_level(GstAutoExposure* self, const Settings& settings,
                                           const cv::Mat& image) {
  State& st = *self->state;
  if (settings.hot_pixels > image.total() && !st.warned_hot_pixels) {
    st.warned_hot_pixels = true;
    GST_ELEMENT_WARNING(
        self, RESOURCE, SETTINGS,
        ("%s: hot-pixels %u is more than the %dx%d frame's %zu samples: the "
         "level measured is the frame's darkest",
         GST_OBJECT_NAME(self), settings.hot_pixels, image.cols, image.rows, image.total()),
        ("hot-pixels larger than the frame"));
  }
  return pyrocam::hot_level(image, static_cast<int>(settings.hot_pixels), st.saturation_dn);
}

/* Bracketing by the camera's setting (see the element's doc): one frame per step passes, the
 * first factor's frames drive the base exposure, and each step sets the camera to base x its
 * factor. Returns whether the frame passes. */
static bool bracket_frame(GstAutoExposure* self, const Settings& settings, GstBuffer* buffer,
                          const std::optional<pyrocam::ExposureSetting>& known,
                          const pyrocam::ExposureSetting& current, bool& failed) {
  State& st = *self->state;
  const bool controls_gain = st.controller->settings().max_gain_db > 0;
  const pyrocam::CameraBracket::Step step = st.bracket->next_frame();
  const bool keep = step.keep && known.has_value();
  if (keep && step.first) {
    pyrocam::HotLevel level;
    std::optional<pyrocam::ExposureCommand> command;
    // The frame as if taken with the base: the controller's answer is a new base.
    const pyrocam::ExposureSetting taken{known->exposure_us / step.factor, known->gain_db};
    if (!PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not measure the frame", [&] {
          pg::MappedImage image;
          image.map_raw(buffer, st.format);
          level = measure_hot_level(self, settings, image.image());
          command = st.controller->update(level, taken, st.base);
        })) {
      failed = true;
      return false;
    }
    if (command) {
      const pyrocam::ExposureSetting previous = st.base;
      st.base = {command->exposure_us, controls_gain ? command->gain_db : current.gain_db};
      post_exposure_message(self, *command, previous, level, GST_BUFFER_PTS(buffer));
    }
  }
  if (step.set) {
    const pyrocam::ExposureControlSettings& c = st.controller->settings();
    const double wanted = st.base.exposure_us * step.next_factor;
    const double exposure = std::clamp(wanted, c.min_exposure_us, c.max_exposure_us);
    if (exposure != wanted && !st.warned_bracket_limit)
      GST_ELEMENT_WARNING(
          self, RESOURCE, SETTINGS,
          ("The bracket's exposure %g us (%g x %g) is outside the camera's range "
           "%g..%g us: clamped",
           wanted, st.base.exposure_us, step.next_factor, c.min_exposure_us, c.max_exposure_us),
          ("bracket exposure clamped"));
    st.warned_bracket_limit = st.warned_bracket_limit || exposure != wanted;
    set_camera(self, exposure,
               controls_gain ? std::optional<double>(st.base.gain_db) : std::nullopt);
  }
  return keep;
}

static GstFlowReturn gst_auto_exposure_transform_ip(GstBaseTransform* trans, GstBuffer* buffer) {
  GstAutoExposure* self = GST_AUTO_EXPOSURE(trans);
  const Settings settings = pg::locked_copy(self, *self->settings);
  State& st = *self->state;
  if (!st.camera_looked_up) look_up_camera(self, settings);
  if (!st.camera) return GST_FLOW_OK;
  if (settings.serial != st.serial) {
    pyrocam::ExposureControlSettings c;
    if (!PYROCAM_GUARDED(self, pg::ErrorKind::kSettings, "Bad exposure control settings", [&] {
          c = controller_settings(self, settings);
          st.controller = std::make_unique<pyrocam::ExposureController>(c);
          st.in_effect = std::make_unique<pyrocam::SettingInEffect>(c.latency_frames);
          st.bracket = settings.bracket.empty() ? nullptr
                                                : std::make_unique<pyrocam::CameraBracket>(
                                                      settings.bracket, c.latency_frames);
        }))
      return GST_FLOW_ERROR;
    st.serial = settings.serial;
  }
  const bool controls_gain = st.controller->settings().max_gain_db > 0;
  std::optional<pyrocam::ExposureSetting> frame;
  if (const PyrocamExposureMeta* meta = pyrocam_buffer_get_exposure_meta(buffer))
    frame = pyrocam::ExposureSetting{meta->exposure_us, meta->gain_db};
  pyrocam::ExposureSetting current;
  g_object_get(st.camera, "exposure", &current.exposure_us, nullptr);
  if (st.has_gain) g_object_get(st.camera, "gain", &current.gain_db, nullptr);
  // aravissrc's -1 is "not set": the camera's own gain, taken as 0 dB (its usual default).
  current.gain_db = std::max(current.gain_db, 0.0);
  // A frame that does not say what it was taken with gets the camera's setting once that is
  // known to have reached it, for everything downstream (ratiotemp's noise model, thermalfuse).
  const std::optional<pyrocam::ExposureSetting> in_effect = st.in_effect->frame_setting(current);
  if (!frame && in_effect)
    pyrocam_buffer_add_exposure_meta(buffer, in_effect->exposure_us, in_effect->gain_db);
  // A camera on its own automatic exposure (pyrocamsrc's 0) whose frames say what they were
  // taken with: control starts from there (a fixed start far off it saturated the first frames).
  if (!(current.exposure_us > 0) && frame && frame->exposure_us > 0) current = *frame;
  if (!(current.exposure_us > 0)) {
    // Not set either (aravissrc's -1): nothing to scale from, so start from a set value.
    const pyrocam::ExposureControlSettings& c = st.controller->settings();
    const double start = std::clamp(DEFAULT_START_EXPOSURE, c.min_exposure_us, c.max_exposure_us);
    if (!st.warned_no_exposure)
      GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS,
                          ("Camera %s reports no exposure (%g): exposure control starts from %g us",
                           GST_OBJECT_NAME(st.camera), current.exposure_us, start),
                          ("exposure property not set"));
    st.warned_no_exposure = true;  // once, should the camera keep reporting none
    g_object_set(st.camera, "exposure", start, nullptr);
    st.controller->set_by_caller({start, current.gain_db});
    return GST_FLOW_OK;
  }
  if (st.bracket) {
    if (st.base.exposure_us <= 0) st.base = current;  // the camera as it streamed
    bool failed = false;
    const bool keep =
        bracket_frame(self, settings, buffer, frame ? frame : in_effect, current, failed);
    if (failed) return GST_FLOW_ERROR;
    return keep ? GST_FLOW_OK : GST_BASE_TRANSFORM_FLOW_DROPPED;
  }
  pyrocam::HotLevel level;
  std::optional<pyrocam::ExposureCommand> command;
  if (!PYROCAM_GUARDED(self, pg::ErrorKind::kFormat, "Could not measure the frame", [&] {
        pg::MappedImage image;
        image.map_raw(buffer, st.format);
        level = measure_hot_level(self, settings, image.image());
        command = st.controller->update(level, frame, current);
      }))
    return GST_FLOW_ERROR;
  if (st.controller->at_limit() && !st.warned_limit) {
    GST_ELEMENT_WARNING(
        self, RESOURCE, SETTINGS,
        ("The exposure wanted is outside the camera's range %g..%g us (gain up "
         "to %g dB): clamped (the hottest region reads %g DN%s)",
         st.controller->settings().min_exposure_us, st.controller->settings().max_exposure_us,
         st.controller->settings().max_gain_db, level.level_dn,
         level.clipped ? ", saturated: if the scene is not that bright, a defective pixel may "
                         "be; raise hot-pixels past the camera's defective pixels"
                       : ""),
        ("exposure clamped"));
  }
  st.warned_limit = st.controller->at_limit();
  if (!command) return GST_FLOW_OK;
  const pyrocam::ExposureSetting previous = frame.value_or(current);
  GST_DEBUG_OBJECT(self, "level %g DN%s: exposure %g -> %g us, gain %g -> %g dB", level.level_dn,
                   level.clipped ? " (saturated)" : "", previous.exposure_us, command->exposure_us,
                   previous.gain_db, command->gain_db);
  set_camera(self, command->exposure_us,
             controls_gain ? std::optional<double>(command->gain_db) : std::nullopt);
  post_exposure_message(self, *command, previous, level, GST_BUFFER_PTS(buffer));
  return GST_FLOW_OK;
}

static void reset_state(GstAutoExposure* self) {
  delete self->state;
  self->state = new State();  // drops the camera reference
}

static gboolean gst_auto_exposure_start(GstBaseTransform* trans) {
  pg::forget_posted_errors(GST_ELEMENT(trans));
  GstAutoExposure* self = GST_AUTO_EXPOSURE(trans);
  const Settings settings = pg::locked_copy(self, *self->settings);
  std::string why;
  try {
    const std::vector<double> factors = pyrocam::parse_bracket(settings.bracket_text);
    if (!factors.empty()) pyrocam::CameraBracket(factors, static_cast<int>(settings.latency));
  } catch (const std::exception& e) {
    why = e.what();
  }
  if (!why.empty()) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings, why, "the bracket property is not usable");
    return FALSE;
  }
  reset_state(self);
  return TRUE;
}

static gboolean gst_auto_exposure_stop(GstBaseTransform* trans) {
  reset_state(GST_AUTO_EXPOSURE(trans));
  return TRUE;
}

static void gst_auto_exposure_set_property(GObject* object, guint prop_id, const GValue* value,
                                           GParamSpec* pspec) {
  GstAutoExposure* self = GST_AUTO_EXPOSURE(object);
  pg::ObjectLock lock(self);
  Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_TARGET:
      s.target = g_value_get_double(value);
      break;
    case PROP_HOT_PIXELS:
      s.hot_pixels = g_value_get_uint(value);
      break;
    case PROP_DARK_LEVEL:
      s.dark_level = g_value_get_double(value);
      break;
    case PROP_MIN_EXPOSURE:
      s.min_exposure_us = g_value_get_double(value);
      break;
    case PROP_MAX_EXPOSURE:
      s.max_exposure_us = g_value_get_double(value);
      break;
    case PROP_MAX_STEP:
      s.max_step = g_value_get_double(value);
      break;
    case PROP_TOLERANCE:
      s.tolerance = g_value_get_double(value);
      break;
    case PROP_LATENCY:
      s.latency = g_value_get_uint(value);
      break;
    case PROP_MAX_GAIN:
      s.max_gain_db = g_value_get_double(value);
      break;
    case PROP_CAMERA: {
      const char* v = g_value_get_string(value);
      s.camera = v ? v : "";
      break;
    }
    case PROP_BRACKET: {
      const char* v = g_value_get_string(value);
      s.bracket_text = v ? v : "";
      try {
        s.bracket = pyrocam::parse_bracket(s.bracket_text);
      } catch (const std::exception& e) {
        GST_WARNING_OBJECT(self, "%s", e.what());  // start() refuses to run
        s.bracket.clear();
      }
      break;
    }
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      return;
  }
  ++s.serial;
}

static void gst_auto_exposure_get_property(GObject* object, guint prop_id, GValue* value,
                                           GParamSpec* pspec) {
  GstAutoExposure* self = GST_AUTO_EXPOSURE(object);
  pg::ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_TARGET:
      g_value_set_double(value, s.target);
      break;
    case PROP_HOT_PIXELS:
      g_value_set_uint(value, s.hot_pixels);
      break;
    case PROP_DARK_LEVEL:
      g_value_set_double(value, s.dark_level);
      break;
    case PROP_MIN_EXPOSURE:
      g_value_set_double(value, s.min_exposure_us);
      break;
    case PROP_MAX_EXPOSURE:
      g_value_set_double(value, s.max_exposure_us);
      break;
    case PROP_MAX_STEP:
      g_value_set_double(value, s.max_step);
      break;
    case PROP_TOLERANCE:
      g_value_set_double(value, s.tolerance);
      break;
    case PROP_LATENCY:
      g_value_set_uint(value, s.latency);
      break;
    case PROP_MAX_GAIN:
      g_value_set_double(value, s.max_gain_db);
      break;
    case PROP_CAMERA:
      g_value_set_string(value, s.camera.empty() ? nullptr : s.camera.c_str());
      break;
    case PROP_BRACKET:
      g_value_set_string(value, s.bracket_text.c_str());
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

static void gst_auto_exposure_finalize(GObject* object) {
  GstAutoExposure* self = GST_AUTO_EXPOSURE(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_auto_exposure_parent_class)->finalize(object);
}

static void gst_auto_exposure_class_init(GstAutoExposureClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseTransformClass* trans_class = GST_BASE_TRANSFORM_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_auto_exposure_debug, "autoexposure", 0, "pyrocam exposure control");

  gobject_class->set_property = gst_auto_exposure_set_property;
  gobject_class->get_property = gst_auto_exposure_get_property;
  gobject_class->finalize = gst_auto_exposure_finalize;

  const auto playing = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING);
  g_object_class_install_property(
      gobject_class, PROP_TARGET,
      g_param_spec_double("target", "Target",
                          "Where the hottest region's level is kept, as a share of the way from "
                          "dark-level to the saturation level (0.05..0.95)",
                          0.05, 0.95, DEFAULT_TARGET, playing));
  g_object_class_install_property(
      gobject_class, PROP_HOT_PIXELS,
      g_param_spec_uint("hot-pixels", "Hot pixels",
                        "The level measured is the hot-pixels-th brightest raw value of the "
                        "frame (1: the brightest, so that no sample of a hot core saturates; "
                        "raise it past the camera's defective bright pixels) (1..1000000)",
                        1, 1000000, DEFAULT_HOT_PIXELS, playing));
  g_object_class_install_property(
      gobject_class, PROP_DARK_LEVEL,
      g_param_spec_double("dark-level", "Dark level",
                          "The camera's raw dark level in DN (0..65535), as given to darksub", 0.0,
                          65535.0, DEFAULT_DARK_LEVEL, playing));
  g_object_class_install_property(
      gobject_class, PROP_MIN_EXPOSURE,
      g_param_spec_double(
          "min-exposure", "Minimum exposure",
          "Shortest exposure to set, microseconds (0.001..1e9): set the camera's own minimum", 1e-3,
          1e9, DEFAULT_MIN_EXPOSURE, playing));
  g_object_class_install_property(
      gobject_class, PROP_MAX_EXPOSURE,
      g_param_spec_double("max-exposure", "Maximum exposure",
                          "Longest exposure to set, microseconds (0.001..1e9; keep it below the "
                          "frame period for the full frame rate)",
                          1e-3, 1e9, DEFAULT_MAX_EXPOSURE, playing));
  g_object_class_install_property(
      gobject_class, PROP_MAX_STEP,
      g_param_spec_double("max-step", "Largest step",
                          "Largest factor by which one adjustment changes the exposure; a "
                          "saturated frame steps down by this much (1.5..100)",
                          1.5, 100.0, DEFAULT_MAX_STEP, playing));
  g_object_class_install_property(
      gobject_class, PROP_TOLERANCE,
      g_param_spec_double("tolerance", "Tolerance",
                          "No change while the level's signal is within this share of the "
                          "target's (0.01..0.49)",
                          0.01, 0.49, DEFAULT_TOLERANCE, playing));
  g_object_class_install_property(
      gobject_class, PROP_LATENCY,
      g_param_spec_uint("latency", "Latency",
                        "Frames between setting an exposure and the first frame taken with it, "
                        "for frames that do not carry their exposure (0..100)",
                        0, 100, DEFAULT_LATENCY, playing));
  g_object_class_install_property(
      gobject_class, PROP_MAX_GAIN,
      g_param_spec_double("max-gain", "Maximum gain",
                          "Largest analogue gain to set on the camera's gain property, dB "
                          "(0..48); the gain rises above 0 dB only with the exposure at "
                          "max-exposure. 0: the gain is left as it is",
                          0.0, MAX_MAX_GAIN, DEFAULT_MAX_GAIN, playing));
  g_object_class_install_property(
      gobject_class, PROP_CAMERA,
      g_param_spec_string("camera", "Camera",
                          "Name of the element whose exposure property is set (empty: the first "
                          "element upstream without a sink pad)",
                          nullptr,
                          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                   GST_PARAM_MUTABLE_READY)));

  g_object_class_install_property(
      gobject_class, PROP_BRACKET,
      g_param_spec_string(
          "bracket", "Exposure bracket",
          "Exposure factors the camera's exposure cycles through, comma-separated, 2 to 16 of "
          "0.001..1000 times the controlled exposure (the first factor's frames are kept at the "
          "target), e.g. 1,8 for thermalfuse frames=2: each is held for latency + 1 frames and "
          "only the last frame of each passes, with its exposure; for cameras whose frames do "
          "not carry their exposure (aravissrc; pyrocamsrc has its own bracket). Empty (the "
          "default): no bracketing",
          "",
          static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                   GST_PARAM_MUTABLE_READY)));

  gst_element_class_set_static_metadata(
      element_class, "Exposure control for thermal reading", "Filter/Analyzer/Video",
      "Sets the camera's exposure (and gain) so that the hottest region neither saturates nor "
      "goes dim",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &sink_template);
  gst_element_class_add_static_pad_template(element_class, &src_template);

  // In place, not passthrough: the buffer must be writable to take a meta (a shared one is
  // copied without its pixels).
  trans_class->start = GST_DEBUG_FUNCPTR(gst_auto_exposure_start);
  trans_class->stop = GST_DEBUG_FUNCPTR(gst_auto_exposure_stop);
  trans_class->set_caps = GST_DEBUG_FUNCPTR(gst_auto_exposure_set_caps);
  trans_class->transform_ip = GST_DEBUG_FUNCPTR(gst_auto_exposure_transform_ip);
}

static void gst_auto_exposure_init(GstAutoExposure* self) {
  self->settings = new Settings();
  self->state = new State();
  gst_base_transform_set_in_place(GST_BASE_TRANSFORM(self), TRUE);
}
