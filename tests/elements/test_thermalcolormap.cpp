// thermalcolormap: output formats, colours against the library, transparent no-reading pixels,
// live property changes, auto range, scale bar, isotherm, and an overlay with compositor.
#include <cmath>

#include "element_support.h"
#include "pyrocam/runtime/colormap.h"
#include "saturation_meta_support.h"

namespace pyrocam::test {
namespace {

std::uint16_t code_of(double t_c) {
  return static_cast<std::uint16_t>(std::lround((t_c + 273.15) * 10));
}

class ThermalColormap : public HarnessTest {
 protected:
  ThermalColormap() : HarnessTest("thermalcolormap") {}
  // The first message of a type on the bus: its domain, code and message ("" if none).
  std::string first(GstMessageType type, GQuark* domain = nullptr, int* code = nullptr) {
    GstMessage* m = gst_bus_pop_filtered(bus, type);
    if (!m) return "";
    GError* err = nullptr;
    if (type == GST_MESSAGE_ERROR)
      gst_message_parse_error(m, &err, nullptr);
    else
      gst_message_parse_warning(m, &err, nullptr);
    const std::string text = err->message;
    if (domain) *domain = err->domain;
    if (code) *code = err->code;
    g_error_free(err);
    gst_message_unref(m);
    return text;
  }
  // The harness fed GRAY16_LE codes of w x h_, its output format fixed where `out_format`.
  void start(const char* launch, const char* out_format, int w = 4, int h_ = 2) {
    HarnessTest::start(launch, "video/x-raw,format=GRAY16_LE,width=" + std::to_string(w) +
                                   ",height=" + std::to_string(h_) + ",framerate=30/1");
    if (out_format)
      gst_harness_set_sink_caps_str(h, (std::string("video/x-raw,format=") + out_format).c_str());
  }
  std::vector<std::uint8_t> run(const std::vector<std::uint16_t>& codes) {
    return push_pull<std::uint8_t>(h, buffer_from(codes));
  }
};

// The library's bytes for codes under given settings.
std::vector<std::uint8_t> library(const std::vector<std::uint16_t>& codes,
                                  const ColormapSettings& s) {
  pyrocam::ThermalColormap map;
  map.configure(s);
  std::vector<std::uint8_t> out;
  for (std::uint16_t c : codes) {
    const auto p = map.pixel(c);
    out.insert(out.end(), p.begin(), p.end());
  }
  return out;
}

const std::vector<std::uint16_t> kCodes = {
    0, code_of(900), code_of(1100), code_of(1300), code_of(1500), code_of(1700), code_of(1900), 0};

TEST_F(ThermalColormap, fixed_range_rgba_matches_the_library_with_transparent_invalid) {
  start("thermalcolormap range-mode=fixed min-temperature=1000 max-temperature=1800", nullptr);
  const auto out = run(kCodes);
  ColormapSettings s;
  s.min_c = 1000;
  s.max_c = 1800;
  EXPECT_EQ(out, library(kCodes, s));
  EXPECT_EQ(out[3], 0);  // alpha of "no reading"
  EXPECT_EQ(out[7], 255);
  const std::string caps = sink_caps(h);
  EXPECT_NE(caps.find("format=(string)RGBA"), std::string::npos) << caps;
}

// A frame without an image (GAP: darksub capturing a dark) stays flagged when coloured, and the
// next frame with one is not: the base class clears the flag for elements that do not say they
// keep it, and a recorder downstream took the empty frame for one of a cold scene.
TEST_F(ThermalColormap, keeps_the_gap_flag) {
  start("thermalcolormap", nullptr);
  for (bool gap : {true, false}) {
    GstBuffer* in = buffer_from(kCodes);
    if (gap) GST_BUFFER_FLAG_SET(in, GST_BUFFER_FLAG_GAP);
    GstBuffer* out = push_pull_buffer(h, in);
    ASSERT_NE(out, nullptr);
    EXPECT_EQ(GST_BUFFER_FLAG_IS_SET(out, GST_BUFFER_FLAG_GAP), gap);
    gst_buffer_unref(out);
  }
}

TEST_F(ThermalColormap, bgra_output_and_palette_change_while_playing) {
  start("thermalcolormap range-mode=fixed min-temperature=1000 max-temperature=1800", "BGRA");
  ColormapSettings s;
  s.min_c = 1000;
  s.max_c = 1800;
  s.order = ChannelOrder::kBGRA;
  EXPECT_EQ(run(kCodes), library(kCodes, s));
  GstElement* e = find_element(h, "thermalcolormap");
  g_object_set(e, "palette", 1 /* inferno */, "invalid-color", 0x80FF0000u, nullptr);
  gst_object_unref(e);
  s.palette = Palette::kInferno;
  s.invalid_argb = 0x80FF0000u;
  const auto out = run(kCodes);
  EXPECT_EQ(out, library(kCodes, s));
  EXPECT_EQ(out[2], 0xFF);  // red of the invalid colour, BGRA order
  EXPECT_EQ(out[3], 0x80);
}

TEST_F(ThermalColormap, isotherm_marks_hot_pixels) {
  start("thermalcolormap range-mode=fixed isotherm-threshold=1500 isotherm-color=0xFF0000FF",
        "RGBx");
  const auto out = run(kCodes);
  for (int i : {4, 5, 6}) {
    EXPECT_EQ(out[4 * i + 0], 0) << i;
    EXPECT_EQ(out[4 * i + 2], 255) << i;  // blue
  }
  EXPECT_NE(out[4 * 3 + 0], 0);  // 1300 degC in the iron palette has red
}

TEST_F(ThermalColormap, controlled_isotherm_follows_the_controller_by_buffer_time) {
  start("thermalcolormap range-mode=fixed isotherm-color=0xFF0000FF", "RGBx");
  GstElement* e = find_element(h, "thermalcolormap");
  // No isotherm until 1 s, then one at 1500 degC.
  ASSERT_TRUE(control_property(e, "isotherm-threshold", {{0, -273.15}, {GST_SECOND, 1500.0}}));
  gst_object_unref(e);
  auto run_at = [&](GstClockTime pts) {
    return push_pull<std::uint8_t>(h, with_pts(buffer_from(kCodes), pts));
  };
  const auto before = run_at(0);
  ASSERT_EQ(before.size(), kCodes.size() * 4);
  EXPECT_NE(before[4 * 5 + 2], 255);  // 1700 degC in the iron palette, not the isotherm's blue
  const auto after = run_at(GST_SECOND);
  ASSERT_EQ(after.size(), kCodes.size() * 4);
  for (int i : {4, 5, 6}) {
    EXPECT_EQ(after[4 * i + 0], 0) << i;
    EXPECT_EQ(after[4 * i + 2], 255) << i;
  }
}

TEST_F(ThermalColormap, auto_range_widens_at_once_and_narrows_smoothly) {
  start("thermalcolormap range-mode=auto auto-smoothing=0.5 palette=grey", nullptr, 2, 1);
  // First frame: its own range, so the hot end is white and the cold end black.
  auto out = run({code_of(1000), code_of(2000)});
  EXPECT_EQ(out[0], 0);
  EXPECT_EQ(out[4], 255);
  // A hotter frame: the top takes in 2200 degC at once (white is 2200, not a clipped 2100), the
  // bottom rises only half way (1100).
  out = run({code_of(1200), code_of(2200)});
  ColormapSettings s;
  s.palette = Palette::kGrey;
  s.min_c = 1100;
  s.max_c = 2200;
  EXPECT_EQ(out, library({code_of(1200), code_of(2200)}, s));
  EXPECT_EQ(out[4], 255);
}

TEST_F(ThermalColormap, scale_bar_is_opaque_over_invalid_pixels) {
  start("thermalcolormap scale-bar=true range-mode=fixed", nullptr, 160, 120);
  const auto out = run(std::vector<std::uint16_t>(160 * 120, 0));
  int opaque = 0;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 160; ++x) {
      if (x < 80) {
        EXPECT_EQ(out[4 * (y * 160 + x) + 3], 0) << x << "," << y;
      }
      if (out[4 * (y * 160 + x) + 3] == 255) ++opaque;
    }
  EXPECT_GT(opaque, 300);
}

// A 20 x 20 spot at 1600 degC on a w x h frame without readings, and the same with its 4 x 4
// core left without a reading (saturated).
struct SpotFrames {
  std::vector<std::uint16_t> spot, cored;
};
SpotFrames spot_frames(int w, int h) {
  SpotFrames f{std::vector<std::uint16_t>(static_cast<std::size_t>(w * h), 0), {}};
  for (int y = 50; y < 70; ++y)
    for (int x = 70; x < 90; ++x) f.spot[static_cast<std::size_t>(y * w + x)] = code_of(1600);
  f.cored = f.spot;
  for (int y = 58; y < 62; ++y)
    for (int x = 78; x < 82; ++x) f.cored[static_cast<std::size_t>(y * w + x)] = 0;
  return f;
}

// How many RGBA bytes of two w x h outputs differ in the label's rows (the top 24) and below.
std::pair<std::size_t, std::size_t> label_and_other_differences(const std::vector<std::uint8_t>& a,
                                                                const std::vector<std::uint8_t>& b,
                                                                int w, int h) {
  std::size_t label = 0, other = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 4; ++c) {
        const std::size_t i = static_cast<std::size_t>(4 * (y * w + x) + c);
        (y < 24 ? label : other) += a[i] != b[i];
      }
  return {label, other};
}

