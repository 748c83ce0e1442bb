// demosaic25: caps in both directions, planes against the library, marks through darksub and
// demosaic25, 5x5 macro-pixels, profile band map, flush/EOS, bus errors.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <numeric>

#include "element_support.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/mixed_pixels.h"

namespace pyrocam::test {
namespace {

class Demosaic25 : public HarnessTest {
 protected:
  Demosaic25() : HarnessTest("demosaic25") {}
  // Pushes one float mosaic and returns the output planes (empty on failure).
  std::vector<float> run(const std::vector<float>& mosaic) {
    return push_pull<float>(h, buffer_from(mosaic));
  }
  void expect_library_planes(const char* launch, const std::string& pattern, DemosaicMethod method);
};

std::vector<float> ramp(int w, int h) {
  std::vector<float> v(static_cast<std::size_t>(w * h));
  for (int i = 0; i < w * h; ++i) v[i] = static_cast<float>((i * 37) % 101);
  return v;
}

// The library's planes for a mosaic, concatenated.
std::vector<float> library(const std::vector<float>& mosaic, int w, int h,
                           const MosaicLayout& layout, DemosaicMethod method,
                           float no_signal_dn = -std::numeric_limits<float>::infinity()) {
  cv::Mat in(h, w, CV_32F, const_cast<float*>(mosaic.data()));
  std::vector<cv::Mat> planes;
  demosaic(in, layout, method, planes, no_signal_dn);
  std::vector<float> out;
  for (const cv::Mat& p : planes) out.insert(out.end(), p.begin<float>(), p.end<float>());
  return out;
}

std::string mosaic_caps(const char* pattern, int w, int h) {
  return "video/x-pyrocam-mosaic,format=F32LE,width=" + std::to_string(w) +
         ",height=" + std::to_string(h) + ",framerate=30/1,pattern=" + pattern + ",bit-depth=8";
}

void expect_same(const std::vector<float>& a, const std::vector<float>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::isnan(b[i])) {
      EXPECT_TRUE(std::isnan(a[i])) << i;
    } else {
      EXPECT_EQ(a[i], b[i]) << i;
    }
  }
}

// Starts a demosaic25 (its launch words) on an 8x6 Bayer mosaic of `pattern` (lower case, as in
// caps) and checks its planes of a ramp against the library's for `method`.
void Demosaic25::expect_library_planes(const char* launch, const std::string& pattern,
                                       DemosaicMethod method) {
  start(launch, mosaic_caps(pattern.c_str(), 8, 6));
  std::string upper = pattern;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const auto mosaic = ramp(8, 6);
  expect_same(run(mosaic), library(mosaic, 8, 6, MosaicLayout::bayer(upper), method));
}

TEST_F(Demosaic25, bilinear_keeps_full_resolution) {
  expect_library_planes("demosaic25 method=bilinear", "gbrg", DemosaicMethod::kBilinear);
  const std::string caps = sink_caps(h);
  for (const char* part : {"video/x-pyrocam-bands", "bands=(int)3", "width=(int)8", "height=(int)6",
                           "layout=(string)bayer", "format=(string)F32LE"})
    EXPECT_NE(caps.find(part), std::string::npos) << part << " in " << caps;
}

TEST_F(Demosaic25, mixed_pixels_at_a_sharp_edge_get_no_reading_and_the_rest_stays) {
  // An 8x6 RGGB mosaic: columns 0-3 a hot object (100..110 DN, a gentle gradient), columns 4-7
  // the cold background (2 DN).
  std::vector<float> mosaic(8 * 6);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 8; ++x) mosaic[y * 8 + x] = x < 4 ? 100.f + 3.f * x : 2.f;
  start("demosaic25 method=bilinear mixed-pixels=0.2", mosaic_caps("rggb", 8, 6));
  const auto checked = run(mosaic);
  const auto plain = library(mosaic, 8, 6, MosaicLayout::bayer("RGGB"), DemosaicMethod::kBilinear);
  ASSERT_EQ(checked.size(), plain.size());
  for (int b = 0; b < 3; ++b)
    for (int y = 0; y < 6; ++y)
      for (int x = 0; x < 8; ++x) {
        const std::size_t i = static_cast<std::size_t>(b * 48 + y * 8 + x);
        // Columns 3 and 4 have footprints across the edge; the others are one level each.
        if (x == 3 || x == 4)
          EXPECT_TRUE(std::isnan(checked[i])) << b << " " << x << "," << y;
        else
          EXPECT_EQ(checked[i], plain[i]) << b << " " << x << "," << y;
      }
}

