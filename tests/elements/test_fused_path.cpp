// The fused path between demosaic25 and ratiotemp: the two agree on the band planes as their
// mosaic (video/x-pyrocam-bands(memory:PyrocamMosaic)) when linked, and the ratio readings are
// then the ones the planes give (but for the edge checks' rings, read from the mosaic); the
// brightness readings and the blur correction are the library's on those; other elements get the
// planes; turning the mixed-pixel check on while playing goes back to the planes; the curvature
// check takes a hot spot's peak; fused caps without what ratiotemp needs are refused; a 5x5
// model's brightness readings on its planes.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <tuple>
#include <vector>

#include "element_support.h"
#include "pyrocam-caps.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/blur_bias.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/scaled_brightness.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::test {
namespace {

// Colour frames of the simulated camera (a melt pool whose core saturates, hot and cold
// frames) up to demosaic25.
std::string colour_chain(int frames) {
  return "pyrocamsrc num-buffers=" + std::to_string(frames) +
         " scene=melt-pool ! video/x-bayer,width=320,height=240 ! darksub dark-level=50 ! "
         "demosaic25 name=d ! ";
}

// The caps on an element's pad once a pipeline has prerolled (empty if it did not).
struct Negotiated {
  std::string caps;
  bool fused = false;
};
Negotiated negotiated(const std::string& description, const char* element, const char* pad) {
  Negotiated n;
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  EXPECT_TRUE(pipeline && !error) << (error ? error->message : "");
  if (error) g_error_free(error);
  if (!pipeline) return n;
  EXPECT_NE(gst_element_set_state(pipeline, GST_STATE_PAUSED), GST_STATE_CHANGE_FAILURE);
  EXPECT_EQ(gst_element_get_state(pipeline, nullptr, nullptr, 20 * GST_SECOND),
            GST_STATE_CHANGE_SUCCESS);
  GstElement* e = gst_bin_get_by_name(GST_BIN(pipeline), element);
  if (e) {
    GstPad* p = gst_element_get_static_pad(e, pad);
    n.caps = current_caps(p);
    n.fused = n.caps.find(PYROCAM_CAPS_FEATURE_MOSAIC) != std::string::npos;
    gst_object_unref(p);
    gst_object_unref(e);
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(pipeline);
  return n;
}

// The fused path reads the dim-edge and saturation-edge checks' rings (dim_edge.h,
// saturation_edge.h) from the mosaic, the planes path from the band planes: they may differ on
// whether a pixel with a band just above the dim threshold or just below the saturation level
// reads, never on a reading both give. Checks that, and that such pixels are few (at
// most 1 % of the readings, and 5).
void expect_same_readings(const std::vector<std::uint8_t>& fused,
                          const std::vector<std::uint8_t>& planes, std::size_t frame) {
  ASSERT_EQ(fused.size(), planes.size()) << "frame " << frame;
  std::size_t read = 0, one_only = 0, differ = 0;
  for (std::size_t k = 0; k + 1 < fused.size(); k += 2) {
    const int a = fused[k] | fused[k + 1] << 8, b = planes[k] | planes[k + 1] << 8;
    read += a != 0;
    one_only += (a != 0) != (b != 0);
    differ += a != 0 && b != 0 && a != b;
  }
  EXPECT_EQ(differ, 0u) << "frame " << frame << ": readings that both paths give differ";
  EXPECT_LE(one_only, std::max<std::size_t>(5, read / 100))
      << "frame " << frame << ": " << one_only << " pixels read on one path only, of " << read;
}

TEST(FusedPath, demosaic25_and_ratiotemp_agree_on_it_and_read_what_the_planes_read) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  // The ratio readings alone: the planes have no brightness readings.
  const std::string ratiotemp =
      "ratiotemp name=r brightness-radius=0 model=" + test_model_path("test-model-rgb.json");
  for (const char* settings : {"", " output=uncertainty", " method=likelihood partial-bands=any"}) {
    SCOPED_TRACE(settings);
    const std::string fused = colour_chain(8) + ratiotemp + settings + " ! fakesink name=sink";
    // A capsfilter of plain bands between them keeps the planes.
    const std::string planes = colour_chain(8) + "video/x-pyrocam-bands ! " + ratiotemp + settings +
                               " ! fakesink name=sink";
    const Negotiated n = negotiated(fused, "r", "sink");
    EXPECT_TRUE(n.fused) << n.caps;
    EXPECT_NE(n.caps.find("no-signal-level=(double)"), std::string::npos) << n.caps;
    EXPECT_FALSE(negotiated(planes, "r", "sink").fused);
    const auto a = sink_frames(fused), b = sink_frames(planes);
    ASSERT_EQ(a.size(), 8u);
    ASSERT_EQ(b.size(), 8u);
    std::size_t read = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      expect_same_readings(a[i], b[i], i);
      for (std::size_t k = 0; k + 1 < a[i].size(); k += 2) read += a[i][k] || a[i][k + 1];
    }
    EXPECT_GT(read, 100u);  // the pools read, so the comparison means something
  }
}

