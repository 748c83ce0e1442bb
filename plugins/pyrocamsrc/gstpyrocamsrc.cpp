/**
 * SECTION:element-pyrocamsrc
 * @title: pyrocamsrc
 *
 * A simulated camera, the thermal counterpart of videotestsrc: renders raw mosaic frames of a
 * test scene (a hot plate, a filament, or a melt pool crossing the frame) through a camera
 * profile with EMVA 1288 noise (pyrocam::Simulator). The "typical" unit deviates from the
 * profile's datasheet the way a real camera does (filter leak, per-band scale and tilt); the
 * "hostile" one also has moved filter edges, narrow leaks, a sloping ND glass and band shape
 * changes; the "foreign" one, deviations of other kinds (a moved and softened filter, weak
 * blocking everywhere outside its pass band, a bent lens transmission, stretched and reshaped
 * bands).
 *
 * Output follows the profile: 8-bit Bayer profiles give video/x-bayer (format = the pattern),
 * 5x5 profiles give video/x-raw GRAY8, profiles deeper than 8 bit GRAY16_LE; gray video carries
 * the profile's mosaic (pattern), bit-depth and saturation-level (its inference saturation
 * threshold) in the caps, as pyrocam-caps.h describes, so that darksub reads it right. Width and
 * height must be multiples of the mosaic period (2 or 5); the default 320x240 at 30/1 suits both.
 * Frames are timestamped from 0 at the negotiated frame rate; with #GstPyrocamSrc:is-live they
 * are pushed in real time. The simulated sensor clamps its black level: the dark level is the
 * profile's offset (50 DN for the shipped profiles, darksub dark-level=50) at every exposure,
 * the dark current adding its noise only (a camera without a clamp needs a dark frame of the
 * exposure: darksub location or capture-dark).
 *
 * The melt pool crosses the frame every 100 frames, its peak swinging between 1500 and
 * 2500 degC; the plate and the filament glow at #GstPyrocamSrc:temperature. Emissivities are
 * those of the calibration tool's scenes (plate 0.7, filament 0.4, melt pool 0.35). With
 * #GstPyrocamSrc:exposure 0 the exposure puts the brightest band 140 DN above the dark level (an
 * 8-bit camera's; a deeper one's the same share of its range) at the scene's nominal temperature
 * (plate, filament) or at 2000 degC (melt pool, as the calibration tool's scene sequences: the
 * hottest frames saturate, the coolest are dim). #GstPyrocamSrc:bracket cycles frame by frame
 * through exposure factors (e.g. "1,0.1": the exposure, then a tenth of it) for thermalfuse, which
 * reads each pixel from the most exposed frame where it reads. #GstPyrocamSrc:gain (dB) multiplies
 * the signal of the collected charge, shot noise included, by 10^(gain/20); the read noise stays as
 * it is in DN (simpler than a real sensor, whose read noise at the output grows partly with gain).
 * Every frame carries the exposure and gain it was taken with (PyrocamExposureMeta).
 *
 * ## Example launch line
 * |[
 * gst-launch-1.0 pyrocamsrc scene=filament temperature=1400 num-buffers=100 ! \
 *     darksub dark-level=50 ! demosaic25 ! fakesink
 * ]|
 */
#include "gstpyrocamsrc.h"

#include <gst/video/video.h>

#include <cmath>
#include <memory>
#include <string>

#include "pyrocam-caps.h"
#include "pyrocam-common.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/bracket_fusion.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "pyrocamsrc-private.h"

GST_DEBUG_CATEGORY_STATIC(gst_pyrocam_src_debug);
#define GST_CAT_DEFAULT gst_pyrocam_src_debug

namespace pg = pyrocam::gst;

