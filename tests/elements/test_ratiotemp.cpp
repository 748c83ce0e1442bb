// ratiotemp: caps for colour and 5x5 bands, codes against the library for every method and
// for the uncertainty, no-reading marks through the chain, live method/region changes, the
// statistics message against region_stats, flush/EOS, the peak (test_ratiotemp_errors.cpp: whole
// pipelines and the bus errors for bad models and caps).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>

#include "element_support.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/emissivity.h"
#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/runtime/region_stats.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

std::string rgb_model_path() { return test_model_path("test-model-rgb.json"); }
std::string nir_model_path() { return test_model_path("test-model-nir5x5.json"); }

// The test models, loaded once per binary.
const std::shared_ptr<const ThermalModel>& rgb_model() {
  static const auto m = std::make_shared<const ThermalModel>(load_model(rgb_model_path()));
  return m;
}
const std::shared_ptr<const ThermalModel>& nir_model() {
  static const auto m = std::make_shared<const ThermalModel>(load_model(nir_model_path()));
  return m;
}

// What the element's auto method is for a model (its documented rule): the lookup table for
// two-ratio models when it gives the network's answer on the model's locus (within 1 degC, and
// reading where the network does at all but 1 % of the samples), else likelihood.
bool lut_passes_its_check(const std::shared_ptr<const ThermalModel>& m) {
  const auto lut = make_estimator(m, Method::kLut);
  const auto mlp = make_estimator(m, Method::kMlp);
  const LocusAgreement a = compare_on_locus(*m, *lut, *mlp);
  return a.max_difference_c <= 1.0 && a.validity_differs * 100 <= a.samples;
}
Method rgb_auto_method() {
  static const Method m = lut_passes_its_check(rgb_model()) ? Method::kLut : Method::kLikelihood;
  return m;
}

// Band planes (plane after plane) of a graybody whose temperature runs from t0 to t1 over the
// pixels, brightest band at `peak` DN, with a small per-pixel, per-band wobble so that the
// ratios leave the locus a little as noisy pixels do.
std::vector<float> graybody_planes(const ThermalModel& m, int w, int h, double t0, double t1,
                                   double peak = 150) {
  const int bands = m.profile().band_count();
  const int n = w * h;
  std::vector<float> v(static_cast<std::size_t>(bands * n));
  for (int i = 0; i < n; ++i) {
    const double t = n > 1 ? t0 + (t1 - t0) * i / (n - 1) : t0;
    const Eigen::VectorXd rates = m.camera.rates(t);
    const double scale = peak / rates.maxCoeff();
    for (int b = 0; b < bands; ++b)
      v[static_cast<std::size_t>(b * n + i)] =
          static_cast<float>(rates[b] * scale * (1 + 0.01 * std::sin(1.7 * i + 0.9 * b)));
  }
  return v;
}

std::string bands_caps(int bands, const char* layout, int w, int h) {
  return "video/x-pyrocam-bands,format=F32LE,bands=" + std::to_string(bands) +
         ",width=" + std::to_string(w) + ",height=" + std::to_string(h) +
         ",framerate=30/1,layout=" + layout;
}

std::vector<cv::Mat> plane_views(const std::vector<float>& planes, int bands, int w, int h) {
  std::vector<cv::Mat> p;
  for (int b = 0; b < bands; ++b)
    p.emplace_back(h, w, CV_32F, const_cast<float*>(planes.data()) + b * w * h);
  return p;
}

// The library's answer: temperature (degC) and, when asked, uncertainty. Unless `partial`,
// pixels with any band that is not a reading have none (the element's allow-partial=false).
struct LibraryResult {
  cv::Mat t, u;
};
LibraryResult library(const std::shared_ptr<const ThermalModel>& model, Method method,
                      const std::vector<cv::Mat>& planes, bool uncertainty = false,
                      bool partial = false) {
  const ThermalModel& m = *model;
  LibraryResult r;
  PlaneEstimator est(model, method);
  est.set_allow_partial(partial);
  est.estimate(planes, r.t, uncertainty ? &r.u : nullptr);
  if (!partial) {
    // Checked here against the independent mask, so that the element's results compared with
    // these are held to it too.
    const double dim_dn = m.profile().thresholds.inference_dim_dn;
    for (int y = 0; y < r.t.rows; ++y)
      for (int x = 0; x < r.t.cols; ++x) {
        bool complete = true;
        for (const cv::Mat& plane : planes) {
          const float v = plane.at<float>(y, x);
          complete = complete && std::isfinite(v) && v >= dim_dn;
        }
        if (!complete) {
          EXPECT_TRUE(std::isnan(r.t.at<float>(y, x)));
        }
      }
  }
  return r;
}
LibraryResult library(const std::shared_ptr<const ThermalModel>& m, Method method,
                      const std::vector<float>& planes, int w, int h, bool uncertainty = false,
                      bool partial = false) {
  return library(m, method, plane_views(planes, m->profile().band_count(), w, h), uncertainty,
                 partial);
}

std::vector<std::uint16_t> codes_of(const cv::Mat& codes) {
  std::vector<std::uint16_t> v;
  for (int y = 0; y < codes.rows; ++y)
    v.insert(v.end(), codes.ptr<std::uint16_t>(y), codes.ptr<std::uint16_t>(y) + codes.cols);
  return v;
}
std::vector<std::uint16_t> library_codes(const std::shared_ptr<const ThermalModel>& m,
                                         Method method, const std::vector<float>& planes, int w,
                                         int h, bool partial = false) {
  return codes_of(encode_decikelvin(library(m, method, planes, w, h, false, partial).t));
}