// Without a profile the check's noise is the shipped colour camera's, band by band (its green
// and blue samples are noisier than its red: 0.06 and 0.12 against 0.03 DN per electron), so
// that demosaic25 mixed-pixels=0.5 marks what pyrocam-calib measure --mixed-pixels 0.5 marks
// for a model of that camera. A hot spot whose samples differ band by band near the allowance.
TEST_F(Demosaic25, mixed_pixel_check_without_a_profile_uses_the_colour_cameras_noise) {
  constexpr int kW = 24, kH = 16;
  std::vector<float> mosaic(kW * kH);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double r2 = ((x - 11.3) * (x - 11.3) + (y - 7.6) * (y - 7.6)) / 16.0;
      mosaic[static_cast<std::size_t>(y * kW + x)] =
          static_cast<float>(5 + 180 * std::exp(-r2) + ((x * 7 + y * 3) % 5));
    }
  const CameraProfile profile = load_profile_by_name("rgb-reference");
  const auto marked = [&](const std::vector<SignalNoise>& noise) {
    FootprintCheck check;
    check.relative_spread = 0.5;
    check.noise = noise;
    cv::Mat in(kH, kW, CV_32F, mosaic.data());
    std::vector<cv::Mat> planes;
    demosaic_marking_mixed(in, profile.mosaic, DemosaicMethod::kBilinear, check, planes,
                           static_cast<float>(no_signal_level_dn(noise)));
    std::vector<float> out;
    for (const cv::Mat& p : planes) out.insert(out.end(), p.begin<float>(), p.end<float>());
    return out;
  };
  std::vector<SignalNoise> noise, red_everywhere;
  for (int b = 0; b < profile.band_count(); ++b) noise.push_back(signal_noise(profile, b));
  red_everywhere.assign(noise.size(), noise[0]);
  const auto expected = marked(noise);
  const auto nan_count = [](const std::vector<float>& v) {
    return std::count_if(v.begin(), v.end(), [](float f) { return std::isnan(f); });
  };
  // The scene tells the two noise models apart, and it has marks to compare.
  ASSERT_GT(nan_count(expected), 0);
  ASSERT_NE(nan_count(marked(red_everywhere)), nan_count(expected));
  start("demosaic25 method=bilinear mixed-pixels=0.5", mosaic_caps("rggb", kW, kH));
  expect_same(run(mosaic), expected);
}

TEST_F(Demosaic25, matched_gives_no_band_mixing_a_cold_background_into_a_lit_one) {
  // The edge of the test above: a lit object (100..109 DN) beside a background without light
  // (2 DN, under 5 noise-floor standard deviations at 8 bits). Each band value is either
  // measured light or dim (0); none lies between, where a ratio of two temperatures would.
  std::vector<float> mosaic(8 * 6);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 8; ++x) mosaic[y * 8 + x] = x < 4 ? 100.f + 3.f * x : 2.f;
  start("demosaic25 method=matched", mosaic_caps("rggb", 8, 6));
  const auto planes = run(mosaic);
  ASSERT_EQ(planes.size(), 3u * 48);
  int dim = 0;
  for (std::size_t i = 0; i < planes.size(); ++i) {
    const int x = static_cast<int>(i % 8);
    if (planes[i] == 0.f) {
      ++dim;
      EXPECT_GE(x, 2) << i;  // only kernels that reach the background
    } else {
      EXPECT_GE(planes[i], 100.f) << i;
      EXPECT_LE(x, 3) << i;
    }
  }
  // Dim: every band of columns 4-7; every kernel at column 3 reaches column 4 or 5; at column
  // 2 those with samples 2 columns right (2 of the 3 bands in each row).
  EXPECT_EQ(dim, 3 * 6 * 4 + 3 * 6 + 2 * 6);
  // A lit mosaic reads as the library's matched planes.
  std::vector<float> lit = ramp(8, 6);
  for (float& v : lit) v += 50.f;
  expect_same(run(lit), library(lit, 8, 6, MosaicLayout::bayer("RGGB"), DemosaicMethod::kMatched));
}

TEST_F(Demosaic25, matched_mixed_pixel_check_tests_each_kernel) {
  // An edge between two lit levels (100 and 40 DN): every pixel with a kernel across it
  // (columns 2-5, 5x5 kernels) gets no reading, the others keep the library's values.
  std::vector<float> mosaic(8 * 6);
  for (int y = 0; y < 6; ++y)
    for (int x = 0; x < 8; ++x) mosaic[y * 8 + x] = x < 4 ? 100.f : 40.f;
  start("demosaic25 method=matched mixed-pixels=0.2", mosaic_caps("rggb", 8, 6));
  const auto checked = run(mosaic);
  const auto plain = library(mosaic, 8, 6, MosaicLayout::bayer("RGGB"), DemosaicMethod::kMatched);
  ASSERT_EQ(checked.size(), plain.size());
  for (std::size_t i = 0; i < checked.size(); ++i) {
    const int x = static_cast<int>(i % 8);
    if (x >= 2 && x <= 5)
      EXPECT_TRUE(std::isnan(checked[i])) << i;
    else
      EXPECT_EQ(checked[i], plain[i]) << i;
  }
}