namespace {

enum {
  PROP_0,
  PROP_SCENE,
  PROP_PROFILE,
  PROP_UNIT,
  PROP_EXPOSURE,
  PROP_TEMPERATURE,
  PROP_SEED,
  PROP_IS_LIVE,
  PROP_BRACKET,
  PROP_GAIN,
};

constexpr GstPyrocamSrcScene DEFAULT_SCENE = GST_PYROCAM_SRC_SCENE_MELT_POOL;
constexpr const char* DEFAULT_PROFILE = "rgb-reference";
constexpr GstPyrocamSrcUnit DEFAULT_UNIT = GST_PYROCAM_SRC_UNIT_TYPICAL;
constexpr double DEFAULT_EXPOSURE = 0.0;
constexpr double DEFAULT_GAIN = 0.0;
constexpr double MAX_GAIN = 24.0;
constexpr double DEFAULT_TEMPERATURE = 1200.0;
constexpr guint64 DEFAULT_SEED = 1;
constexpr gboolean DEFAULT_IS_LIVE = FALSE;
constexpr int DEFAULT_WIDTH = 320, DEFAULT_HEIGHT = 240, DEFAULT_FPS = 30;
constexpr int kMeltPoolFrames = 100;
// Exposure and emissivities as pyrocam-calib's scene sequences (pyrocam::kSceneDefaults); the
// exposure property's description and the documentation above give these numbers.
constexpr pyrocam::SceneDefaults kScene = pyrocam::kSceneDefaults;
static_assert(kScene.target_dn == 140 && kScene.melt_pool_exposure_c == 2000,
              "update the exposure property's description, the element documentation and "
              "tests/elements/inspect/pyrocamsrc.txt");
static_assert(kScene.plate_emissivity == 0.7 && kScene.filament_emissivity == 0.4 &&
                  kScene.melt_pool_emissivity == 0.35,
              "update the element documentation");

struct Settings {
  GstPyrocamSrcScene scene = DEFAULT_SCENE;
  std::string profile = DEFAULT_PROFILE;
  GstPyrocamSrcUnit unit = DEFAULT_UNIT;
  double exposure_us = DEFAULT_EXPOSURE;
  double gain_db = DEFAULT_GAIN;
  double temperature_c = DEFAULT_TEMPERATURE;
  guint64 seed = DEFAULT_SEED;
  std::string bracket_text;     // as set
  std::vector<double> bracket;  // parsed factors; empty: none
  bool bracket_valid = true;    // else start() refuses to run
};

struct State {
  std::unique_ptr<pyrocam::Simulator> camera;  // built in start()
  int width = 0, height = 0, fps_n = 0, fps_d = 1;
  bool bayer_caps = false;
  gsize stride = 0, frame_size = 0;
  guint64 frame = 0;
  bool exposure_held = false;  // a frame's exposure was held to the range (warned once)
  // The last static scene, kept while scene and temperature do not change.
  cv::Mat scene_map;
  GstPyrocamSrcScene scene_kind = DEFAULT_SCENE;
  double scene_temperature = NAN;
};

pyrocam::SceneKind scene_kind(GstPyrocamSrcScene scene) {
  switch (scene) {
    case GST_PYROCAM_SRC_SCENE_PLATE:
      return pyrocam::SceneKind::kPlate;
    case GST_PYROCAM_SRC_SCENE_FILAMENT:
      return pyrocam::SceneKind::kFilament;
    default:
      return pyrocam::SceneKind::kMeltPool;
  }
}

}  // namespace

struct _GstPyrocamSrc {
  GstPushSrc parent;
  Settings* settings;
  State* state;
};

G_DEFINE_TYPE(GstPyrocamSrc, gst_pyrocam_src, GST_TYPE_PUSH_SRC);
GST_ELEMENT_REGISTER_DEFINE(pyrocamsrc, "pyrocamsrc", GST_RANK_NONE, GST_TYPE_PYROCAM_SRC);

namespace {
const char* unit_name(GstPyrocamSrcUnit unit) {
  switch (unit) {
    case GST_PYROCAM_SRC_UNIT_TYPICAL:
      return "typical";
    case GST_PYROCAM_SRC_UNIT_HOSTILE:
      return "hostile";
    case GST_PYROCAM_SRC_UNIT_FOREIGN:
      return "foreign";
    default:
      return "datasheet";
  }
}
}  // namespace

static GstStaticPadTemplate src_template =
    GST_STATIC_PAD_TEMPLATE("src", GST_PAD_SRC, GST_PAD_ALWAYS, GST_STATIC_CAPS(PYROCAM_RAW_CAPS));

static Settings copy_settings(GstPyrocamSrc* self) {
  return pg::locked_copy(self, *self->settings);
}

