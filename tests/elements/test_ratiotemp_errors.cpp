// ratiotemp in whole pipelines (a simulated plate and snapshot camera through the chain, an
// FFV1 recording bit for bit), and the bus errors for bad models, caps and settings.
#include <cmath>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"
#include "test_support.h"

namespace pyrocam::test {
namespace {

std::string rgb_model_path() { return test_model_path("test-model-rgb.json"); }
std::string nir_model_path() { return test_model_path("test-model-nir5x5.json"); }

// Runs a pipeline to EOS or error, collecting the statistics messages.
struct StatsRun {
  BusResult result;
  std::vector<GstStructure*> stats;
  ~StatsRun() { free_all(stats); }
};
void run_with_stats(const std::string& description, StatsRun* run) {
  GError* error = nullptr;
  GstElement* pipeline = gst_parse_launch(description.c_str(), &error);
  ASSERT_TRUE(pipeline && !error) << (error ? error->message : "");
  GstBus* bus = gst_element_get_bus(pipeline);
  gst_element_set_state(pipeline, GST_STATE_PLAYING);
  for (;;) {
    GstMessage* msg = gst_bus_timed_pop_filtered(
        bus, 30 * GST_SECOND,
        static_cast<GstMessageType>(GST_MESSAGE_EOS | GST_MESSAGE_ERROR | GST_MESSAGE_ELEMENT));
    if (!msg) {
      run->result.timed_out = true;
      break;
    }
    const GstMessageType type = GST_MESSAGE_TYPE(msg);
    if (type == GST_MESSAGE_ELEMENT) {
      const GstStructure* s = gst_message_get_structure(msg);
      if (s && gst_structure_has_name(s, "pyrocam-temperature-stats"))
        run->stats.push_back(gst_structure_copy(s));
    } else if (type == GST_MESSAGE_EOS) {
      run->result.eos = true;
    } else {
      GError* err = nullptr;
      gst_message_parse_error(msg, &err, nullptr);
      run->result.error = true;
      run->result.message = err->message;
      g_error_free(err);
    }
    gst_message_unref(msg);
    if (type != GST_MESSAGE_ELEMENT) break;
  }
  gst_element_set_state(pipeline, GST_STATE_NULL);
  gst_object_unref(bus);
  gst_object_unref(pipeline);
}

TEST(RatioTempPipeline, simulated_plate_reads_its_temperature_through_the_chain) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp", "thermalcolormap"})
    REQUIRE_ELEMENT(e);
  StatsRun run;
  // The plate fills the central 60 %: the region is well inside it.
  run_with_stats(
      "pyrocamsrc scene=plate temperature=1050 num-buffers=3 ! "
      "video/x-bayer,width=80,height=60 ! darksub dark-level=50 ! demosaic25 ! "
      "ratiotemp stats-interval=1 region=30,20,20,20 model=" +
          rgb_model_path() + " ! thermalcolormap ! fakesink",
      &run);
  ASSERT_TRUE(run.result.eos) << run.result.message;
  ASSERT_EQ(run.stats.size(), 3u);
  for (const GstStructure* s : run.stats) {
    EXPECT_GT(field_double(s, "region-valid-fraction"), 0.9);
    // A test model (short training) on a simulated typical unit: within 50 degC.
    EXPECT_NEAR(field_double(s, "region-median-c"), 1050, 50);
    // The cold background has no reading.
    EXPECT_LT(field_double(s, "valid-fraction"), 0.7);
  }
}

TEST(RatioTempPipeline, snapshot_camera_through_the_chain) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
  StatsRun run;
  run_with_stats(
      "pyrocamsrc profile=nir5x5-reference scene=plate temperature=1000 num-buffers=2 ! "
      "video/x-raw,width=100,height=50 ! darksub dark-level=50 pattern=5x5 ! demosaic25 ! "
      "ratiotemp stats-interval=1 region=8,4,4,2 model=" +
          nir_model_path() + " ! fakesink",
      &run);
  ASSERT_TRUE(run.result.eos) << run.result.message;
  ASSERT_EQ(run.stats.size(), 2u);
  int w = 0;
  EXPECT_TRUE(gst_structure_get_int(run.stats[0], "width", &w));
  EXPECT_EQ(w, 20);
  EXPECT_STREQ(gst_structure_get_string(run.stats[0], "method"), "likelihood");
  EXPECT_NEAR(field_double(run.stats[0], "region-median-c"), 1000, 50);
}