// GRAY16_LE pixels of an output buffer, without the row padding (stride GST_ROUND_UP_4(2 w)).
std::vector<std::uint16_t> gray16_of(GstBuffer* buffer, int w, int h) {
  const int stride = GST_ROUND_UP_4(2 * w);
  EXPECT_EQ(gst_buffer_get_size(buffer), static_cast<gsize>(stride * h));
  const auto bytes = values_of<std::uint8_t>(buffer);
  std::vector<std::uint16_t> v(static_cast<std::size_t>(w * h));
  if (bytes.size() < static_cast<std::size_t>(stride * h)) return v;
  for (int y = 0; y < h; ++y)
    std::memcpy(&v[static_cast<std::size_t>(y * w)], &bytes[static_cast<std::size_t>(y * stride)],
                static_cast<std::size_t>(2 * w));
  return v;
}

class RatioTemp : public HarnessTest {
 protected:
  RatioTemp() : HarnessTest("ratiotemp") {}
  void TearDown() override {
    if (element) gst_object_unref(element);
    element = nullptr;
    HarnessTest::TearDown();
  }
  // The harness around a parsed chain, with a bus attached before it starts so that messages
  // posted at start are kept.
  void start(const std::string& launch, const std::string& caps) {
    GError* error = nullptr;
    GstElement* bin = gst_parse_bin_from_description(launch.c_str(), TRUE, &error);
    ASSERT_TRUE(bin && !error) << (error ? error->message : launch);
    bus = gst_bus_new();
    gst_element_set_bus(bin, bus);
    h = gst_harness_new_with_element(bin, "sink", "src");
    gst_object_unref(bin);
    element = find_element(h, "ratiotemp");
    gst_harness_set_src_caps_str(h, caps.c_str());
  }
  // Pushes one frame of band planes (or raw bytes) and returns the output codes.
  template <typename T>
  std::vector<std::uint16_t> run(const std::vector<T>& input, int w, int height,
                                 GstClockTime pts = GST_CLOCK_TIME_NONE) {
    GstBuffer* out = push_pull_buffer(h, with_pts(buffer_from(input), pts));
    if (!out) return {};
    auto v = gray16_of(out, w, height);
    gst_buffer_unref(out);
    return v;
  }
  // The same with darksub (dark level 50) and demosaic25 in front, fed raw 8x8 RGGB frames.
  // Bilinear demosaicking: the saturated pixel's neighbours are the 3x3 it reaches.
  void start_on_raw_frames(const std::string& ratiotemp,
                           const std::string& demosaic = "demosaic25 method=bilinear") {
    start("darksub dark-level=50 ! " + demosaic + " ! " + ratiotemp,
          "video/x-bayer,format=rggb,width=8,height=8,framerate=30/1");
  }
  // Element messages of a name posted so far.
  std::vector<GstStructure*> messages(const char* name) {
    std::vector<GstStructure*> out;
    while (GstMessage* m = gst_bus_pop_filtered(
               bus, static_cast<GstMessageType>(GST_MESSAGE_ELEMENT | GST_MESSAGE_WARNING))) {
      const GstStructure* s = gst_message_get_structure(m);
      if (GST_MESSAGE_TYPE(m) == GST_MESSAGE_WARNING) {
        GError* err = nullptr;
        gst_message_parse_warning(m, &err, nullptr);
        warnings.push_back(err->message);
        g_error_free(err);
      } else if (s && gst_structure_has_name(s, name)) {
        out.push_back(gst_structure_copy(s));
      }
      gst_message_unref(m);
    }
    return out;
  }
  std::vector<GstStructure*> stats() { return messages("pyrocam-temperature-stats"); }

  GstElement* element = nullptr;
  std::vector<std::string> warnings;
};

TEST_F(RatioTemp, bayer_bands_negotiate_to_gray16_of_the_same_size) {
  start("ratiotemp model=" + rgb_model_path(), bands_caps(3, "bayer", 7, 5));
  const auto planes = graybody_planes(*rgb_model(), 7, 5, 900, 1600);
  const auto out = run(planes, 7, 5);  // odd width: rows padded to 16 bytes
  EXPECT_EQ(out, library_codes(rgb_model(), rgb_auto_method(), planes, 7, 5));
  EXPECT_GT(count_nonzero(out), 30u);
  const std::string caps = sink_caps(h);
  for (const char* part : {"video/x-raw", "format=(string)GRAY16_LE", "width=(int)7",
                           "height=(int)5", "framerate=(fraction)30/1"})
    EXPECT_NE(caps.find(part), std::string::npos) << part << " in " << caps;
}

TEST_F(RatioTemp, snapshot_bands_negotiate_with_the_5x5_model) {
  start("ratiotemp model=" + nir_model_path(), bands_caps(25, "5x5", 4, 3));
  const auto planes = graybody_planes(*nir_model(), 4, 3, 1000, 2000);
  const auto out = run(planes, 4, 3);
  // auto is likelihood for a 25-band model.
  EXPECT_EQ(out, library_codes(nir_model(), Method::kLikelihood, planes, 4, 3));
  EXPECT_GT(count_nonzero(out), 8u);
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("format=(string)GRAY16_LE"), std::string::npos) << caps;
  EXPECT_NE(caps.find("width=(int)4"), std::string::npos) << caps;
}