static GstCaps* gst_pyrocam_src_get_caps(GstBaseSrc* src, GstCaps* filter) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(src);
  GstCaps* caps;
  const bool have = pg::locked_copy(self, self->state->camera != nullptr);
  if (have)
    caps = pyrocam::gst::pyrocamsrc::profile_caps(self->state->camera->profile());
  else
    caps = gst_pad_get_pad_template_caps(GST_BASE_SRC_PAD(src));
  if (filter) {
    GstCaps* tmp = gst_caps_intersect_full(filter, caps, GST_CAPS_INTERSECT_FIRST);
    gst_caps_unref(caps);
    caps = tmp;
  }
  return caps;
}

/* GstBaseSrc says only "not-negotiated" when downstream takes none of the profile's formats. */
static gboolean gst_pyrocam_src_negotiate(GstBaseSrc* src) {
  if (GST_BASE_SRC_CLASS(gst_pyrocam_src_parent_class)->negotiate(src)) return TRUE;
  GstPyrocamSrc* self = GST_PYROCAM_SRC(src);
  if (self->state->camera)
    pyrocam::gst::pyrocamsrc::explain_refused_caps(GST_ELEMENT(src), GST_BASE_SRC_PAD(src),
                                                   self->state->camera->profile());
  return FALSE;
}

static GstCaps* gst_pyrocam_src_fixate(GstBaseSrc* src, GstCaps* caps) {
  caps = gst_caps_make_writable(caps);
  GstStructure* s = gst_caps_get_structure(caps, 0);
  gst_structure_fixate_field_nearest_int(s, "width", DEFAULT_WIDTH);
  gst_structure_fixate_field_nearest_int(s, "height", DEFAULT_HEIGHT);
  gst_structure_fixate_field_nearest_fraction(s, "framerate", DEFAULT_FPS, 1);
  return GST_BASE_SRC_CLASS(gst_pyrocam_src_parent_class)->fixate(src, caps);
}

static gboolean gst_pyrocam_src_set_caps(GstBaseSrc* src, GstCaps* caps) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(src);
  State& st = *self->state;
  if (!st.camera) return FALSE;
  const pyrocam::MosaicLayout& mosaic = st.camera->profile().mosaic;
  pg::RawFormat f;
  const GstStructure* s = gst_caps_get_structure(caps, 0);
  if (!pg::parse_raw_caps(caps, &f) ||
      !gst_structure_get_fraction(s, "framerate", &st.fps_n, &st.fps_d)) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation, "Unsupported output format",
                       "caps without size or frame rate");
    return FALSE;
  }
  if (st.fps_n <= 0) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       "framerate " + std::to_string(st.fps_n) + "/" + std::to_string(st.fps_d) +
                           ": the simulated camera runs at a fixed frame rate; give one above 0",
                       "variable frame rate asked for");
    return FALSE;
  }
  if (f.width % mosaic.period_width || f.height % mosaic.period_height) {
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kNegotiation,
                       std::to_string(f.width) + "x" + std::to_string(f.height) +
                           " is not a whole number of " + mosaic.pattern + " mosaic periods",
                       "width and height must be multiples of the mosaic period");
    return FALSE;
  }
  st.width = f.width;
  st.height = f.height;
  st.bayer_caps = f.bayer_caps;
  st.frame_size = pg::raw_frame_size(f);
  st.stride = f.bayer_caps ? static_cast<gsize>(GST_ROUND_UP_4(f.width))
                           : static_cast<gsize>(GST_VIDEO_INFO_PLANE_STRIDE(&f.info, 0));
  st.scene_map.release();
  gst_base_src_set_blocksize(src, static_cast<guint>(st.frame_size));
  GST_INFO_OBJECT(self, "%dx%d at %d/%d, %" G_GSIZE_FORMAT " bytes per frame", st.width, st.height,
                  st.fps_n, st.fps_d, st.frame_size);
  return TRUE;
}

static gboolean gst_pyrocam_src_decide_allocation(GstBaseSrc* src, GstQuery* query) {
  pg::pyrocamsrc::propose_own_pool(query, GST_PYROCAM_SRC(src)->state->frame_size);
  return GST_BASE_SRC_CLASS(gst_pyrocam_src_parent_class)->decide_allocation(src, query);
}