// blur-correction on the fused path: the library's correction of the frame read without it, the
// same pixels read; on the planes (where the demosaicking is not known) nothing changes.
TEST(FusedPath, blur_correction_corrects_the_fused_readings_only) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  const std::string model = test_model_path("test-model-rgb.json");
  const std::string ratiotemp = "ratiotemp brightness-radius=0 model=" + model;
  const std::string tail = " ! fakesink name=sink";
  const auto plain = sink_frames(colour_chain(4) + ratiotemp + tail);
  const auto corrected = sink_frames(colour_chain(4) + ratiotemp + " blur-correction=true" + tail);
  const auto planes = sink_frames(colour_chain(4) + "video/x-pyrocam-bands ! " + ratiotemp +
                                  " blur-correction=true" + tail);
  ASSERT_EQ(plain.size(), 4u);
  ASSERT_EQ(corrected.size(), 4u);
  ASSERT_EQ(planes.size(), 4u);
  const pyrocam::ThermalModel m = pyrocam::load_model(model);
  const pyrocam::BlurBiasCorrection blur(m, pyrocam::DemosaicMethod::kMatched);
  std::size_t changed = 0, read = 0;
  for (std::size_t i = 0; i < plain.size(); ++i) {
    expect_same_readings(plain[i], planes[i], i);
    cv::Mat codes(240, 320, CV_16U);
    ASSERT_EQ(plain[i].size(), codes.total() * 2);
    std::memcpy(codes.data, plain[i].data(), plain[i].size());
    const cv::Mat before = codes.clone();
    blur.apply_codes(codes);
    ASSERT_EQ(corrected[i].size(), plain[i].size());
    EXPECT_EQ(std::memcmp(codes.data, corrected[i].data(), plain[i].size()), 0) << "frame " << i;
    read += static_cast<std::size_t>(cv::countNonZero(before));
    changed += static_cast<std::size_t>(cv::countNonZero(before != codes));
    EXPECT_EQ(cv::countNonZero(before), cv::countNonZero(codes));
  }
  EXPECT_GT(read, 100u);
  EXPECT_GT(changed, 10u);  // the pools' sides
}