TEST_F(RatioTemp, every_method_gives_the_library_codes) {
  struct Case {
    const char* method;
    Method library_method;
    bool colour;
  };
  std::vector<Case> cases = {Case{"mlp", Method::kMlp, true},
                             Case{"likelihood", Method::kLikelihood, true},
                             Case{"auto", rgb_auto_method(), true},
                             Case{"mlp", Method::kMlp, false},
                             Case{"likelihood", Method::kLikelihood, false},
                             Case{"auto", Method::kLikelihood, false}};
  // lut only where it passed its check (else the element refuses it: see RatioTempErrors).
  if (rgb_auto_method() == Method::kLut) cases.push_back(Case{"lut", Method::kLut, true});
  for (const Case& c : cases) {
    SCOPED_TRACE(std::string(c.method) + (c.colour ? " colour" : " 5x5"));
    const std::shared_ptr<const ThermalModel>& model = c.colour ? rgb_model() : nir_model();
    const ThermalModel& m = *model;
    const int w = 6, hh = 4;
    start(std::string("ratiotemp method=") + c.method +
              " model=" + (c.colour ? rgb_model_path() : nir_model_path()),
          bands_caps(m.profile().band_count(), c.colour ? "bayer" : "5x5", w, hh));
    const auto planes = graybody_planes(m, w, hh, 800, 2400);
    const auto out = run(planes, w, hh);
    EXPECT_EQ(out, library_codes(model, c.library_method, planes, w, hh));
    EXPECT_GT(count_nonzero(out), 12u);
    TearDown();
  }
}

TEST_F(RatioTemp, uncertainty_output_gives_the_library_uncertainty) {
  start("ratiotemp output=uncertainty model=" + rgb_model_path(), bands_caps(3, "bayer", 5, 4));
  auto planes = graybody_planes(*rgb_model(), 5, 4, 900, 1500);
  for (int b = 0; b < 3; ++b) planes[b * 20 + 3] = kInf;  // pixel 3 saturated: no reading
  const auto out = run(planes, 5, 4);
  const LibraryResult lib = library(rgb_model(), rgb_auto_method(), planes, 5, 4, true);
  EXPECT_EQ(out, codes_of(encode_decikelvin_difference(lib.u)));
  EXPECT_EQ(out[3], 0);
  // The uncertainty is there exactly where the temperature is, in 0.1 K without the 273.15 K
  // offset of temperatures.
  const auto t = codes_of(encode_decikelvin(lib.t));
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_EQ(out[i] != 0, t[i] != 0) << i;
    if (out[i]) {
      EXPECT_NEAR(out[i] / 10.0, lib.u.at<float>(static_cast<int>(i)), 0.0501) << i;
    }
  }
  // The statistics stay those of the temperatures.
  auto s = stats();
  ASSERT_EQ(s.size(), 1u);
  double median = NAN;
  EXPECT_TRUE(gst_structure_get_double(s[0], "median-c", &median));
  EXPECT_DOUBLE_EQ(median, region_stats(lib.t).median_c);
  free_all(s);
}

TEST_F(RatioTemp, saturated_nan_and_dim_bands_give_no_reading) {
  start("ratiotemp method=mlp model=" + rgb_model_path(), bands_caps(3, "bayer", 4, 2));
  auto planes = graybody_planes(*rgb_model(), 4, 2, 1200, 1200);
  const int n = 8;
  const float nan = std::nanf("");
  planes[0 * n + 0] = kInf;                             // R saturated
  planes[1 * n + 1] = nan;                              // G without a reading
  planes[2 * n + 2] = 5;                                // B below the 20 DN dim threshold
  for (int b = 0; b < 3; ++b) planes[b * n + 3] = nan;  // nothing at all
  planes[0 * n + 4] = kInf, planes[2 * n + 4] = 5;      // only G left
  // The network needs every band.
  const auto out = run(planes, 4, 2);
  ASSERT_EQ(out.size(), 8u);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(out[i], 0) << i;
  for (int i = 5; i < 8; ++i) {
    // The untouched pixels read about 1200 degC (the wobble moves them a little).
    EXPECT_NEAR(out[i] / 10.0 - 273.15, 1200, 60) << i;
  }
  // likelihood is held to every band too, unless allow-partial.
  gst_util_set_object_arg(G_OBJECT(element), "method", "likelihood");
  const auto lik = run(planes, 4, 2);
  EXPECT_EQ(lik, library_codes(rgb_model(), Method::kLikelihood, planes, 4, 2));
  for (int i = 0; i < 5; ++i) EXPECT_EQ(lik[i], 0) << i;
  EXPECT_EQ(count_nonzero(lik), 3u);
  // With allow-partial it drops a saturated, missing or dim band and fits the rest, as the
  // library does; with fewer than two bands left there is no reading.
  g_object_set(element, "allow-partial", TRUE, nullptr);
  const auto partial = run(planes, 4, 2);
  EXPECT_EQ(partial, library_codes(rgb_model(), Method::kLikelihood, planes, 4, 2, true));
  EXPECT_EQ(partial[3], 0);
  EXPECT_EQ(partial[4], 0);
  for (int i = 5; i < 8; ++i) EXPECT_EQ(partial[i], lik[i]) << i;
}