static gboolean gst_pyrocam_src_start(GstBaseSrc* src) {
  pg::forget_posted_errors(GST_ELEMENT(src));
  GstPyrocamSrc* self = GST_PYROCAM_SRC(src);
  const Settings settings = copy_settings(self);
  if (!settings.bracket_valid) {
    std::string why;
    try {
      pyrocam::parse_bracket(settings.bracket_text);
    } catch (const std::exception& e) {
      why = e.what();
    }
    PYROCAM_POST_ERROR(self, pg::ErrorKind::kSettings, why, "the bracket property did not parse");
    return FALSE;
  }
  std::unique_ptr<pyrocam::Simulator> camera;
  const bool ok = PYROCAM_GUARDED(
      self, pg::profile_error_kind(settings.profile),
      "Could not set up the simulated camera " + settings.profile, [&] {
        const pyrocam::CameraProfile profile = pyrocam::load_profile_by_name(settings.profile);
        const auto unit = pyrocam::UnitPerturbation::parse(unit_name(settings.unit), settings.seed);
        camera = std::make_unique<pyrocam::Simulator>(profile, unit, settings.seed + 6);
        // Its dark level is the profile's offset at any exposure, what darksub dark-level
        // says: the automatic exposure of a cold scene runs to seconds (33 s for the 5x5 camera
        // at 550 degC), whose dark current read it 270 degC high with dark-level=50.
        camera->set_black_level_clamp(true);
      });
  if (!ok) return FALSE;
  GST_INFO_OBJECT(self, "camera profile %s, %s unit", camera->profile().name.c_str(),
                  unit_name(settings.unit));
  pg::ObjectLock lock(self);
  *self->state = State();
  self->state->camera = std::move(camera);
  return TRUE;
}

static gboolean gst_pyrocam_src_stop(GstBaseSrc* src) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(src);
  pg::ObjectLock lock(self);
  *self->state = State();
  return TRUE;
}

static void gst_pyrocam_src_get_times(GstBaseSrc* src, GstBuffer* buffer, GstClockTime* start,
                                      GstClockTime* end) {
  /* Live: basesrc waits on the clock until each frame's time. */
  if (gst_base_src_is_live(src)) {
    const GstClockTime pts = GST_BUFFER_PTS(buffer);
    if (GST_CLOCK_TIME_IS_VALID(pts)) {
      *start = pts;
      if (GST_BUFFER_DURATION_IS_VALID(buffer)) *end = pts + GST_BUFFER_DURATION(buffer);
    }
  } else {
    *start = GST_CLOCK_TIME_NONE;
    *end = GST_CLOCK_TIME_NONE;
  }
}

