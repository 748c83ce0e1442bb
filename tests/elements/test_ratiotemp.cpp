// ratiotemp: caps for colour and 5x5 bands, codes against the library for every method and
// for the uncertainty, no-reading marks through the chain, live method/region changes, flush/EOS
// (test_ratiotemp_stats.cpp: the statistics message and the peak; test_ratiotemp_errors.cpp:
// whole pipelines and the bus errors for bad models and caps).
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/emissivity.h"
#include "pyrocam/runtime/region_stats.h"
#include "ratiotemp_support.h"

namespace pyrocam::test {
namespace {

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
  // Frames of uncertainties carry no table of them (temperature frames do: ratiotemp_stats).
  EXPECT_TRUE(last_u_expanded_c.empty());
}

// Planes that say how demosaic25 made them (demosaic, pattern): each band value's noise is its
// kernel's, as the library takes it from demosaic_noise, and smaller than one sample's.
TEST_F(RatioTemp, the_uncertainty_follows_the_demosaicking_the_caps_name) {
  start("ratiotemp output=uncertainty model=" + rgb_model_path(),
        bands_caps(3, "bayer", 6, 4) + ",demosaic=matched,pattern=grbg");
  const auto planes = graybody_planes(*rgb_model(), 6, 4, 900, 1500);
  const auto out = run(planes, 6, 4);
  PlaneEstimator est(rgb_model(), rgb_auto_method());
  est.set_demosaic_noise(demosaic_noise(MosaicLayout::bayer("grbg"), DemosaicMethod::kMatched));
  cv::Mat t, u;
  est.estimate(plane_views(planes, 3, 6, 4), t, &u);
  EXPECT_EQ(out, codes_of(encode_decikelvin_difference(u)));
  const LibraryResult one_sample = library(rgb_model(), rgb_auto_method(), planes, 6, 4, true);
  int read = 0;
  for (std::size_t i = 0; i < out.size(); ++i)
    if (out[i]) {
      ++read;
      EXPECT_LT(u.at<float>(static_cast<int>(i)), one_sample.u.at<float>(static_cast<int>(i))) << i;
    }
  EXPECT_GT(read, 12);
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

// The saturation-edge check (saturation_edge.h) judges a band near darksub's saturation level,
// the one the caps name: on a plate exposed so that red sits 140 DN above the dark level, with
// samples marked saturated from 192 DN raw (red about a standard deviation of its noise below
// that), the pixels whose red samples all stayed below it would read, and low; the plate reads
// on almost none instead. With the model's 220 DN the same frames read.
TEST(RatioTempSaturationEdge, a_band_near_the_caps_saturation_level_reads_on_none) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
  const auto readings = [](int level) {
    const auto frames = sink_frames(
        "pyrocamsrc num-buffers=2 scene=plate temperature=1300 ! "
        "video/x-bayer,width=160,height=120 ! darksub dark-level=50 saturation-level=" +
        std::to_string(level) + " ! demosaic25 ! ratiotemp model=" +
        test_model_path("test-model-rgb.json") + " ! fakesink name=sink");
    EXPECT_EQ(frames.size(), 2u);
    std::size_t read = 0;
    for (const auto& f : frames)
      for (std::size_t k = 0; k + 1 < f.size(); k += 2) read += f[k] || f[k + 1];
    return read;
  };
  const std::size_t at_model_level = readings(220), near_level = readings(192);
  EXPECT_GT(at_model_level, 2 * 160 * 120 / 5u);  // the plate: a third of the frame
  EXPECT_LT(near_level, at_model_level / 50) << "read where red's noise kept it below the level";
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

}  // namespace
}  // namespace pyrocam::test