// The peak readout says "peak >= N degC (saturated)" where the frame's saturation meta names
// samples that left pixels without a reading, and not where every pixel still reads: the label
// differs (the same width of text would be drawn the same), nothing else does.
TEST_F(ThermalColormap, peak_readout_is_a_lower_bound_where_saturation_hid_readings) {
  const int w = 160, h_ = 120;
  start("thermalcolormap peak-marker=true range-mode=fixed", "RGBA", w, h_);
  const auto [spot, cored] = spot_frames(w, h_);
  const auto push_with_meta = [&](const std::vector<std::uint16_t>& codes, bool meta) {
    GstBuffer* in = buffer_from(codes);
    if (meta) add_saturation_meta(in, 4, cv::Rect(79, 59, 2, 2), w, h_);
    return push_pull<std::uint8_t>(h, in);
  };
  const auto plain = push_with_meta(cored, false), flagged = push_with_meta(cored, true),
             all_read = push_with_meta(spot, true), spot_plain = push_with_meta(spot, false);
  ASSERT_EQ(plain.size(), static_cast<std::size_t>(4 * w * h_));
  EXPECT_EQ(all_read, spot_plain);  // saturation that hid nothing changes nothing
  const auto [label, elsewhere] = label_and_other_differences(plain, flagged, w, h_);
  EXPECT_GT(label, 100u);  // "peak >= N degC (saturated)" against "peak N degC"
  EXPECT_EQ(elsewhere, 0u);
}