static GstFlowReturn gst_pyrocam_src_fill(GstPushSrc* push, GstBuffer* buffer) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(push);
  State& st = *self->state;
  if (!st.camera || st.width == 0) return GST_FLOW_NOT_NEGOTIATED;
  const GstClockTime pts = gst_util_uint64_scale(
      st.frame, static_cast<guint64>(st.fps_d) * GST_SECOND, static_cast<guint64>(st.fps_n));
  // Controlled properties (scene, exposure, gain, temperature) take their values at the frame's
  // time; the segment starts at 0, so that is its stream time.
  gst_object_sync_values(GST_OBJECT(self), pts);
  const Settings settings = copy_settings(self);
  const double emissivity = kScene.emissivity(scene_kind(settings.scene));
  const bool ok = PYROCAM_GUARDED(self, pg::ErrorKind::kSettings, "Could not render a frame", [&] {
    const cv::Mat* map;
    cv::Mat pool;
    double nominal_c = settings.temperature_c;
    if (settings.scene == GST_PYROCAM_SRC_SCENE_MELT_POOL) {
      const int index = static_cast<int>(st.frame % kMeltPoolFrames);
      pool = pyrocam::melt_pool_scene(st.width, st.height, index, kMeltPoolFrames);
      map = &pool;
      nominal_c = kScene.melt_pool_exposure_c;
    } else {
      if (st.scene_map.empty() || st.scene_kind != settings.scene ||
          st.scene_temperature != settings.temperature_c) {
        st.scene_map = settings.scene == GST_PYROCAM_SRC_SCENE_PLATE
                           ? pyrocam::plate_scene(st.width, st.height, settings.temperature_c)
                           : pyrocam::filament_scene(st.width, st.height, settings.temperature_c);
        st.scene_kind = settings.scene;
        st.scene_temperature = settings.temperature_c;
      }
      map = &st.scene_map;
    }
    const double factor =
        settings.bracket.empty() ? 1.0 : settings.bracket[st.frame % settings.bracket.size()];
    // The automatic exposure of a cold scene runs to hours (a 300 degC plate: 7500 s): held to
    // the property's range, as a camera holds it to its own.
    const double exposure =
        pg::pyrocamsrc::frame_exposure_us(GST_ELEMENT(self), *st.camera, settings.exposure_us,
                                          factor, nominal_c, emissivity, st.exposure_held);
    const cv::Mat raw = st.camera->render(*map, exposure, emissivity, settings.gain_db);
    pyrocam_buffer_add_exposure_meta(buffer, exposure, settings.gain_db);
    GstMapInfo info;
    if (!gst_buffer_map(buffer, &info, GST_MAP_WRITE))
      throw pyrocam::InputError("cannot map the output buffer");
    const std::size_t row_bytes = raw.elemSize() * static_cast<std::size_t>(raw.cols);
    if (info.size < st.frame_size || row_bytes > st.stride) {
      gst_buffer_unmap(buffer, &info);
      throw pyrocam::InputError("output buffer too small");
    }
    for (int y = 0; y < raw.rows; ++y)
      std::memcpy(info.data + static_cast<std::size_t>(y) * st.stride, raw.ptr(y), row_bytes);
    gst_buffer_unmap(buffer, &info);
  });
  if (!ok) return GST_FLOW_ERROR;

  const GstClockTime next = gst_util_uint64_scale(
      st.frame + 1, static_cast<guint64>(st.fps_d) * GST_SECOND, static_cast<guint64>(st.fps_n));
  GST_BUFFER_PTS(buffer) = pts;
  GST_BUFFER_DTS(buffer) = GST_CLOCK_TIME_NONE;
  GST_BUFFER_DURATION(buffer) = next - pts;
  GST_BUFFER_OFFSET(buffer) = st.frame;
  GST_BUFFER_OFFSET_END(buffer) = st.frame + 1;
  ++st.frame;
  return GST_FLOW_OK;
}

static void gst_pyrocam_src_set_property(GObject* object, guint prop_id, const GValue* value,
                                         GParamSpec* pspec) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(object);
  if (prop_id == PROP_IS_LIVE) {
    // Made live while PLAYING, basesrc waited for a PLAYING that had already come: no frame
    // again, no error, no end.
    if (GST_STATE(self) > GST_STATE_READY) {
      pg::warn_not_changeable_while_running(GST_ELEMENT(self), "is-live");
      return;
    }
    gst_base_src_set_live(GST_BASE_SRC(self), g_value_get_boolean(value));
    return;
  }
  const char* refused_while_running = nullptr;  // posted once the lock is released
  std::string refused_bracket;                  // the same
  {
    pg::ObjectLock lock(self);
    Settings& s = *self->settings;
    const bool running = GST_STATE(self) > GST_STATE_READY;
    switch (prop_id) {
      case PROP_SCENE:
        s.scene = static_cast<GstPyrocamSrcScene>(g_value_get_enum(value));
        break;
      case PROP_PROFILE:
        if (running) {
          refused_while_running = "profile";
        } else {
          const char* v = g_value_get_string(value);
          s.profile = v && *v ? v : DEFAULT_PROFILE;
        }
        break;
      case PROP_UNIT:
        if (running)
          refused_while_running = "unit";
        else
          s.unit = static_cast<GstPyrocamSrcUnit>(g_value_get_enum(value));
        break;
      case PROP_EXPOSURE:
        s.exposure_us = g_value_get_double(value);
        break;
      case PROP_GAIN:
        s.gain_db = g_value_get_double(value);
        break;
      case PROP_TEMPERATURE:
        s.temperature_c = g_value_get_double(value);
        break;
      case PROP_SEED:
        if (running)
          refused_while_running = "seed";
        else
          s.seed = g_value_get_uint64(value);
        break;
      case PROP_BRACKET: {
        const char* v = g_value_get_string(value);
        try {
          s.bracket = pyrocam::parse_bracket(v ? v : "");
          s.bracket_text = v ? v : "";
          s.bracket_valid = true;
        } catch (const std::exception& e) {
          // Playing: the last good bracket stays, and reads back; else start() refuses to run.
          if (running) {
            refused_bracket = std::string("bracket '") + (v ? v : "") + "' refused (" + e.what() +
                              "); the bracket stays '" + s.bracket_text + "'";
          } else {
            s.bracket_text = v ? v : "";
            s.bracket_valid = false;
          }
        }
        break;
      }
      default:
        G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
        break;
    }
  }
  if (refused_while_running)
    pg::warn_not_changeable_while_running(GST_ELEMENT(self), refused_while_running);
  if (!refused_bracket.empty())
    GST_ELEMENT_WARNING(self, RESOURCE, SETTINGS, ("%s", refused_bracket.c_str()),
                        ("bracket set while running"));
}