// misfit-probability: off by default; on, a pixel whose bands fit no graybody (green covered only
// in part, as at an edge) has no reading, while the graybody pixels keep theirs, for every
// method and for the statistics path as for the codes path.
TEST_F(RatioTemp, mixed_pixel_has_no_reading_with_the_misfit_check) {
  const ThermalModel& m = *rgb_model();
  const Eigen::VectorXd rates = m.camera.rates(1000);
  const Eigen::VectorXd s = rates * (200 / rates.maxCoeff());
  std::vector<float> planes(3 * 4);
  for (int i = 0; i < 4; ++i)
    for (int b = 0; b < 3; ++b)
      planes[static_cast<std::size_t>(b * 4 + i)] = static_cast<float>(s[b]);
  planes[1 * 4 + 0] *= 0.3f;  // pixel 0: green from the cold side in part
  for (const char* method : {"mlp", "likelihood"}) {
    SCOPED_TRACE(method);
    start(std::string("ratiotemp stats-interval=0 method=") + method + " model=" + rgb_model_path(),
          bands_caps(3, "bayer", 4, 1));
    double probability = -1;
    g_object_get(element, "misfit-probability", &probability, nullptr);
    EXPECT_EQ(probability, 0.0);
    const auto off = run(planes, 4, 1);
    ASSERT_EQ(off.size(), 4u);
    EXPECT_NE(off[0], 0);  // read, and far off: the estimators have no way to tell
    g_object_set(element, "misfit-probability", 1e-6, nullptr);
    const auto on = run(planes, 4, 1);
    ASSERT_EQ(on.size(), 4u);
    EXPECT_EQ(on[0], 0);
    for (int i = 1; i < 4; ++i) {
      EXPECT_EQ(on[i], off[i]) << i;
      EXPECT_NEAR(on[i] / 10.0 - 273.15, 1000, 30) << i;
    }
    // The float path (statistics due) drops it too.
    g_object_set(element, "stats-interval", G_GUINT64_CONSTANT(1), nullptr);
    EXPECT_EQ(run(planes, 4, 1), on);
    TearDown();
  }
}

// e-slope: a surface whose emissivity falls 30 %/100 nm reads far off as grey, and at its true
// temperature with e-slope=-30 set while playing; values outside -50..50 and NaN never get in.
TEST_F(RatioTemp, e_slope_reads_a_tilted_surface_at_its_temperature) {
  const ThermalModel& m = *nir_model();
  const CameraModel tilted{m.profile(),
                           with_emissivity_slope(m.profile(), m.camera.system_qe, -0.3),
                           m.camera.band_scale};
  const std::vector<double> truth = {1000, 1300, 1600, 2000};
  const int n = static_cast<int>(truth.size()), bands = m.profile().band_count();
  std::vector<float> planes(static_cast<std::size_t>(bands * n));
  for (int i = 0; i < n; ++i) {
    const Eigen::VectorXd r = tilted.rates(truth[static_cast<std::size_t>(i)]);
    for (int b = 0; b < bands; ++b)
      planes[static_cast<std::size_t>(b * n + i)] = static_cast<float>(r[b] * 100 / r.minCoeff());
  }
  start("ratiotemp method=likelihood model=" + nir_model_path(), bands_caps(bands, "5x5", n, 1));
  double slope = NAN;
  g_object_get(element, "e-slope", &slope, nullptr);
  EXPECT_EQ(slope, 0.0);
  const auto grey = run(planes, n, 1);
  g_object_set(element, "e-slope", -30.0, nullptr);
  const auto corrected = run(planes, n, 1);
  ASSERT_EQ(grey.size(), truth.size());
  ASSERT_EQ(corrected.size(), truth.size());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    EXPECT_TRUE(grey[i] == 0 || std::abs(grey[i] / 10.0 - 273.15 - truth[i]) > 20) << truth[i];
    EXPECT_NEAR(corrected[i] / 10.0 - 273.15, truth[i], 0.1) << truth[i];
  }
  // The property's range: GLib refuses what is outside it (and NaN), the value stays.
  GParamSpec* spec = g_object_class_find_property(G_OBJECT_GET_CLASS(element), "e-slope");
  ASSERT_TRUE(spec && G_IS_PARAM_SPEC_DOUBLE(spec));
  EXPECT_EQ(G_PARAM_SPEC_DOUBLE(spec)->minimum, -50.0);
  EXPECT_EQ(G_PARAM_SPEC_DOUBLE(spec)->maximum, 50.0);
  EXPECT_EQ(G_PARAM_SPEC_DOUBLE(spec)->default_value, 0.0);
  for (double bad : {60.0, -50.5, static_cast<double>(NAN)}) {
    g_object_set(element, "e-slope", bad, nullptr);  // GLib warns on stderr
    g_object_get(element, "e-slope", &slope, nullptr);
    EXPECT_EQ(slope, -30.0) << bad;
  }
  // The uncertainty of the slope: the model's by default (negative).
  double u = 0;
  g_object_get(element, "e-slope-uncertainty", &u, nullptr);
  EXPECT_LT(u, 0);
  EXPECT_EQ(run(planes, n, 1), corrected);
  // Back to grey while playing: the readings of the start.
  g_object_set(element, "e-slope", 0.0, nullptr);
  EXPECT_EQ(run(planes, n, 1), grey);
}

// A raw 8x8 RGGB frame of a graybody at t_c whose brightest band is 120 DN above the dark
// level of 50, with a dim corner.
std::vector<std::uint8_t> raw_bayer_frame(const ThermalModel& m, double t_c) {
  const Eigen::VectorXd rates = m.camera.rates(t_c);
  const Eigen::VectorXd dn = rates * (120 / rates.maxCoeff());
  std::vector<std::uint8_t> raw(64);
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x < 8; ++x) {
      const int band = (y % 2 == 0 && x % 2 == 0) ? 0 : (y % 2 == 1 && x % 2 == 1) ? 2 : 1;
      raw[y * 8 + x] = static_cast<std::uint8_t>(std::lround(50 + dn[band]));
    }
  for (int y = 0; y < 2; ++y)
    for (int x = 6; x < 8; ++x) raw[y * 8 + x] = 55;  // 5 DN above dark: too dim
  return raw;
}

