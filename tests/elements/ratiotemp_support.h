// ratiotemp element tests' shared pieces: the test models, graybody band planes, the
// library's answer to compare with, and the RatioTemp fixture (a harness around a parsed
// chain with its bus). Used by test_ratiotemp.cpp and test_ratiotemp_stats.cpp.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam-meta.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/model.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "test_support.h"

namespace pyrocam::test {

inline std::string rgb_model_path() { return test_model_path("test-model-rgb.json"); }
inline std::string nir_model_path() { return test_model_path("test-model-nir5x5.json"); }

// The test models, loaded once per binary.
inline const std::shared_ptr<const ThermalModel>& rgb_model() {
  static const auto m = std::make_shared<const ThermalModel>(load_model(rgb_model_path()));
  return m;
}
inline const std::shared_ptr<const ThermalModel>& nir_model() {
  static const auto m = std::make_shared<const ThermalModel>(load_model(nir_model_path()));
  return m;
}

// What the element's auto method is for a model (its documented rule): the lookup table for
// two-ratio models when it gives the network's answer on the model's locus (within 1 degC, and
// reading where the network does at all but 1 % of the samples), else likelihood.
inline bool lut_passes_its_check(const std::shared_ptr<const ThermalModel>& m) {
  const auto lut = make_estimator(m, Method::kLut);
  const auto mlp = make_estimator(m, Method::kMlp);
  const LocusAgreement a = compare_on_locus(*m, *lut, *mlp);
  return a.max_difference_c <= 1.0 && a.validity_differs * 100 <= a.samples;
}
inline Method rgb_auto_method() {
  static const Method m = lut_passes_its_check(rgb_model()) ? Method::kLut : Method::kLikelihood;
  return m;
}

// Band planes (plane after plane) of a graybody whose temperature runs from t0 to t1 over the
// pixels, brightest band at `peak` DN, with a small per-pixel, per-band wobble so that the
// ratios leave the locus a little as noisy pixels do.
inline std::vector<float> graybody_planes(const ThermalModel& m, int w, int h, double t0, double t1,
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

inline std::string bands_caps(int bands, const char* layout, int w, int h) {
  return "video/x-pyrocam-bands,format=F32LE,bands=" + std::to_string(bands) +
         ",width=" + std::to_string(w) + ",height=" + std::to_string(h) +
         ",framerate=30/1,layout=" + layout;
}

inline std::vector<cv::Mat> plane_views(const std::vector<float>& planes, int bands, int w, int h) {
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
inline LibraryResult library(const std::shared_ptr<const ThermalModel>& model, Method method,
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
inline LibraryResult library(const std::shared_ptr<const ThermalModel>& m, Method method,
                             const std::vector<float>& planes, int w, int h,
                             bool uncertainty = false, bool partial = false) {
  return library(m, method, plane_views(planes, m->profile().band_count(), w, h), uncertainty,
                 partial);
}

inline std::vector<std::uint16_t> codes_of(const cv::Mat& codes) {
  std::vector<std::uint16_t> v;
  for (int y = 0; y < codes.rows; ++y)
    v.insert(v.end(), codes.ptr<std::uint16_t>(y), codes.ptr<std::uint16_t>(y) + codes.cols);
  return v;
}
inline std::vector<std::uint16_t> library_codes(const std::shared_ptr<const ThermalModel>& m,
                                                Method method, const std::vector<float>& planes,
                                                int w, int h, bool partial = false) {
  return codes_of(encode_decikelvin(library(m, method, planes, w, h, false, partial).t));
}

// GRAY16_LE pixels of an output buffer, without the row padding (stride GST_ROUND_UP_4(2 w)).
inline std::vector<std::uint16_t> gray16_of(GstBuffer* buffer, int w, int h) {
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

// A raw 8x8 RGGB frame of a graybody at t_c whose brightest band is 120 DN above the dark
// level of 50, with a dim corner.
inline std::vector<std::uint8_t> raw_bayer_frame(const ThermalModel& m, double t_c) {
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
  bool last_gap = false;  // whether run's output frame was flagged GAP (no image)
  // The pixels its PyrocamAboveRangeMeta counts (G_MAXUINT64: none attached).
  guint64 last_above_range = G_MAXUINT64;
  // Its PyrocamUncertaintyMeta's temperatures and expanded uncertainties (empty: none attached).
  std::vector<double> last_u_temperature_c, last_u_expanded_c;
  // Pushes one frame of band planes (or raw bytes) and returns the output codes.
  template <typename T>
  std::vector<std::uint16_t> run(const std::vector<T>& input, int w, int height,
                                 GstClockTime pts = GST_CLOCK_TIME_NONE) {
    GstBuffer* out = push_pull_buffer(h, with_pts(buffer_from(input), pts));
    if (!out) return {};
    last_gap = GST_BUFFER_FLAG_IS_SET(out, GST_BUFFER_FLAG_GAP);
    // By the API's registered name: the tests do not link the plugin.
    const GType above_api = g_type_from_name("PyrocamAboveRangeMetaAPI");
    const auto* above =
        above_api
            ? reinterpret_cast<const PyrocamAboveRangeMeta*>(gst_buffer_get_meta(out, above_api))
            : nullptr;
    last_above_range = above ? above->pixels : G_MAXUINT64;
    const GType u_api = g_type_from_name("PyrocamUncertaintyMetaAPI");
    const auto* u =
        u_api ? reinterpret_cast<const PyrocamUncertaintyMeta*>(gst_buffer_get_meta(out, u_api))
              : nullptr;
    last_u_temperature_c.assign(u ? u->temperature_c : nullptr,
                                u ? u->temperature_c + u->count : nullptr);
    last_u_expanded_c.assign(u ? u->expanded_u_c : nullptr,
                             u ? u->expanded_u_c + u->count : nullptr);
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

}  // namespace pyrocam::test