static void gst_pyrocam_src_get_property(GObject* object, guint prop_id, GValue* value,
                                         GParamSpec* pspec) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(object);
  if (prop_id == PROP_IS_LIVE) {
    g_value_set_boolean(value, gst_base_src_is_live(GST_BASE_SRC(self)));
    return;
  }
  pg::ObjectLock lock(self);
  const Settings& s = *self->settings;
  switch (prop_id) {
    case PROP_SCENE:
      g_value_set_enum(value, s.scene);
      break;
    case PROP_PROFILE:
      g_value_set_string(value, s.profile.c_str());
      break;
    case PROP_UNIT:
      g_value_set_enum(value, s.unit);
      break;
    case PROP_EXPOSURE:
      g_value_set_double(value, s.exposure_us);
      break;
    case PROP_GAIN:
      g_value_set_double(value, s.gain_db);
      break;
    case PROP_TEMPERATURE:
      g_value_set_double(value, s.temperature_c);
      break;
    case PROP_BRACKET:
      g_value_set_string(value, s.bracket_text.c_str());
      break;
    case PROP_SEED:
      g_value_set_uint64(value, s.seed);
      break;
    default:
      G_OBJECT_WARN_INVALID_PROPERTY_ID(object, prop_id, pspec);
      break;
  }
}

static void gst_pyrocam_src_finalize(GObject* object) {
  GstPyrocamSrc* self = GST_PYROCAM_SRC(object);
  delete self->settings;
  delete self->state;
  G_OBJECT_CLASS(gst_pyrocam_src_parent_class)->finalize(object);
}