// The library's chain on a raw frame: dark level 50, default saturation, bilinear, estimator.
std::vector<std::uint16_t> library_chain(const std::vector<std::uint8_t>& raw, Method method,
                                         DemosaicMethod demosaic_method = DemosaicMethod::kBilinear,
                                         float no_signal_dn = 0) {
  cv::Mat signal;
  subtract_dark_level(cv::Mat(8, 8, CV_8U, const_cast<std::uint8_t*>(raw.data())), 50,
                      default_saturation_level(8), signal);
  std::vector<cv::Mat> planes;
  demosaic(signal, MosaicLayout::bayer("RGGB"), demosaic_method, planes, no_signal_dn);
  return codes_of(encode_decikelvin(library(rgb_model(), method, planes).t));
}

TEST_F(RatioTemp, saturated_pixel_stays_no_reading_through_darksub_and_demosaic25) {
  for (const char* e : {"darksub", "demosaic25"}) REQUIRE_ELEMENT(e);
  start_on_raw_frames("ratiotemp method=mlp model=" + rgb_model_path());
  auto raw = raw_bayer_frame(*rgb_model(), 1300);
  raw[4 * 8 + 4] = 255;  // an R pixel, saturated
  const auto out = run(raw, 8, 8);
  ASSERT_EQ(out.size(), 64u);
  EXPECT_EQ(out, library_chain(raw, Method::kMlp));
  // The saturated R pixel and the pixels whose R is interpolated from it have no reading.
  for (int y = 3; y <= 5; ++y)
    for (int x = 3; x <= 5; ++x) EXPECT_EQ(out[y * 8 + x], 0) << x << "," << y;
  EXPECT_EQ(out[1 * 8 + 7], 0);  // dim corner
  EXPECT_NEAR(out[6 * 8 + 1] / 10.0 - 273.15, 1300, 60);
  EXPECT_GT(count_nonzero(out), 40u);
}

// demosaic25's default for Bayer (matched) draws each band from a 5x5 footprint: the saturated
// pixel takes every reading within two pixels of it.
TEST_F(RatioTemp, saturated_pixel_takes_the_matched_footprint_with_the_default_demosaic) {
  for (const char* e : {"darksub", "demosaic25"}) REQUIRE_ELEMENT(e);
  start_on_raw_frames("ratiotemp method=mlp model=" + rgb_model_path(), "demosaic25");
  auto raw = raw_bayer_frame(*rgb_model(), 1300);
  raw[4 * 8 + 4] = 255;  // an R pixel, saturated
  const auto out = run(raw, 8, 8);
  ASSERT_EQ(out.size(), 64u);
  const CameraProfile colour = load_profile_by_name("rgb-reference");
  std::vector<SignalNoise> noise;
  for (int b = 0; b < colour.band_count(); ++b) noise.push_back(signal_noise(colour, b));
  EXPECT_EQ(out, library_chain(raw, Method::kMlp, DemosaicMethod::kMatched,
                               static_cast<float>(no_signal_level_dn(noise))));
  int read_near = 0;
  for (int y = 2; y <= 6; ++y)
    for (int x = 2; x <= 6; ++x) read_near += out[y * 8 + x] != 0;
  EXPECT_LT(read_near, 25 - 9);  // more than bilinear's 3x3 lost
  EXPECT_EQ(out[4 * 8 + 4], 0);
  EXPECT_GT(count_nonzero(out), 0u);
}

TEST_F(RatioTemp, saturated_area_has_no_reading_with_the_default_method) {
  for (const char* e : {"darksub", "demosaic25"}) REQUIRE_ELEMENT(e);
  start_on_raw_frames("ratiotemp model=" + rgb_model_path());
  auto raw = raw_bayer_frame(*rgb_model(), 1300);
  for (int y = 2; y < 6; ++y)
    for (int x = 2; x < 6; ++x) raw[y * 8 + x] = 255;
  const auto out = run(raw, 8, 8);
  ASSERT_EQ(out.size(), 64u);
  EXPECT_EQ(out, library_chain(raw, rgb_auto_method()));
  // Every band of the central 2x2 comes from saturated pixels only.
  for (int y = 3; y <= 4; ++y)
    for (int x = 3; x <= 4; ++x) EXPECT_EQ(out[y * 8 + x], 0) << x << "," << y;
  EXPECT_EQ(out[1 * 8 + 7], 0);  // dim corner
  EXPECT_NEAR(out[7 * 8 + 0] / 10.0 - 273.15, 1300, 60);
}