TEST_F(Demosaic25, bin2x2_halves_resolution) {
  expect_library_planes("demosaic25 method=bin2x2", "rggb", DemosaicMethod::kBinCells);
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("width=(int)4"), std::string::npos) << caps;
  EXPECT_NE(caps.find("height=(int)3"), std::string::npos) << caps;
}

TEST_F(Demosaic25, snapshot_gives_25_bands_per_macro_pixel) {
  start("demosaic25 profile=nir5x5-reference method=bin2x2", mosaic_caps("5x5", 10, 15));
  auto mosaic = ramp(10, 15);
  mosaic[3] = kInf;                    // band 3 of macro-pixel (0,0)
  mosaic[10 * 5 + 7] = std::nanf("");  // band 2 of macro-pixel (1,1)
  const auto out = run(mosaic);
  std::vector<int> identity(25);
  std::iota(identity.begin(), identity.end(), 0);
  expect_same(out, library(mosaic, 10, 15, MosaicLayout::snapshot(5, 5, identity),
                           DemosaicMethod::kBinCells));
  ASSERT_EQ(out.size(), 25u * 2 * 3);
  EXPECT_EQ(out[3 * 6 + 0], kInf);
  EXPECT_TRUE(std::isnan(out[2 * 6 + 1 * 2 + 1]));
  const std::string caps = sink_caps(h);
  for (const char* part : {"bands=(int)25", "width=(int)2", "height=(int)3", "layout=(string)5x5"})
    EXPECT_NE(caps.find(part), std::string::npos) << part << " in " << caps;
}

// The default (auto) is matched for Bayer too: the library's, with the shipped colour camera's
// level of samples without light at 8 bits (5.5 DN), so a sample below it makes a band dim.
TEST_F(Demosaic25, bayer_default_is_matched_at_full_resolution) {
  constexpr int kW = 12, kH = 10;
  auto mosaic = ramp(kW, kH);
  for (int x = 0; x < kW; ++x) mosaic[static_cast<std::size_t>(9 * kW + x)] = 3.f;  // no light
  start("demosaic25", mosaic_caps("bggr", kW, kH));
  const auto out = run(mosaic);
  const CameraProfile colour = load_profile_by_name("rgb-reference");
  std::vector<SignalNoise> noise;
  for (int b = 0; b < colour.band_count(); ++b) noise.push_back(signal_noise(colour, b));
  const float no_signal = static_cast<float>(no_signal_level_dn(noise));
  EXPECT_NEAR(no_signal, 5.5f, 0.1f);
  expect_same(out, library(mosaic, kW, kH, MosaicLayout::bayer("BGGR"), DemosaicMethod::kMatched,
                           no_signal));
  const auto bilinear =
      library(mosaic, kW, kH, MosaicLayout::bayer("BGGR"), DemosaicMethod::kBilinear);
  ASSERT_EQ(out.size(), bilinear.size());
  int differ = 0, dim = 0;
  for (std::size_t i = 0; i < out.size(); ++i) differ += out[i] != bilinear[i], dim += out[i] == 0;
  EXPECT_GT(differ, static_cast<int>(out.size()) / 2);
  EXPECT_GT(dim, 0);  // the row without light made the bands near it dim
}

TEST_F(Demosaic25, snapshot_bands_are_read_at_the_cell_centre_by_default) {
  // The default (auto) is matched for 5x5 mosaics: the library's, with the profile's level of
  // samples without light; a ramp's bands then differ from their binned values.
  start("demosaic25 profile=nir5x5-reference", mosaic_caps("5x5", 15, 15));
  const auto mosaic = ramp(15, 15);
  const auto out = run(mosaic);
  const CameraProfile profile = load_profile_by_name("nir5x5-reference");
  std::vector<SignalNoise> noise;
  for (int b = 0; b < profile.band_count(); ++b) noise.push_back(signal_noise(profile, b));
  const float no_signal = static_cast<float>(no_signal_level_dn(noise));
  EXPECT_GT(no_signal, 0.f);
  expect_same(out, library(mosaic, 15, 15, profile.mosaic, DemosaicMethod::kMatched, no_signal));
  const auto binned = library(mosaic, 15, 15, profile.mosaic, DemosaicMethod::kBinCells);
  ASSERT_EQ(out.size(), binned.size());
  int differ = 0;
  for (std::size_t i = 0; i < out.size(); ++i) differ += out[i] != binned[i];
  EXPECT_GT(differ, static_cast<int>(out.size()) / 2);
}