// With ratiotemp's uncertainty meta, a peak that reads carries the model's systematic interval
// ("peak 1600 degC +/-30 sys"): only the label changes. A peak that is only a lower bound
// (saturation hid readings) carries none.
TEST_F(ThermalColormap, peak_readout_carries_the_systematic_uncertainty_of_a_reading) {
  const int w = 160, h_ = 120;
  start("thermalcolormap peak-marker=true range-mode=fixed", "RGBA", w, h_);
  const auto [spot, cored] = spot_frames(w, h_);
  const auto push = [&](const std::vector<std::uint16_t>& codes, bool uncertainty, bool saturated) {
    GstBuffer* in = buffer_from(codes);
    if (uncertainty) add_uncertainty_meta(in, 500, 10, 3500, 50);  // 30 degC at 1600
    if (saturated) add_saturation_meta(in, 4, cv::Rect(79, 59, 2, 2), w, h_);
    return push_pull<std::uint8_t>(h, in);
  };
  const auto plain = push(spot, false, false), with_u = push(spot, true, false);
  ASSERT_EQ(plain.size(), static_cast<std::size_t>(4 * w * h_));
  const auto [label, elsewhere] = label_and_other_differences(plain, with_u, w, h_);
  EXPECT_GT(label, 100u);
  EXPECT_EQ(elsewhere, 0u);
  EXPECT_EQ(push(cored, true, true), push(cored, false, true));
}