TEST_F(RatioTemp, method_and_region_change_while_playing) {
  start("ratiotemp method=likelihood stats-interval=0 model=" + rgb_model_path(),
        bands_caps(3, "bayer", 6, 4));
  const auto planes = graybody_planes(*rgb_model(), 6, 4, 900, 1800);
  EXPECT_EQ(run(planes, 6, 4), library_codes(rgb_model(), Method::kLikelihood, planes, 6, 4));
  gst_util_set_object_arg(G_OBJECT(element), "method", "mlp");
  const auto mlp = library_codes(rgb_model(), Method::kMlp, planes, 6, 4);
  EXPECT_EQ(run(planes, 6, 4), mlp);
  gst_util_set_object_arg(G_OBJECT(element), "method", "lut");
  const bool lut = rgb_auto_method() == Method::kLut;
  // The table where it passed its check; else refused with a warning, and the network stays.
  EXPECT_EQ(run(planes, 6, 4), lut ? library_codes(rgb_model(), Method::kLut, planes, 6, 4) : mlp);
  gst_util_set_object_arg(G_OBJECT(element), "method", "mlp");
  EXPECT_EQ(run(planes, 6, 4), mlp);
  auto s = stats();
  EXPECT_TRUE(s.empty());  // stats-interval=0: none
  // Statistics and a region switched on while playing.
  g_object_set(element, "stats-interval", GST_SECOND, "region", "1,1,2,2", nullptr);
  run(planes, 6, 4, 0);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  const char* method = gst_structure_get_string(s[0], "method");
  EXPECT_STREQ(method, "mlp");
  int rw = 0;
  EXPECT_TRUE(gst_structure_get_int(s[0], "region-width", &rw));
  EXPECT_EQ(rw, 2);
  free_all(s);
  g_object_set(element, "region", "2,0,3,1", nullptr);
  run(planes, 6, 4, 2 * GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  guint64 pixels = 0;
  EXPECT_TRUE(gst_structure_get_uint64(s[0], "region-pixels", &pixels));
  EXPECT_EQ(pixels, 3u);
  free_all(s);
  // An invalid region while playing: a warning, no region fields, frames still flow.
  g_object_set(element, "region", "2,0,x", nullptr);
  EXPECT_EQ(count_nonzero(run(planes, 6, 4, 4 * GST_SECOND)), count_nonzero(run(planes, 6, 4)));
  s = stats();
  ASSERT_FALSE(s.empty());
  EXPECT_FALSE(gst_structure_has_field(s[0], "region-pixels"));
  free_all(s);
  ASSERT_EQ(warnings.size(), lut ? 1u : 2u);
  if (!lut) {
    EXPECT_NE(warnings[0].find("lookup table differs"), std::string::npos) << warnings[0];
  }
  EXPECT_NE(warnings.back().find("2,0,x"), std::string::npos) << warnings.back();
}

TEST_F(RatioTemp, auto_uses_the_lookup_table_only_when_it_passes_its_check) {
  start("ratiotemp stats-interval=1 model=" + rgb_model_path(), bands_caps(3, "bayer", 3, 2));
  const auto planes = graybody_planes(*rgb_model(), 3, 2, 1100, 1300);
  EXPECT_EQ(run(planes, 3, 2, 0), library_codes(rgb_model(), rgb_auto_method(), planes, 3, 2));
  auto s = stats();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_EQ(gst_structure_get_string(s[0], "method"), method_name(rgb_auto_method()));
  free_all(s);
  if (rgb_auto_method() == Method::kLut) {
    EXPECT_TRUE(warnings.empty());
  } else {
    // The user is told why, with the size of the table's error.
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("uses likelihood, not lut"), std::string::npos) << warnings[0];
    EXPECT_NE(warnings[0].find("differs from its network by up to"), std::string::npos)
        << warnings[0];
  }
}

TEST_F(RatioTemp, lut_asked_for_while_playing_with_the_5x5_model_is_refused_n) {
  start("ratiotemp model=" + nir_model_path(), bands_caps(25, "5x5", 3, 2));
  const auto planes = graybody_planes(*nir_model(), 3, 2, 1200, 1800);
  const auto expected = library_codes(nir_model(), Method::kLikelihood, planes, 3, 2);
  EXPECT_EQ(run(planes, 3, 2), expected);
  gst_util_set_object_arg(G_OBJECT(element), "method", "lut");
  EXPECT_EQ(run(planes, 3, 2), expected);  // still likelihood
  EXPECT_EQ(run(planes, 3, 2), expected);
  auto s = stats();
  free_all(s);
  ASSERT_EQ(warnings.size(), 1u);  // once, not per frame
  EXPECT_NE(warnings[0].find("lut"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("likelihood"), std::string::npos) << warnings[0];
}

guint64 field_uint64(const GstStructure* s, const char* name) {
  guint64 v = 0;
  EXPECT_TRUE(gst_structure_get_uint64(s, name, &v)) << name;
  return v;
}

void expect_stats(const GstStructure* s, const std::string& prefix, const RegionStats& r) {
  SCOPED_TRACE(prefix);
  EXPECT_EQ(field_uint64(s, (prefix + "pixels").c_str()), r.pixels);
  EXPECT_EQ(field_uint64(s, (prefix + "valid").c_str()), r.valid);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "valid-fraction").c_str()), r.valid_fraction);
  if (r.valid == 0) {
    EXPECT_FALSE(gst_structure_has_field(s, (prefix + "median-c").c_str()));
    return;
  }
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "min-c").c_str()), r.min_c);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "max-c").c_str()), r.max_c);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "mean-c").c_str()), r.mean_c);
  EXPECT_DOUBLE_EQ(field_double(s, (prefix + "median-c").c_str()), r.median_c);
}