TEST(RatioTempPipeline, temperatures_survive_an_ffv1_recording_bit_exactly) {
  for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
  for (const char* e : {"avenc_ffv1", "avdec_ffv1", "matroskamux", "matroskademux"})
    if (!have_element(e)) GTEST_SKIP() << e << " is not installed (gstreamer1.0-libav, -good)";
  ScratchDir dir("ratiotemp-ffv1");
  const std::string file = (dir / "t.mkv").string();
  const auto direct = sink_frames(
      "pyrocamsrc scene=plate temperature=1200 num-buffers=3 ! video/x-bayer,width=32,height=24 ! "
      "darksub dark-level=50 ! demosaic25 ! ratiotemp model=" +
      rgb_model_path() + " ! tee name=t ! queue ! avenc_ffv1 ! matroskamux ! filesink location=" +
      file + " t. ! queue ! fakesink name=sink");
  ASSERT_EQ(direct.size(), 3u);
  const auto codes = std::vector<std::uint16_t>(
      reinterpret_cast<const std::uint16_t*>(direct[0].data()),
      reinterpret_cast<const std::uint16_t*>(direct[0].data() + direct[0].size()));
  EXPECT_GT(count_nonzero(codes), 100u);  // the plate reads
  const auto back = sink_frames("filesrc location=" + file +
                                " ! matroskademux ! avdec_ffv1 ! video/x-raw,format=GRAY16_LE ! "
                                "fakesink name=sink");
  EXPECT_EQ(back, direct);
}

const std::string kColourChain =
    "pyrocamsrc num-buffers=1 ! video/x-bayer,width=20,height=10 ! darksub dark-level=50 ! "
    "demosaic25 ! ";
const std::string kSnapshotChain =
    "pyrocamsrc num-buffers=1 profile=nir5x5-reference ! video/x-raw,width=20,height=10 ! "
    "darksub dark-level=50 pattern=5x5 ! demosaic25 ! ";

// Runs `chain` into a ratiotemp (its launch words) and a fakesink.
BusResult run_chain(const std::string& chain, const std::string& ratiotemp) {
  return run_pipeline(chain + ratiotemp + " ! fakesink");
}

TEST(RatioTempErrors, rejects_a_5x5_mosaic_with_a_colour_model_n) {
  // darksub used to read the untagged 5x5 mosaic as RGGB: plausible temperatures, all wrong.
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=1 profile=nir5x5-reference ! video/x-raw,width=20,height=10 ! "
      "darksub dark-level=5 ! demosaic25 ! ratiotemp model=" +
      rgb_model_path() + " ! fakesink");
  ASSERT_TRUE(r.error) << "ran to the end with a colour model on a 5x5 mosaic";
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"5x5", "bayer"});
}

TEST(RatioTempErrors, rejects_5x5_bands_in_another_order_than_the_models_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_pipeline(
      "videotestsrc num-buffers=1 ! video/x-raw,format=GRAY8,width=20,height=10,pattern=5x5,"
      "band-map=(string)\"1,0,2,3,4,5,6,7,8,9,10,11,12,13,14,15,16,17,18,19,20,21,22,23,24\" ! "
      "darksub dark-level=5 ! demosaic25 ! ratiotemp model=" +
      nir_model_path() + " ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"in the order 0,1,2", "in the order 1,0,2"});
}

TEST(RatioTempErrors, rejects_a_saturation_level_above_the_models_n) {
  // darksub would pass 220..239 DN unmarked, which the model's camera calls saturated.
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_pipeline(
      "pyrocamsrc num-buffers=1 ! video/x-bayer,width=20,height=10 ! darksub dark-level=50 "
      "saturation-level=240 ! demosaic25 ! ratiotemp model=" +
      rgb_model_path() + " ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"from 240 DN", "220 DN"});
}

// A 12-bit stream on a model of an 8-bit camera: named as that, not as a saturation level to
// lower (which then ran, with every DN sixteen times the model's).
TEST(RatioTempErrors, names_a_stream_deeper_than_the_models_camera_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_pipeline(
      "videotestsrc num-buffers=1 ! video/x-raw,format=GRAY16_LE,width=20,height=10 ! "
      "darksub dark-level=50 pattern=rggb bit-depth=12 ! demosaic25 ! ratiotemp model=" +
      rgb_model_path() + " ! fakesink");
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"255 DN full scale of the 8-bit camera", "deeper than the model's camera"});
}

TEST(RatioTempErrors, rejects_running_without_a_model_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kColourChain, "ratiotemp");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"model"});
}

TEST(RatioTempErrors, rejects_a_missing_model_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kColourChain, "ratiotemp model=/nonexistent/cam.json");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND, {"/nonexistent/cam.json"});
}