// Where ratiotemp's above-range meta names pixels hotter than the model's range, the readout
// says "peak > 2000 degC (above range)" and the ring goes round them, not round the readings'
// peak.
TEST_F(ThermalColormap, peak_readout_names_the_range_end_where_pixels_are_hotter_than_it) {
  const int w = 160, h_ = 120;
  start("thermalcolormap peak-marker=true range-mode=fixed", "RGBA", w, h_);
  std::vector<std::uint16_t> codes(w * h_, 0);
  for (int y = 50; y < 70; ++y)
    for (int x = 70; x < 90; ++x) codes[y * w + x] = code_of(1600);  // read
  // (20..29, 90..99): no reading, hotter than the range
  const auto push_with_meta = [&](bool meta) {
    GstBuffer* in = buffer_from(codes);
    if (meta) add_above_range_meta(in, 100, cv::Rect(20, 90, 10, 10), w, h_, 2000);
    return push_pull<std::uint8_t>(h, in);
  };
  const auto plain = push_with_meta(false), flagged = push_with_meta(true);
  ASSERT_EQ(plain.size(), static_cast<std::size_t>(4 * w * h_));
  const auto differing = [&](const cv::Rect& r) {
    std::size_t n = 0;
    for (int y = r.y; y < r.y + r.height; ++y)
      for (int x = r.x; x < r.x + r.width; ++x)
        for (int c = 0; c < 4; ++c) {
          const std::size_t i = static_cast<std::size_t>(4 * (y * w + x) + c);
          n += plain[i] != flagged[i];
        }
    return n;
  };
  EXPECT_GT(differing(cv::Rect(0, 0, w, 24)), 100u);    // the label
  EXPECT_GT(differing(cv::Rect(10, 80, 30, 30)), 20u);  // the ring, now round the hot part
  EXPECT_GT(differing(cv::Rect(65, 45, 30, 30)), 20u);  // and no more round the readings
  EXPECT_EQ(differing(cv::Rect(100, 30, 60, 90)), 0u);  // nothing else
}