TEST_F(RatioTemp, stats_message_matches_region_stats_of_the_frame) {
  start("ratiotemp stats-interval=1000000000 region=4,2,10,10 model=" + rgb_model_path(),
        bands_caps(3, "bayer", 7, 5));
  auto planes = graybody_planes(*rgb_model(), 7, 5, 900, 1700);
  for (int b = 0; b < 3; ++b) {  // two pixels without a reading, whatever the method
    planes[b * 35 + 0] = kInf;
    planes[b * 35 + 33] = NAN;
  }
  std::vector<float> dark(planes.size(), 1.0f);  // every band dim: no reading anywhere
  // Frames at 0, 0.5, 1.0 and 1.2 s: the first and the third post.
  run(planes, 7, 5, 0);
  run(planes, 7, 5, GST_SECOND / 2);
  run(planes, 7, 5, GST_SECOND);
  run(dark, 7, 5, GST_SECOND + GST_SECOND / 5);
  auto s = stats();
  ASSERT_EQ(s.size(), 2u);
  const cv::Mat t = library(rgb_model(), rgb_auto_method(), planes, 7, 5).t;
  const cv::Rect region(4, 2, 3, 3);  // clipped to the 7x5 frame
  for (std::size_t k = 0; k < 2; ++k) {
    const GstStructure* m = s[k];
    EXPECT_EQ(field_uint64(m, "timestamp"), k * GST_SECOND);
    EXPECT_EQ(field_uint64(m, "running-time"), k * GST_SECOND);
    EXPECT_EQ(field_uint64(m, "stream-time"), k * GST_SECOND);
    EXPECT_EQ(gst_structure_get_string(m, "method"), method_name(rgb_auto_method()));
    int v = 0;
    EXPECT_TRUE(gst_structure_get_int(m, "width", &v) && v == 7);
    EXPECT_TRUE(gst_structure_get_int(m, "height", &v) && v == 5);
    EXPECT_TRUE(gst_structure_get_int(m, "region-x", &v) && v == 4);
    EXPECT_TRUE(gst_structure_get_int(m, "region-y", &v) && v == 2);
    EXPECT_TRUE(gst_structure_get_int(m, "region-width", &v) && v == 3);
    EXPECT_TRUE(gst_structure_get_int(m, "region-height", &v) && v == 3);
    const RegionStats frame = region_stats(t);
    EXPECT_EQ(frame.valid, 33u);
    expect_stats(m, "", frame);
    const RegionStats reg = region_stats(t(region));
    EXPECT_EQ(reg.pixels, 9u);
    EXPECT_EQ(reg.valid, 8u);
    expect_stats(m, "region-", reg);
    // The median is reported apart from the mean.
    EXPECT_NE(field_double(m, "median-c"), field_double(m, "mean-c"));
  }
  free_all(s);
  // A frame without any reading: counts, fraction 0, no temperatures.
  g_object_set(element, "stats-interval", G_GUINT64_CONSTANT(1), nullptr);
  run(dark, 7, 5, 3 * GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  expect_stats(s[0], "", region_stats(cv::Mat(5, 7, CV_32F, cv::Scalar(NAN))));
  EXPECT_EQ(field_uint64(s[0], "pixels"), 35u);
  EXPECT_FALSE(gst_structure_has_field(s[0], "min-c"));
  free_all(s);
}

TEST_F(RatioTemp, survives_flush_and_eos) {
  start("ratiotemp model=" + rgb_model_path(), bands_caps(3, "bayer", 4, 4));
  const auto planes = graybody_planes(*rgb_model(), 4, 4, 1000, 1400);
  const auto expected = library_codes(rgb_model(), rgb_auto_method(), planes, 4, 4);
  EXPECT_EQ(run(planes, 4, 4, 0), expected);
  EXPECT_EQ(run(planes, 4, 4, GST_SECOND / 10), expected);
  auto s = stats();
  EXPECT_EQ(s.size(), 1u);  // the second frame is within the 1 s default interval
  free_all(s);
  push_flush(h);
  EXPECT_EQ(run(planes, 4, 4, GST_SECOND / 5), expected);
  s = stats();
  EXPECT_EQ(s.size(), 1u);  // after a flush the next frame posts
  free_all(s);
  EXPECT_TRUE(eos_passes(h));
  // And it starts again after a state change.
  ASSERT_EQ(gst_element_set_state(h->element, GST_STATE_READY), GST_STATE_CHANGE_SUCCESS);
  ASSERT_EQ(gst_element_set_state(h->element, GST_STATE_PLAYING), GST_STATE_CHANGE_SUCCESS);
}

TEST(RatioTempLut, rejects_a_lookup_table_that_disagrees_with_the_network_n) {
  REQUIRE_ELEMENT("ratiotemp");
  if (rgb_auto_method() == Method::kLut)
    GTEST_SKIP() << "the test model's lookup table passes its check";
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=1 ! video/x-bayer,width=20,height=10 ! darksub dark-level=50 ! "
      "demosaic25 ! ratiotemp method=lut model=" +
      rgb_model_path() + " ! fakesink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS,
               {"lookup table differs from its network by up to"});
}

// A plate at 1000 degC with a 7x7 hot spot at 1400 centred on (12, 7) and one wild pixel at
// 1750 (a mixed pixel at an edge), as band planes of the colour model.
std::vector<float> plate_with_spot_and_outlier(int w, int h) {
  const ThermalModel& m = *rgb_model();
  const auto plate = graybody_planes(m, w, h, 1000, 1000),
             spot = graybody_planes(m, w, h, 1400, 1400),
             wild = graybody_planes(m, w, h, 1750, 1750);
  std::vector<float> v = plate;
  const int n = w * h;
  for (int b = 0; b < m.profile().band_count(); ++b)
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t i = static_cast<std::size_t>(b * n + y * w + x);
        if (std::abs(x - 12) <= 3 && std::abs(y - 7) <= 3) v[i] = spot[i];
        if (x == 3 && y == 12) v[i] = wild[i];
      }
  return v;
}