TEST(RatioTempErrors, names_a_folder_given_as_the_model_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kColourChain, "ratiotemp model=/tmp");
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_NOT_FOUND, {"/tmp is a folder"});
}

// A value the property refuses (an even window) fails the start, naming it: the element would
// otherwise run with another setting than the one given. (Values out of a property's range GLib
// refuses itself, with a warning: pyrocam-launch refuses such a line.)
TEST(RatioTempErrors, a_refused_property_value_fails_the_start_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const std::string model = " model=" + rgb_model_path();
  expect_error(run_chain(kColourChain, "ratiotemp peak-window=4" + model), GST_RESOURCE_ERROR,
               GST_RESOURCE_ERROR_SETTINGS, {"peak-window 4 is even"});
  const auto fine = run_chain(kColourChain, "ratiotemp peak-window=4 peak-window=7" + model);
  EXPECT_TRUE(fine.eos) << fine.message;
}

TEST(RatioTempErrors, rejects_a_truncated_model_n) {
  REQUIRE_ELEMENT("ratiotemp");
  ScratchDir dir("ratiotemp-truncated");
  const std::string text = read_text(rgb_model_path());
  ASSERT_GT(text.size(), 1000u);
  write_text(dir / "cam.json", text.substr(0, text.size() / 2));
  const auto r = run_chain(kColourChain, "ratiotemp model=" + (dir / "cam.json").string());
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_READ, {"cam.json"});
}

TEST(RatioTempErrors, rejects_a_model_of_another_version_n) {
  REQUIRE_ELEMENT("ratiotemp");
  ScratchDir dir("ratiotemp-version");
  nlohmann::json j = nlohmann::json::parse(read_text(rgb_model_path()));
  j["version"] = kModelFormatVersion + 1;
  write_text(dir / "cam.json", j.dump());
  const auto r = run_chain(kColourChain, "ratiotemp model=" + (dir / "cam.json").string());
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_READ, {"cam.json"});
}

TEST(RatioTempErrors, rejects_a_band_count_mismatch_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kColourChain, "ratiotemp model=" + nir_model_path());
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION, {"25 bands", "3 bands"});
  EXPECT_EQ(r.source.rfind("ratiotemp", 0), 0u) << r.source;
}

TEST(RatioTempErrors, rejects_a_colour_model_on_a_snapshot_camera_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kSnapshotChain, "ratiotemp model=" + rgb_model_path());
  expect_error(r, GST_CORE_ERROR, GST_CORE_ERROR_NEGOTIATION,
               {"3 bands of a bayer", "25 bands of a 5x5"});
}

TEST(RatioTempErrors, rejects_lut_with_the_5x5_model_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kSnapshotChain, "ratiotemp method=lut model=" + nir_model_path());
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"lut", "two ratios"});
}

// A network no table can follow (its inputs' scale several times too small, so that what it
// reads varies that much faster across the ratios): method=lut is refused, naming the
// difference. Which factor makes the table differ depends on the trained network (at 40 the
// test model's network once did, a retrained one reads almost nothing in range there, and
// tables of networks that read nothing agree), so the first that the library's check refuses.
TEST(RatioTempErrors, rejects_a_lookup_table_that_disagrees_with_the_network_n) {
  REQUIRE_ELEMENT("ratiotemp");
  ScratchDir dir("ratiotemp-lut-check");
  const ThermalModel trained = load_model(rgb_model_path());
  bool wild = false;
  for (double factor : {40, 25, 15, 8, 5, 3}) {
    auto model = std::make_shared<ThermalModel>(trained);
    nlohmann::json network = model->mlp.to_json();
    for (auto& scale : network["input_scale"]) scale = scale.get<double>() / factor;
    model->mlp = Mlp::from_json(network);
    const auto lut = make_estimator(model, Method::kLut);
    const auto mlp = make_estimator(model, Method::kMlp);
    if (!lut_disagreement(compare_on_locus(*model, *lut, *mlp)).empty()) {
      save_model(*model, dir / "wild.json");
      wild = true;
      break;
    }
  }
  ASSERT_TRUE(wild) << "no input scale made the test model's network wild";
  const auto r =
      run_chain(kColourChain, "ratiotemp method=lut model=" + (dir / "wild.json").string());
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS,
               {"lookup table differs from its network by up to"});
}

TEST(RatioTempErrors, rejects_an_invalid_region_n) {
  REQUIRE_ELEMENT("ratiotemp");
  const auto r = run_chain(kColourChain, "ratiotemp region=10,10,0,5 model=" + rgb_model_path());
  expect_error(r, GST_RESOURCE_ERROR, GST_RESOURCE_ERROR_SETTINGS, {"10,10,0,5"});
}