static void gst_pyrocam_src_class_init(GstPyrocamSrcClass* klass) {
  GObjectClass* gobject_class = G_OBJECT_CLASS(klass);
  GstElementClass* element_class = GST_ELEMENT_CLASS(klass);
  GstBaseSrcClass* basesrc_class = GST_BASE_SRC_CLASS(klass);
  GstPushSrcClass* pushsrc_class = GST_PUSH_SRC_CLASS(klass);

  GST_DEBUG_CATEGORY_INIT(gst_pyrocam_src_debug, "pyrocamsrc", 0, "pyrocam simulated camera");

  gobject_class->set_property = gst_pyrocam_src_set_property;
  gobject_class->get_property = gst_pyrocam_src_get_property;
  gobject_class->finalize = gst_pyrocam_src_finalize;

  const auto ready = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                              GST_PARAM_MUTABLE_READY);
  const auto playing = static_cast<GParamFlags>(G_PARAM_READWRITE | G_PARAM_STATIC_STRINGS |
                                                GST_PARAM_MUTABLE_PLAYING | GST_PARAM_CONTROLLABLE);
  g_object_class_install_property(
      gobject_class, PROP_SCENE,
      g_param_spec_enum("scene", "Scene", "What the camera looks at", GST_TYPE_PYROCAM_SRC_SCENE,
                        DEFAULT_SCENE, playing));
  g_object_class_install_property(
      gobject_class, PROP_PROFILE,
      g_param_spec_string("profile", "Camera profile",
                          "Camera profile: a shipped name (rgb-reference, nir5x5-reference) or "
                          "a path to its JSON file",
                          DEFAULT_PROFILE, ready));
  g_object_class_install_property(
      gobject_class, PROP_UNIT,
      g_param_spec_enum("unit", "Camera unit",
                        "Which unit of the camera model: the datasheet itself, a typical unit "
                        "deviating from it, or a hostile or foreign one (drawn from seed)",
                        GST_TYPE_PYROCAM_SRC_UNIT, DEFAULT_UNIT, ready));
  g_object_class_install_property(
      gobject_class, PROP_EXPOSURE,
      g_param_spec_double("exposure", "Exposure",
                          "Exposure time in microseconds (0..10000000); 0: automatic, the "
                          "brightest band 140 DN above dark (8-bit; deeper cameras: the same share "
                          "of their range) at the scene's nominal temperature (melt pool: 2000 "
                          "degC)",
                          0.0, pg::pyrocamsrc::kMaxExposureUs, DEFAULT_EXPOSURE, playing));
  g_object_class_install_property(
      gobject_class, PROP_GAIN,
      g_param_spec_double("gain", "Gain",
                          "Analogue gain in dB (0..24): the collected charge's signal (shot noise "
                          "included) times 10^(gain/20), the read noise in DN as at 0 dB (a real "
                          "sensor's grows partly with gain); the automatic exposure is for 0 dB",
                          0.0, MAX_GAIN, DEFAULT_GAIN, playing));
  g_object_class_install_property(
      gobject_class, PROP_BRACKET,
      g_param_spec_string(
          "bracket", "Exposure bracket",
          "Exposure factors the frames cycle through, comma-separated, each 0.001..1000 times "
          "the exposure (or the automatic one), at most 16: e.g. 1,0.1 alternates the exposure "
          "and a tenth of it, for thermalfuse; empty: every frame at the exposure",
          "", playing));
  g_object_class_install_property(
      gobject_class, PROP_TEMPERATURE,
      g_param_spec_double("temperature", "Temperature",
                          "Temperature in degC of the plate or filament scene (100..4000)", 100.0,
                          4000.0, DEFAULT_TEMPERATURE, playing));
  g_object_class_install_property(
      gobject_class, PROP_SEED,
      g_param_spec_uint64("seed", "Seed",
                          "Seed of the unit's deviation and of the noise (0..2^64-1); equal "
                          "seeds give equal frames",
                          0, G_MAXUINT64, DEFAULT_SEED, ready));
  g_object_class_install_property(
      gobject_class, PROP_IS_LIVE,
      g_param_spec_boolean("is-live", "Is live",
                           "Behave as a live camera: push frames in real time", DEFAULT_IS_LIVE,
                           ready));

  gst_element_class_set_static_metadata(
      element_class, "Simulated thermal camera", "Source/Video",
      "Raw mosaic frames of hot test scenes through a camera model with sensor noise",
      "pyrocam developers");
  gst_element_class_add_static_pad_template(element_class, &src_template);

  basesrc_class->get_caps = GST_DEBUG_FUNCPTR(gst_pyrocam_src_get_caps);
  basesrc_class->negotiate = GST_DEBUG_FUNCPTR(gst_pyrocam_src_negotiate);
  basesrc_class->fixate = GST_DEBUG_FUNCPTR(gst_pyrocam_src_fixate);
  basesrc_class->set_caps = GST_DEBUG_FUNCPTR(gst_pyrocam_src_set_caps);
  basesrc_class->decide_allocation = GST_DEBUG_FUNCPTR(gst_pyrocam_src_decide_allocation);
  basesrc_class->start = GST_DEBUG_FUNCPTR(gst_pyrocam_src_start);
  basesrc_class->stop = GST_DEBUG_FUNCPTR(gst_pyrocam_src_stop);
  basesrc_class->get_times = GST_DEBUG_FUNCPTR(gst_pyrocam_src_get_times);
  pushsrc_class->fill = GST_DEBUG_FUNCPTR(gst_pyrocam_src_fill);

  gst_type_mark_as_plugin_api(GST_TYPE_PYROCAM_SRC_SCENE, static_cast<GstPluginAPIFlags>(0));
  gst_type_mark_as_plugin_api(GST_TYPE_PYROCAM_SRC_UNIT, static_cast<GstPluginAPIFlags>(0));
}

static void gst_pyrocam_src_init(GstPyrocamSrc* self) {
  self->settings = new Settings();
  self->state = new State();
  gst_base_src_set_format(GST_BASE_SRC(self), GST_FORMAT_TIME);
  gst_base_src_set_live(GST_BASE_SRC(self), DEFAULT_IS_LIVE);
}