// Brightness readings on the fused path: the library's on the ratio readings and
// the dark-subtracted mosaic, the same pixels read and many changed, and the same output on
// frames with statistics (read from the codes there too); on the planes none.
TEST(FusedPath, brightness_readings_are_the_librarys_on_the_fused_path_only) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  const std::string model = test_model_path("test-model-rgb.json");
  const std::string tail = " ! fakesink name=sink";
  const std::string chain = colour_chain(4) + "ratiotemp model=" + model;
  const auto ratio = sink_frames(chain + " brightness-radius=0 stats-interval=0" + tail);
  const auto bright = sink_frames(chain + " brightness-radius=2 stats-interval=0" + tail);
  const auto with_stats = sink_frames(chain + " brightness-radius=2 stats-interval=1" + tail);
  const auto planes =
      sink_frames(colour_chain(4) + "video/x-pyrocam-bands ! ratiotemp model=" + model +
                  " brightness-radius=2 stats-interval=0" + tail);
  const auto mosaics = sink_frames(
      "pyrocamsrc num-buffers=4 scene=melt-pool ! video/x-bayer,width=320,height=240 ! "
      "darksub dark-level=50" +
      tail);
  ASSERT_EQ(ratio.size(), 4u);
  ASSERT_EQ(bright.size(), 4u);
  ASSERT_EQ(with_stats.size(), 4u);
  ASSERT_EQ(planes.size(), 4u);
  ASSERT_EQ(mosaics.size(), 4u);
  pyrocam::ScaledBrightness sb(pyrocam::load_model(model), 2);
  std::size_t read = 0, changed = 0;
  for (std::size_t i = 0; i < ratio.size(); ++i) {
    expect_same_readings(ratio[i], planes[i], i);
    EXPECT_EQ(with_stats[i], bright[i]) << "frame " << i;
    cv::Mat codes(240, 320, CV_16U), mosaic(240, 320, CV_32F);
    ASSERT_EQ(ratio[i].size(), codes.total() * 2);
    ASSERT_EQ(mosaics[i].size(), mosaic.total() * 4);
    std::memcpy(codes.data, ratio[i].data(), ratio[i].size());
    std::memcpy(mosaic.data, mosaics[i].data(), mosaics[i].size());
    const cv::Mat before = codes.clone();
    sb.apply_codes(mosaic, codes);
    ASSERT_EQ(bright[i].size(), ratio[i].size());
    EXPECT_EQ(std::memcmp(codes.data, bright[i].data(), codes.total() * 2), 0) << "frame " << i;
    read += static_cast<std::size_t>(cv::countNonZero(before));
    changed += static_cast<std::size_t>(cv::countNonZero(before != codes));
    EXPECT_EQ(cv::countNonZero(before), cv::countNonZero(codes));
  }
  EXPECT_GT(read, 100u);
  EXPECT_GT(changed, read / 2);
}

TEST(FusedPath, a_queue_between_them_keeps_it) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  const Negotiated n = negotiated(colour_chain(1) + "queue ! ratiotemp name=r model=" +
                                      test_model_path("test-model-rgb.json") + " ! fakesink",
                                  "r", "sink");
  EXPECT_TRUE(n.fused) << n.caps;
}

TEST(FusedPath, other_elements_and_other_settings_get_the_planes) {
  REQUIRE_ELEMENT("demosaic25");
  REQUIRE_ELEMENT("pyrocamsrc");
  // A sink that takes anything gets the planes, three of the frame's size.
  const Negotiated sink = negotiated(colour_chain(1) + "fakesink name=s", "s", "sink");
  EXPECT_FALSE(sink.fused) << sink.caps;
  EXPECT_NE(sink.caps.find("video/x-pyrocam-bands"), std::string::npos) << sink.caps;
  const auto frames = sink_frames(colour_chain(2) + "fakesink name=sink");
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].size(), 3u * 320 * 240 * sizeof(float));
  // Settings the fused path does not do: the planes, to ratiotemp too.
  const std::string model = test_model_path("test-model-rgb.json");
  for (const char* demosaic :
       {"demosaic25 method=bilinear", "demosaic25 mixed-pixels=0.5", "demosaic25 method=bin2x2"}) {
    const std::string chain =
        "pyrocamsrc num-buffers=1 scene=melt-pool ! video/x-bayer,width=160,height=120 ! "
        "darksub dark-level=50 ! " +
        std::string(demosaic) + " ! ratiotemp name=r model=" + model + " ! fakesink";
    const Negotiated n = negotiated(chain, "r", "sink");
    EXPECT_FALSE(n.fused) << demosaic << ": " << n.caps;
    EXPECT_NE(n.caps.find("video/x-pyrocam-bands"), std::string::npos) << demosaic;
  }
}

class FusedHarness : public HarnessTest {
 protected:
  FusedHarness() : HarnessTest("ratiotemp") {}
  void TearDown() override {
    if (demosaic) gst_object_unref(demosaic);
    demosaic = nullptr;
    HarnessTest::TearDown();
  }
  std::string src_caps_of_demosaic() {
    GstPad* pad = gst_element_get_static_pad(demosaic, "src");
    std::string caps = current_caps(pad);
    gst_object_unref(pad);
    return caps;
  }
  GstElement* demosaic = nullptr;
};

// A raw 16x12 RGGB frame: a hot block with a sharp edge on a cold background, one saturated.
std::vector<std::uint8_t> raw_frame() {
  std::vector<std::uint8_t> v(16 * 12, 50);
  for (int y = 3; y < 9; ++y)
    for (int x = 4; x < 12; ++x) v[static_cast<std::size_t>(y * 16 + x)] = 180;
  v[5 * 16 + 6] = 255;
  return v;
}