// A 5x5 mosaic cropped by a row at the top reads every pixel, 860 degC low on a 1500 degC
// plate and as tight as a right one: ratiotemp warns that the bands do not fit the model. The
// check's tables are made on their own thread while the first frames pass unchecked, so the
// shifted stream runs until the warning comes (a minute at most); the crop by whole periods at
// the right and bottom says nothing over 40 frames.
TEST(RatioTempErrors, warns_when_the_readings_do_not_fit_the_model_s_spectra) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  if (!have_element("videocrop")) GTEST_SKIP() << "videocrop (gst-plugins-good) missing";
  const auto chain = [](const std::string& frames, const std::string& crop) {
    return "pyrocamsrc is-live=true " + frames +
           " profile=nir5x5-reference scene=plate temperature=1500 ! "
           "video/x-raw,width=400,height=300,framerate=30/1 ! videocrop " +
           crop + " ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=" + nir_model_path() +
           " ! fakesink name=sink";
  };
  const auto whole = run_pipeline(chain("num-buffers=40", "right=5 bottom=5"));
  expect_eos(whole, 40);
  EXPECT_TRUE(whole.warnings.empty()) << whole.warnings.front();
  const auto shifted = run_pipeline(chain("", "top=1 bottom=4"), 60 * GST_SECOND, true);
  ASSERT_FALSE(shifted.error) << shifted.message;
  ASSERT_EQ(shifted.warnings.size(), 1u) << "no warning within a minute";
  for (const char* part : {"do not fit the model's band spectra", "phase", "nir5x5"})
    EXPECT_NE(shifted.warnings[0].find(part), std::string::npos) << shifted.warnings[0];
}

// A colour camera's red and blue traded (an rggb sensor whose frames say bggr: the greens stay in
// place, so darksub's check cannot see it) read a 1300 degC plate near 630 degC, on the locus:
// the band check passes them. Their brightness at the frames' exposure (pyrocamsrc's meta) is
// about ten thousand times a black body's at 630 degC, and ratiotemp warns; the right label says
// nothing.
TEST(RatioTempErrors, warns_when_the_readings_are_brighter_than_a_black_body) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  if (!have_element("capssetter")) GTEST_SKIP() << "capssetter (gst-plugins-good) missing";
  const auto chain = [](const std::string& frames, const char* label) {
    return "pyrocamsrc is-live=true " + frames +
           " scene=plate temperature=1300 ! video/x-bayer,format=rggb,width=160,height=120,"
           "framerate=30/1 ! capssetter caps=video/x-bayer,format=" +
           label + " ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=" + rgb_model_path() +
           " ! fakesink name=sink";
  };
  const auto right = run_pipeline(chain("num-buffers=40", "rggb"));
  expect_eos(right, 40);
  EXPECT_TRUE(right.warnings.empty()) << right.warnings.front();
  const auto traded = run_pipeline(chain("", "bggr"), 60 * GST_SECOND, true);
  ASSERT_FALSE(traded.error) << traded.message;
  ASSERT_EQ(traded.warnings.size(), 1u) << "no warning within a minute";
  for (const char* part : {"times as bright as a black body", "far too cold", "red and blue"})
    EXPECT_NE(traded.warnings[0].find(part), std::string::npos) << traded.warnings[0];
}

// A region in the sensor's pixels on a 5x5 camera, whose frames are macro-pixels (64x48 here):
// its statistics are empty, and a warning says why; one inside says nothing.
TEST(RatioTempErrors, warns_of_a_region_outside_the_frame_n) {
  REQUIRE_ELEMENT("ratiotemp");
  REQUIRE_ELEMENT("pyrocamsrc");
  for (const char* region : {"200,150,40,40", "20,15,10,10"}) {
    SCOPED_TRACE(region);
    const auto r = run_pipeline(
        "pyrocamsrc num-buffers=2 profile=nir5x5-reference scene=plate ! "
        "video/x-raw,width=320,height=240 ! darksub dark-level=50 ! demosaic25 ! ratiotemp model=" +
        nir_model_path() + " region=" + region + " ! fakesink name=sink");
    expect_eos(r, 2);
    const bool outside = std::string(region) == "200,150,40,40";
    ASSERT_EQ(r.warnings.size(), outside ? 1u : 0u);
    if (outside) {
      EXPECT_NE(r.warnings[0].find("region 200,150,40,40 lies outside the 64x48 frame"),
                std::string::npos)
          << r.warnings[0];
    }
  }
}

}  // namespace
}  // namespace pyrocam::test