// Two spots hotter than the range: the ring goes round the larger, not between them.
TEST_F(ThermalColormap, peak_ring_goes_round_the_larger_of_two_spots_above_the_range) {
  const int w = 160, h_ = 120;
  start("thermalcolormap peak-marker=true range-mode=fixed", "RGBA", w, h_);
  const std::vector<std::uint16_t> codes(w * h_, 0);
  const cv::Rect small(140, 10, 4, 4), large(20, 90, 12, 12);
  const auto push_with_meta = [&](bool two) {
    GstBuffer* in = buffer_from(codes);
    add_above_range_meta(in, 100, large, w, h_, 2000);
    if (two) {
      auto* m = reinterpret_cast<PyrocamAboveRangeMeta*>(
          gst_buffer_get_meta(in, gst_meta_get_info("PyrocamAboveRangeMeta")->api));
      const cv::Rect both = small | large;
      m->x = both.x, m->y = both.y, m->width = both.width, m->height = both.height;
      for (int y = small.y; y < small.y + small.height; ++y)
        for (int x = small.x; x < small.x + small.width; ++x)
          m->tiles[y * 64 / h_] |= guint64{1} << (x * 64 / w);
    }
    return push_pull<std::uint8_t>(h, in);
  };
  const auto one = push_with_meta(false), two = push_with_meta(true);
  ASSERT_EQ(one.size(), static_cast<std::size_t>(4 * w * h_));
  // The ring round the large spot in both frames; where the union's centre is (80, 56), none.
  std::size_t differing = 0;
  for (std::size_t i = 0; i < one.size(); ++i) differing += one[i] != two[i];
  EXPECT_EQ(differing, 0u);
  const auto lit = [&](const std::vector<std::uint8_t>& f, const cv::Rect& r) {
    std::size_t n = 0;
    for (int y = r.y; y < r.y + r.height; ++y)
      for (int x = r.x; x < r.x + r.width; ++x)
        n += f[static_cast<std::size_t>(4 * (y * w + x) + 3)] != 0;
    return n;
  };
  EXPECT_GT(lit(two, cv::Rect(10, 80, 32, 32)), 20u);
  EXPECT_EQ(lit(two, cv::Rect(60, 40, 40, 32)), 0u);
}

// An uncertainty stream (ratiotemp output=uncertainty, or a recording of one played back) is
// refused by its tags; a temperature stream's tags pass.
TEST_F(ThermalColormap, refuses_a_stream_whose_tags_say_it_holds_uncertainties_n) {
  start("thermalcolormap", nullptr);
  const auto tagged = [](const char* quantity) {
    const std::string comment =
        std::string("pyrocam-recording; quantity=") + quantity + "; unit=0.1 K; no-reading=0";
    return gst_event_new_tag(
        gst_tag_list_new(GST_TAG_COMMENT, comment.c_str(), static_cast<const char*>(nullptr)));
  };
  gst_harness_push_event(h, tagged("temperature"));
  EXPECT_EQ(first(GST_MESSAGE_ERROR), "");
  // A sticky event is stored whatever the element says: the error says it.
  gst_harness_push_event(h, tagged("expanded-uncertainty"));
  EXPECT_NE(first(GST_MESSAGE_ERROR)
                .find("the stream holds expanded-uncertainty (its tags say so), not temperatures"),
            std::string::npos);
}

TEST_F(ThermalColormap, empty_fixed_range_warns_and_keeps_working_n) {
  start("thermalcolormap range-mode=fixed min-temperature=1500 max-temperature=1500", nullptr);
  EXPECT_EQ(run(kCodes).size(), kCodes.size() * 4);
}

TEST_F(ThermalColormap, one_code_wide_fixed_range_warns_and_finishes_the_frame_n) {
  // One ulp wide: the scale bar's tick loop used to stop advancing and grow without bound.
  start(
      "thermalcolormap range-mode=fixed min-temperature=1000 "
      "max-temperature=1000.0000000000001 scale-bar=true",
      nullptr, 160, 120);
  attach_bus();
  EXPECT_EQ(run(std::vector<std::uint16_t>(160 * 120, code_of(1000))).size(), 160u * 120u * 4u);
  GQuark domain = 0;
  int code = 0;
  const std::string warning = first(GST_MESSAGE_WARNING, &domain, &code);
  EXPECT_EQ(domain, GST_RESOURCE_ERROR);
  EXPECT_EQ(code, GST_RESOURCE_ERROR_SETTINGS);
  EXPECT_NE(warning.find("0.1 degC"), std::string::npos) << warning;
  // Another too narrow range: still a whole frame, painted with the last good range.
  GstElement* e = find_element(h, "thermalcolormap");
  g_object_set(e, "max-temperature", 1000.05, nullptr);
  gst_object_unref(e);
  EXPECT_EQ(run(std::vector<std::uint16_t>(160 * 120, code_of(1000))).size(), 160u * 120u * 4u);
}