TEST_F(FusedHarness, the_mixed_pixel_check_turned_on_while_playing_goes_back_to_the_planes) {
  start("darksub dark-level=50 ! demosaic25 ! ratiotemp model=" +
            test_model_path("test-model-rgb.json"),
        "video/x-bayer,format=rggb,width=16,height=12,framerate=30/1");
  demosaic = find_element(h, "demosaic25");
  ASSERT_NE(demosaic, nullptr);
  GstBuffer* out = push_pull_buffer(h, buffer_from(raw_frame()));
  ASSERT_NE(out, nullptr);
  gst_buffer_unref(out);
  EXPECT_NE(src_caps_of_demosaic().find(PYROCAM_CAPS_FEATURE_MOSAIC), std::string::npos);
  g_object_set(demosaic, "mixed-pixels", 0.5, nullptr);
  out = push_pull_buffer(h, buffer_from(raw_frame()));
  ASSERT_NE(out, nullptr);
  gst_buffer_unref(out);
  const std::string caps = src_caps_of_demosaic();
  EXPECT_EQ(caps.find(PYROCAM_CAPS_FEATURE_MOSAIC), std::string::npos) << caps;
  EXPECT_NE(caps.find("video/x-pyrocam-bands"), std::string::npos) << caps;
  // And back.
  g_object_set(demosaic, "mixed-pixels", 0.0, nullptr);
  out = push_pull_buffer(h, buffer_from(raw_frame()));
  ASSERT_NE(out, nullptr);
  gst_buffer_unref(out);
  EXPECT_NE(src_caps_of_demosaic().find(PYROCAM_CAPS_FEATURE_MOSAIC), std::string::npos);
}

// Steps that need the fused path, asked for on plain planes: one warning naming the property,
// and the frames read without it; none without them.
TEST_F(FusedHarness, fused_only_steps_on_plain_planes_warn_once_and_read_n) {
  for (const auto& [setting, named] : {std::pair{"blur-correction=true", "blur-correction"},
                                       {"brightness-radius=3", "brightness-radius"},
                                       {"", ""}}) {
    SCOPED_TRACE(setting);
    start(std::string("darksub dark-level=50 ! demosaic25 method=bilinear ! ratiotemp ") + setting +
              " model=" + test_model_path("test-model-rgb.json"),
          "video/x-bayer,format=rggb,width=16,height=12,framerate=30/1");
    attach_bus();
    for (int i = 0; i < 2; ++i) {
      GstBuffer* out = push_pull_buffer(h, buffer_from(raw_frame()));
      ASSERT_NE(out, nullptr);
      gst_buffer_unref(out);
    }
    int warnings = 0;
    while (GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_WARNING)) {
      GError* err = nullptr;
      gchar* debug = nullptr;
      gst_message_parse_warning(m, &err, &debug);
      // The frame's saturated sample has its own warning (the statistics').
      const std::string text = err->message;
      if (text.find("saturated a band") == std::string::npos) {
        EXPECT_NE(text.find(named), std::string::npos) << text;
        ++warnings;
      }
      g_error_free(err);
      g_free(debug);
      gst_message_unref(m);
    }
    EXPECT_EQ(warnings, *named ? 1 : 0);
    TearDown();
  }
}