TEST_F(Demosaic25, saturated_pixel_stays_marked_through_darksub_and_demosaic25) {
  REQUIRE_ELEMENT("darksub");
  start("darksub dark-level=50 ! demosaic25",
        "video/x-bayer,format=rggb,width=8,height=8,framerate=30/1");
  std::vector<std::uint8_t> raw(64, 120);
  raw[2 * 8 + 2] = 255;  // an R pixel
  const auto v = push_pull<float>(h, buffer_from(raw));
  ASSERT_EQ(v.size(), 3u * 64);
  EXPECT_EQ(v[2 * 8 + 2], kInf);       // R at the saturated pixel
  EXPECT_EQ(v[3 * 8 + 3], kInf);       // R interpolated from it at the B pixel
  EXPECT_EQ(v[64 + 2 * 8 + 2], 70.f);  // G there is measured around it
  EXPECT_EQ(v[0], 70.f);
  EXPECT_EQ(v[2 * 64 + 5 * 8 + 5], 70.f);  // B far away
}

TEST_F(Demosaic25, survives_flush_and_eos) {
  start("demosaic25 method=bin2x2", mosaic_caps("bggr", 4, 4));
  const auto mosaic = ramp(4, 4);
  EXPECT_EQ(run(mosaic).size(), 12u);
  push_flush(h);
  expect_same(run(mosaic),
              library(mosaic, 4, 4, MosaicLayout::bayer("BGGR"), DemosaicMethod::kBinCells));
  EXPECT_TRUE(eos_passes(h));
}

// A Bayer camera's frames, darks subtracted, up to demosaic25.
const std::string kColourChain =
    "pyrocamsrc num-buffers=1 ! video/x-bayer,width=20,height=10 ! darksub dark-level=50 ! ";

TEST(Demosaic25Errors, rejects_a_missing_profile) {
  REQUIRE_ELEMENT("demosaic25");
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r =
      run_pipeline(kColourChain + "demosaic25 profile=/nonexistent/camera.json ! fakesink");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND, {"/nonexistent/camera.json"});
}

TEST(Demosaic25Errors, rejects_a_stream_that_is_not_the_profiles_mosaic) {
  REQUIRE_ELEMENT("demosaic25");
  REQUIRE_ELEMENT("pyrocamsrc");
  const auto r = run_pipeline(kColourChain + "demosaic25 profile=nir5x5-reference ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"nir5x5-reference has a 5x5 mosaic", "rggb mosaic"});
}

// A 5x5 stream whose camera orders bands 0 and 1 the other way round than row * 5 + column.
const char* kSwappedBandMap = "1,0,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24";
// Its frames, darks subtracted, up to demosaic25.
const std::string kSwappedChain =
    std::string(
        "videotestsrc num-buffers=1 ! "
        "video/x-raw,format=GRAY8,width=20,height=10,pattern=5x5,band-map=(string)\"") +
    kSwappedBandMap + "\" ! darksub dark-level=5 ! ";

TEST(Demosaic25Errors, rejects_a_profile_whose_band_map_differs_from_the_streams) {
  REQUIRE_ELEMENT("demosaic25");
  const auto r = run_pipeline(kSwappedChain + "demosaic25 profile=nir5x5-reference ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"orders the 5x5 bands 0,1,2", kSwappedBandMap});
}

TEST(Demosaic25Pipeline, orders_the_bands_by_the_streams_band_map_and_says_so) {
  REQUIRE_ELEMENT("demosaic25");
  const auto r =
      run_pipeline(kSwappedChain + "demosaic25 ! video/x-pyrocam-bands,band-map=(string)\"" +
                   kSwappedBandMap + "\" ! fakesink name=sink");
  expect_eos(r, 1);
}

TEST(Demosaic25Errors, rejects_caps_it_cannot_produce_n) {
  REQUIRE_ELEMENT("demosaic25");
  REQUIRE_ELEMENT("pyrocamsrc");
  // 25 bands cannot come from a Bayer camera: negotiation fails with an error, no crash.
  const auto r =
      run_pipeline(kColourChain + "demosaic25 ! video/x-pyrocam-bands,bands=25 ! fakesink");
  EXPECT_TRUE(r.error);
  EXPECT_FALSE(r.timed_out);
}

}  // namespace
}  // namespace pyrocam::test