TEST_F(ThermalColormap, rejects_a_too_short_buffer) {
  start("thermalcolormap range-mode=fixed", nullptr);
  attach_bus();
  const std::vector<std::uint16_t> short_frame(kCodes.begin(), kCodes.begin() + 5);
  EXPECT_EQ(gst_harness_push(h, buffer_from(short_frame)), GST_FLOW_ERROR);
  GQuark domain = 0;
  int code = 0;
  const std::string error = first(GST_MESSAGE_ERROR, &domain, &code);
  EXPECT_EQ(domain, GST_STREAM_ERROR);
  EXPECT_EQ(code, GST_STREAM_ERROR_FORMAT);
  EXPECT_NE(error.find("10 bytes"), std::string::npos) << error;  // got
  EXPECT_NE(error.find("16 bytes"), std::string::npos) << error;  // expected: 4x2 GRAY16_LE
  EXPECT_NE(error.find("4x2"), std::string::npos) << error;
  EXPECT_EQ(first(GST_MESSAGE_WARNING), "");  // no "not implemented" warning
}

TEST_F(ThermalColormap, survives_flush_and_eos) {
  start("thermalcolormap range-mode=fixed", nullptr);
  EXPECT_EQ(run(kCodes).size(), kCodes.size() * 4);
  push_flush(h);
  EXPECT_EQ(run(kCodes), library(kCodes, ColormapSettings{}));
  EXPECT_TRUE(eos_passes(h));
}

TEST(ThermalColormapPipeline, overlays_on_a_camera_image_with_compositor) {
  REQUIRE_ELEMENT("thermalcolormap");
  const auto r = run_pipeline(
      "compositor name=mix ! video/x-raw,format=BGRA,width=64,height=48 ! fakesink name=sink "
      "videotestsrc num-buffers=3 ! video/x-raw,width=64,height=48,framerate=10/1 ! mix. "
      "videotestsrc num-buffers=3 pattern=gradient ! "
      "video/x-raw,format=GRAY16_LE,width=64,height=48,framerate=10/1 ! "
      "thermalcolormap scale-bar=true ! mix.");
  expect_eos(r, 3);
}

TEST_F(ThermalColormap, auto_range_leaves_out_a_few_wild_pixels) {
  start("thermalcolormap range-mode=auto auto-smoothing=1 palette=grey", nullptr, 40, 25);
  // A plate at 730..740 degC with 3 wild pixels of 1000 (0.3 %) at 3000 degC.
  std::vector<std::uint16_t> codes(40 * 25);
  for (std::size_t i = 0; i < codes.size(); ++i) codes[i] = code_of(730.0 + (i % 40) / 3.9);
  for (std::size_t i : {5u, 400u, 999u}) codes[i] = code_of(3000);
  GstElement* e = find_element(h, "thermalcolormap");
  double trim = 0;
  g_object_get(e, "auto-trim", &trim, nullptr);
  EXPECT_DOUBLE_EQ(trim, 0.5);
  auto out = run(codes);
  const cv::Mat frame(25, 40, CV_16U, codes.data());
  const auto trimmed = pyrocam::trimmed_range_c(frame, 0.5);
  ASSERT_TRUE(trimmed);
  EXPECT_NEAR(trimmed->first, 730, 0.1);
  EXPECT_NEAR(trimmed->second, 740, 0.1);
  ColormapSettings s;
  s.palette = Palette::kGrey;
  s.min_c = trimmed->first;
  s.max_c = trimmed->second;
  EXPECT_EQ(out, library(codes, s));  // the plate spans the palette; the outliers clamp
  // auto-trim=0: the frame's min and max, as before.
  g_object_set(e, "auto-trim", 0.0, nullptr);
  gst_object_unref(e);
  out = run(codes);
  s.max_c = pyrocam::valid_range_c(frame)->second;
  EXPECT_NEAR(s.max_c, 3000, 0.1);
  EXPECT_EQ(out, library(codes, s));
}

}  // namespace
}  // namespace pyrocam::test