// The curvature check on the fused path: a hot spot T = 2000 - 60 r^2 degC (r in pixels; a
// share of about -140 degC), whose peak the planes path reads about 200 degC low (bound at 100:
// a model reading the red/green ratio above its calibration read it 125 degC low), has no
// reading there; the frames that post statistics (the check as a pass of its own) give the
// codes of those that do not (the check inside the estimate), which are the library's.
TEST_F(FusedHarness, a_hot_spot_a_few_pixels_across_has_no_reading_at_its_peak) {
  constexpr int kW = 32, kH = 24, kX = 16, kY = 12;
  cv::Mat spot(kH, kW, CV_32F, cv::Scalar(NAN));
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      const double t = 2000 - 60.0 * ((x - kX) * (x - kX) + (y - kY) * (y - kY));
      if (t > 500) spot.at<float>(y, x) = static_cast<float>(t);
    }
  const std::shared_ptr<const ThermalModel> model =
      std::make_shared<const ThermalModel>(load_model(test_model_path("test-model-rgb.json")));
  Simulator camera(model->profile(), UnitPerturbation::parse("typical", 1), 3);
  const cv::Mat raw = camera.render(spot, camera.exposure_for(2000, 150), 1.0);
  const std::vector<std::uint8_t> frame(raw.datastart, raw.dataend);
  std::vector<std::vector<std::uint16_t>> out;
  for (const char* link : {"ratiotemp stats-interval=0", "ratiotemp stats-interval=1",
                           "video/x-pyrocam-bands ! ratiotemp"}) {
    start(std::string("darksub dark-level=50 ! demosaic25 ! ") + link +
              " model=" + test_model_path("test-model-rgb.json"),
          "video/x-bayer,format=rggb,width=32,height=24,framerate=30/1");
    GstBuffer* b = push_pull_buffer(h, buffer_from(frame));
    ASSERT_NE(b, nullptr) << link;
    out.push_back(values_of<std::uint16_t>(b));
    gst_buffer_unref(b);
    TearDown();
  }
  constexpr std::size_t kPeak = kY * kW + kX;
  ASSERT_EQ(out[0].size(), static_cast<std::size_t>(kW * kH));
  EXPECT_EQ(out[0], out[1]);
  EXPECT_EQ(out[0][kPeak], kNoReadingCode);
  // The planes (no check): the same kernels read it, wild.
  ASSERT_NE(out[2][kPeak], kNoReadingCode);
  EXPECT_LT(code_to_celsius(out[2][kPeak]), 2000 - 100);
  MeasureOptions options;
  options.method = choose_method(model, MethodRequest::kAuto);
  FrameMeasurer measurer(model, options);
  cv::Mat t;
  measurer.measure(raw, cv::Mat(kH, kW, CV_8U, cv::Scalar(50)), t);
  const cv::Mat codes = encode_decikelvin(t);
  EXPECT_EQ(std::vector<std::uint16_t>(codes.begin<std::uint16_t>(), codes.end<std::uint16_t>()),
            out[0]);
}

// blur-correction and brightness-radius give the codes `pyrocam-calib measure` gives for the same
// frame (the measurer corrected floats and differed by a code on a quarter of a plate's pixels).
TEST_F(FusedHarness, corrections_give_the_measurers_codes) {
  constexpr int kW = 64, kH = 48;
  cv::Mat ramp(kH, kW, CV_32F);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) ramp.at<float>(y, x) = static_cast<float>(1600 + 8.0 * x + 2 * y);
  const std::shared_ptr<const ThermalModel> model =
      std::make_shared<const ThermalModel>(load_model(test_model_path("test-model-rgb.json")));
  Simulator camera(model->profile(), UnitPerturbation::parse("typical", 1), 5);
  const cv::Mat raw = camera.render(ramp, camera.exposure_for(2200, 150), 1.0);
  const std::vector<std::uint8_t> frame(raw.datastart, raw.dataend);
  for (const auto& [setting, blur, radius] :
       {std::tuple{"blur-correction=true", true, 0},
        {"brightness-radius=2", false, 2},
        {"blur-correction=true brightness-radius=2", true, 2}}) {
    SCOPED_TRACE(setting);
    start(std::string("darksub dark-level=50 ! demosaic25 ! ratiotemp stats-interval=0 ") +
              setting + " model=" + test_model_path("test-model-rgb.json"),
          "video/x-bayer,format=rggb,width=64,height=48,framerate=30/1");
    GstBuffer* b = push_pull_buffer(h, buffer_from(frame));
    ASSERT_NE(b, nullptr);
    const std::vector<std::uint16_t> element = values_of<std::uint16_t>(b);
    gst_buffer_unref(b);
    TearDown();
    MeasureOptions options;
    options.method = choose_method(model, MethodRequest::kAuto);
    options.blur_correction = blur;
    options.brightness_radius = radius;
    FrameMeasurer measurer(model, options);
    cv::Mat t;
    measurer.measure(raw, cv::Mat(kH, kW, CV_8U, cv::Scalar(50)), t);
    const cv::Mat codes = encode_decikelvin(t);
    const std::vector<std::uint16_t> measured(codes.begin<std::uint16_t>(),
                                              codes.end<std::uint16_t>());
    ASSERT_EQ(measured.size(), element.size());
    int read = 0, differ = 0;
    for (std::size_t i = 0; i < measured.size(); ++i)
      read += element[i] != kNoReadingCode, differ += element[i] != measured[i];
    EXPECT_GT(read, kW * kH / 2);
    EXPECT_EQ(differ, 0);
  }
}