TEST_F(RatioTemp, stats_peak_is_the_hot_spot_not_a_wild_pixel) {
  const int w = 24, h = 16;
  start("ratiotemp stats-interval=1 region=8,2,12,12 model=" + rgb_model_path(),
        bands_caps(3, "bayer", w, h));
  guint window = 0;
  g_object_get(element, "peak-window", &window, nullptr);
  EXPECT_EQ(window, 5u);
  const auto planes = plate_with_spot_and_outlier(w, h);
  run(planes, w, h, 0);
  auto s = stats();
  ASSERT_EQ(s.size(), 1u);
  const cv::Mat t = library(rgb_model(), rgb_auto_method(), planes, w, h).t;
  EXPECT_NEAR(field_double(s[0], "max-c"), 1750, 30);  // the wild pixel
  const RegionPeak want = region_peak(t, 5);
  EXPECT_DOUBLE_EQ(field_double(s[0], "peak-c"), want.c);
  EXPECT_NEAR(field_double(s[0], "peak-c"), 1400, 30);
  int x = -1, y = -1;
  EXPECT_TRUE(gst_structure_get_int(s[0], "peak-x", &x));
  EXPECT_TRUE(gst_structure_get_int(s[0], "peak-y", &y));
  EXPECT_LE(std::abs(x - 12), 1);
  EXPECT_LE(std::abs(y - 7), 1);
  // The region's peak: windows inside it, the position in frame pixels.
  const RegionPeak in_region = region_peak(t(cv::Rect(8, 2, 12, 12)), 5);
  EXPECT_DOUBLE_EQ(field_double(s[0], "region-peak-c"), in_region.c);
  EXPECT_TRUE(gst_structure_get_int(s[0], "region-peak-x", &x));
  EXPECT_TRUE(gst_structure_get_int(s[0], "region-peak-y", &y));
  EXPECT_EQ(x, in_region.x + 8);
  EXPECT_EQ(y, in_region.y + 2);
  free_all(s);
  // peak-window 0: no peak; even values are refused.
  g_object_set(element, "peak-window", 4u, nullptr);
  g_object_get(element, "peak-window", &window, nullptr);
  EXPECT_EQ(window, 5u);
  g_object_set(element, "peak-window", 0u, nullptr);
  run(planes, w, h, GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_FALSE(gst_structure_has_field(s[0], "peak-c"));
  EXPECT_FALSE(gst_structure_has_field(s[0], "region-peak-c"));
  EXPECT_TRUE(gst_structure_has_field(s[0], "max-c"));
  free_all(s);
  EXPECT_TRUE(warnings.empty());
}

// region-tracks-peak: the region (its size from region) is centred on the frame's peak, moved
// to stay in the frame, so its statistics are the hot spot's; off, it stays where region says.
TEST_F(RatioTemp, region_tracks_the_peak) {
  const int w = 24, h = 16;
  start(
      "ratiotemp stats-interval=1 region=0,0,5,5 region-tracks-peak=true model=" + rgb_model_path(),
      bands_caps(3, "bayer", w, h));
  const auto planes = plate_with_spot_and_outlier(w, h);  // the 7x7 spot centred at (12, 7)
  run(planes, w, h, 0);
  auto s = stats();
  ASSERT_EQ(s.size(), 1u);
  int px = -1, py = -1, rx = -1, ry = -1, rw = 0, rh = 0;
  gboolean tracking = FALSE;
  ASSERT_TRUE(gst_structure_get_int(s[0], "peak-x", &px));
  ASSERT_TRUE(gst_structure_get_int(s[0], "peak-y", &py));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-x", &rx));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-y", &ry));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-width", &rw));
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-height", &rh));
  ASSERT_TRUE(gst_structure_get_boolean(s[0], "region-tracks-peak", &tracking));
  EXPECT_TRUE(tracking);
  EXPECT_EQ(rw, 5);
  EXPECT_EQ(rh, 5);
  EXPECT_EQ(rx, px - 2);
  EXPECT_EQ(ry, py - 2);
  // The region lies in the spot: its median is the spot's, 1400 degC, not the plate's.
  EXPECT_NEAR(field_double(s[0], "region-median-c"), 1400, 30);
  free_all(s);
  g_object_set(element, "region-tracks-peak", FALSE, nullptr);
  run(planes, w, h, GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  ASSERT_TRUE(gst_structure_get_int(s[0], "region-x", &rx));
  ASSERT_TRUE(gst_structure_get_boolean(s[0], "region-tracks-peak", &tracking));
  EXPECT_EQ(rx, 0);
  EXPECT_FALSE(tracking);
  EXPECT_NEAR(field_double(s[0], "region-median-c"), 1000, 30);
  free_all(s);
  EXPECT_TRUE(warnings.empty());
}

TEST_F(RatioTemp, peak_window_larger_than_the_frame_warns_once_and_gives_no_peak) {
  const int w = 24, h = 16;
  start("ratiotemp name=rt0 stats-interval=1 peak-window=17 model=" + rgb_model_path(),
        bands_caps(3, "bayer", w, h));
  const auto planes = plate_with_spot_and_outlier(w, h);
  run(planes, w, h, 0);
  run(planes, w, h, GST_SECOND);
  auto s = stats();
  ASSERT_EQ(s.size(), 2u);
  for (const GstStructure* m : s) {
    EXPECT_FALSE(gst_structure_has_field(m, "peak-c"));
    EXPECT_TRUE(gst_structure_has_field(m, "median-c"));
  }
  free_all(s);
  ASSERT_EQ(warnings.size(), 1u);  // once, not per message
  EXPECT_NE(warnings[0].find("rt0"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("peak-window 17"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[0].find("24x16"), std::string::npos) << warnings[0];
  // A window that fits again: the peak is back.
  g_object_set(element, "peak-window", 15u, nullptr);
  run(planes, w, h, 2 * GST_SECOND);
  s = stats();
  ASSERT_EQ(s.size(), 1u);
  EXPECT_TRUE(gst_structure_has_field(s[0], "peak-c"));
  free_all(s);
}

}  // namespace
}  // namespace pyrocam::test