// On a snapshot (5x5) model's band planes, which take no fused path, brightness-radius reads each
// cell from all its bands (snapshot_brightness.h): the codes `pyrocam-calib measure` gives, the
// fit's cells, most of them moved.
TEST_F(FusedHarness, snapshot_brightness_readings_give_the_measurers_codes) {
  constexpr int kW = 60, kH = 40;  // 12 x 8 cells
  cv::Mat ramp(kH, kW, CV_32F);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) ramp.at<float>(y, x) = static_cast<float>(1500 + 3.0 * x + y);
  const std::string path = test_model_path("test-model-nir5x5.json");
  const std::shared_ptr<const ThermalModel> model =
      std::make_shared<const ThermalModel>(load_model(path));
  Simulator camera(model->profile(), UnitPerturbation::parse("typical", 1), 5);
  const cv::Mat raw = camera.render(ramp, camera.exposure_for(1650, 150), 1.0);
  const std::vector<std::uint8_t> frame(raw.datastart, raw.dataend);
  std::vector<std::uint16_t> element[2];
  for (int radius : {0, 2}) {
    start("darksub dark-level=50 ! demosaic25 ! ratiotemp stats-interval=0 brightness-radius=" +
              std::to_string(radius) + " model=" + path,
          "video/x-raw,format=GRAY8,pattern=5x5,bit-depth=8,width=60,height=40,framerate=30/1");
    GstBuffer* b = push_pull_buffer(h, buffer_from(frame));
    ASSERT_NE(b, nullptr);
    element[radius / 2] = values_of<std::uint16_t>(b);
    gst_buffer_unref(b);
    TearDown();
  }
  MeasureOptions options;
  options.method = choose_method(model, MethodRequest::kAuto);
  options.safe_partial = true;  // ratiotemp's default partial-bands
  options.brightness_radius = 2;
  FrameMeasurer measurer(model, options);
  cv::Mat t;
  measurer.measure(raw, cv::Mat(kH, kW, CV_8U, cv::Scalar(50)), t);
  const cv::Mat codes = encode_decikelvin(t);
  const std::vector<std::uint16_t> measured(codes.begin<std::uint16_t>(),
                                            codes.end<std::uint16_t>());
  ASSERT_EQ(measured.size(), element[1].size());
  ASSERT_EQ(element[0].size(), element[1].size());
  int read = 0, differ = 0, moved = 0;
  for (std::size_t i = 0; i < measured.size(); ++i) {
    EXPECT_EQ(element[0][i] != kNoReadingCode, element[1][i] != kNoReadingCode) << i;
    read += element[1][i] != kNoReadingCode;
    differ += element[1][i] != measured[i];
    moved += element[1][i] != element[0][i];
  }
  EXPECT_GT(read, 12 * 8 / 2);
  EXPECT_EQ(differ, 0);
  EXPECT_GT(moved, read / 2);
}

TEST_F(FusedHarness, fused_bands_without_a_no_signal_level_are_refused_n) {
  start("ratiotemp model=" + test_model_path("test-model-rgb.json"),
        "video/x-pyrocam-bands(memory:PyrocamMosaic),format=F32LE,bands=3,width=8,height=6,"
        "framerate=30/1,layout=bayer,pattern=rggb");
  attach_bus();
  GstBuffer* in = buffer_from(std::vector<float>(8 * 6, 50.f));
  EXPECT_EQ(gst_harness_push(h, in), GST_FLOW_NOT_NEGOTIATED);
  GstMessage* m = gst_bus_pop_filtered(bus, GST_MESSAGE_ERROR);
  ASSERT_NE(m, nullptr);
  GError* err = nullptr;
  gchar* debug = nullptr;
  gst_message_parse_error(m, &err, &debug);
  EXPECT_EQ(err->domain, GST_CORE_ERROR);
  EXPECT_NE(std::string(err->message).find("no-signal-level"), std::string::npos) << err->message;
  g_error_free(err);
  g_free(debug);
  gst_message_unref(m);
}

}  // namespace
}  // namespace pyrocam::test
