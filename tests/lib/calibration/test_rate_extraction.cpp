// Rate extraction of reference sources beyond the furnace (rows of kind reference): their slopes
// carry the band ratios of their true temperature, whatever their unknown scale, and a
// reference that cannot give two bands is refused, naming its manifest line.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>

#include "pyrocam/calibration/calibrate.h"
#include "pyrocam/calibration/rate_extraction.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/spectrum.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

using test::ScratchDir;

template <typename F>
std::string error_of(const F& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(SimulatedReferences, slopes_carry_the_band_ratios_of_the_true_temperature) {
  ScratchDir dir("references");
  const CameraProfile profile = load_profile_by_name("rgb-reference");
  Simulator camera(profile, UnitPerturbation{"typical", 4});
  CampaignSettings s;
  s.temperatures_c = {900, 1000, 1100};
  s.frames_per_setting = 2;
  s.width = s.height = 48;
  s.roi_area_px = 900;
  s.reference_temperatures_c = {1324, 1738, 2474};
  write_furnace_campaign(dir.path(), camera, s);

  const RateTable rt = extract_rates(Dataset::open(dir.path()), profile);
  // The furnace table is the furnace's alone.
  EXPECT_EQ(rt.temperatures_c, (std::vector<double>{900, 1000, 1100}));
  EXPECT_EQ(rt.settings.size(), 90u);
  EXPECT_EQ(rt.rates().rows(), 3);

  const CsvTable truth = read_csv_table(dir / "furnace-truth.csv");
  const auto& nominal = truth.columns[truth.column_index("nominal_c")];
  const auto& true_c = truth.columns[truth.column_index("true_c")];
  ASSERT_EQ(nominal.size(), 6u);  // the furnace steps, then the references
  const std::vector<ReferenceRates> refs = rt.reference_rates();
  ASSERT_EQ(refs.size(), 3u);
  ASSERT_EQ(rt.references.size(), 3u);
  for (std::size_t i = 0; i < refs.size(); ++i) {
    const ReferenceRates& r = refs[i];
    SCOPED_TRACE(r.name);
    EXPECT_DOUBLE_EQ(r.temperature_c, nominal[3 + i]);
    EXPECT_DOUBLE_EQ(r.temperature_uncertainty_c, 0.5);
    std::ostringstream name;
    name << "reference " << nominal[3 + i] << " degC (manifest line " << rt.references[i].line
         << ")";
    EXPECT_EQ(r.name, name.str());
    EXPECT_EQ(rt.references[i].settings.size(), 30u);
    // The true temperature is within a few standard uncertainties of the nominal one.
    EXPECT_LT(std::abs(true_c[3 + i] - nominal[3 + i]), 5 * 0.5);
    // Tolerance: with this ROI and these frames each furnace slope is within 1 % of the true
    // rate (test_calibrate's slopes_recover_the_true_signal_rates), so a ratio of two slopes is
    // within 2 %; the unknown scale cancels in the ratio, and the true temperature is the one
    // rendered, so nothing else enters.
    const Eigen::VectorXd expected = camera.mean_signal_dn(true_c[3 + i], 1.0);
    ASSERT_EQ(r.rates.size(), 3);
    for (int b = 0; b < 3; ++b) {
      ASSERT_TRUE(std::isfinite(r.rates[b])) << profile.band_names[b];
      EXPECT_GE(rt.references[i].fits[b].points, 3) << profile.band_names[b];
      EXPECT_GT(rt.references[i].fits[b].r_squared, 0.999) << profile.band_names[b];
    }
    for (int b = 0; b < 3; ++b)
      for (int c = b + 1; c < 3; ++c)
        EXPECT_NEAR((r.rates[b] / r.rates[c]) / (expected[b] / expected[c]), 1.0, 0.02)
            << profile.band_names[b] << "/" << profile.band_names[c];
    // The scale the reference was rendered with is unknown but between 0.05 and 0.5.
    const double scale = r.rates[1] / (expected[1] * 1e6);
    EXPECT_GT(scale, 0.045);
    EXPECT_LT(scale, 0.55);
  }
}

// A hand-made 8x8 RGGB dataset of exact values: dark 10 DN, furnace frames at 900 and 1000 degC,
// and one reference at 1738 degC whose net value per band and exposure the test chooses.
class HandMadeReference : public ::testing::Test {
 protected:
  using NetFn = std::function<double(int band, double exposure_us, int x, int y)>;
  void write(const NetFn& reference_net) {
    const CameraProfile& p = profile;
    auto image = [&](const std::function<double(int, int, int)>& value) {
      cv::Mat m(8, 8, CV_8U);
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
          m.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(
              std::lround(std::clamp(value(p.mosaic.band_at(x, y), x, y), 0., 255.)));
      return m;
    };
    write_raw_image(dir / "roi.png", cv::Mat(8, 8, CV_8U, cv::Scalar(255)));
    std::vector<ManifestRow> rows;
    const double rate[3] = {0.2, 0.1, 0.05};  // DN/us at 900 degC
    for (double e : exposures) {
      const std::string tag = std::to_string(static_cast<int>(e));
      rows.push_back({"d" + tag + ".pgm", FrameKind::kDark, 20, e});
      write_raw_image(dir / rows.back().file, image([](int, int, int) { return 10.0; }));
      for (double t : {900.0, 1000.0}) {
        rows.push_back({"f" + std::to_string(static_cast<int>(t)) + "_" + tag + ".pgm",
                        FrameKind::kFrame, t, e});
        const double gain = t > 950 ? 1.5 : 1.0;
        write_raw_image(dir / rows.back().file,
                        image([&](int b, int, int) { return 10 + gain * rate[b] * e; }));
      }
      rows.push_back({"r" + tag + ".pgm", FrameKind::kReference, 1738, e, 0.3});
      write_raw_image(dir / rows.back().file,
                      image([&](int b, int x, int y) { return 10 + reference_net(b, e, x, y); }));
    }
    write_manifest(dir / "manifest.csv", rows);
  }
  // The manifest line of the first reference row.
  int reference_line() const {
    for (const auto& r : read_manifest(dir / "manifest.csv"))
      if (r.kind == FrameKind::kReference) return r.line;
    return -1;
  }
  std::string extraction_error() {
    return error_of([&] { extract_rates(Dataset::open(dir.path()), profile); });
  }

  ScratchDir dir{"handmade"};
  const CameraProfile profile = load_profile_by_name("rgb-reference");
  const std::vector<double> exposures{100, 200, 400};
};

TEST_F(HandMadeReference, gives_exact_slopes_and_no_rate_for_a_dim_band) {
  // R and G usable at every exposure, B dim (net < 10 DN) at every one.
  write([](int b, double e, int, int) { return (b == 0 ? 0.2 : b == 1 ? 0.12 : 0.01) * e; });
  const RateTable rt = extract_rates(Dataset::open(dir.path()), profile);
  ASSERT_EQ(rt.references.size(), 1u);
  const ReferenceSweep& ref = rt.references[0];
  EXPECT_EQ(ref.line, reference_line());
  EXPECT_EQ(ref.settings.size(), 3u);
  EXPECT_EQ(ref.status[0][2], PointStatus::kDim);
  const std::vector<ReferenceRates> rr = rt.reference_rates();
  ASSERT_EQ(rr.size(), 1u);
  EXPECT_EQ(rr[0].name,
            "reference 1738 degC (manifest line " + std::to_string(reference_line()) + ")");
  EXPECT_DOUBLE_EQ(rr[0].temperature_uncertainty_c, 0.3);
  // 8-bit rounding: 0.12 DN/us x 100 us = 12 DN exactly; 0.2 x 100 = 20.
  EXPECT_NEAR(rr[0].rates[0], 0.2e6, 1e-6 * 0.2e6);
  EXPECT_NEAR(rr[0].rates[1], 0.12e6, 1e-6 * 0.12e6);
  EXPECT_TRUE(std::isnan(rr[0].rates[2]));
  bool warned = false;
  for (const auto& w : rt.warnings)
    warned = warned || w.find(rr[0].name + " band B: 0 usable point(s)") != std::string::npos;
  EXPECT_TRUE(warned);
  // The furnace rates do not see the reference.
  EXPECT_EQ(rt.temperatures_c, (std::vector<double>{900, 1000}));
  EXPECT_NEAR(rt.rates()(0, 0), 0.2e6, 1e-6 * 0.2e6);
}

TEST_F(HandMadeReference, rejects_a_reference_dim_at_every_exposure_n) {
  write([](int, double e, int, int) { return 0.01 * e; });
  const std::string e = extraction_error();
  EXPECT_NE(e.find("manifest.csv: reference 1738 degC (manifest line " +
                   std::to_string(reference_line()) +
                   "): every band is dim or saturated at every one of its 3 exposure(s) "
                   "(100-400 us)"),
            std::string::npos)
      << e;
}

TEST_F(HandMadeReference, rejects_a_reference_saturated_at_every_exposure_n) {
  write([](int, double, int, int) { return 250.0; });
  const std::string e = extraction_error();
  EXPECT_NE(e.find("(manifest line " + std::to_string(reference_line()) +
                   "): every band is dim or saturated"),
            std::string::npos)
      << e;
}

TEST_F(HandMadeReference, rejects_a_reference_with_one_usable_band_n) {
  write([](int b, double e, int, int) { return (b == 0 ? 0.2 : 0.01) * e; });
  const std::string e = extraction_error();
  EXPECT_NE(e.find("(manifest line " + std::to_string(reference_line()) +
                   "): 1 band(s) (R) with 2 or more usable exposures"),
            std::string::npos)
      << e;
}

TEST_F(HandMadeReference, reads_references_through_reference_roi_png) {
  // The source fills the top-left 4x4 pixels; around it the image is saturated.
  write([](int b, double e, int x, int y) {
    return x < 4 && y < 4 ? (b == 0 ? 0.2 : b == 1 ? 0.12 : 0.06) * e : 250.0;
  });
  EXPECT_NE(extraction_error().find("every band is dim or saturated"), std::string::npos);
  cv::Mat mask = cv::Mat::zeros(8, 8, CV_8U);
  mask(cv::Rect(0, 0, 4, 4)) = 255;
  write_raw_image(dir / kReferenceRoiFile, mask);
  const RateTable rt = extract_rates(Dataset::open(dir.path()), profile);
  ASSERT_EQ(rt.references.size(), 1u);
  EXPECT_NEAR(rt.references[0].fits[2].rate_dn_per_s, 0.06e6, 1e-6 * 0.06e6);
  EXPECT_NEAR(rt.rates()(1, 0), 0.3e6, 1e-6 * 0.3e6);  // the furnace keeps roi.png
  // A reference ROI without a pixel of some band cannot give that band's mean.
  mask = cv::Mat::zeros(8, 8, CV_8U);
  mask.at<std::uint8_t>(0, 0) = 255;
  write_raw_image(dir / kReferenceRoiFile, mask);
  const std::string e = extraction_error();
  EXPECT_NE(e.find("reference-roi.png: the reference ROI holds no pixel of band"),
            std::string::npos)
      << e;
}

TEST_F(HandMadeReference, calibrate_rejects_a_reference_outside_the_models_range_n) {
  write([](int b, double e, int, int) { return (b == 0 ? 0.2 : 0.12) * e; });
  CalibrationOptions options;
  options.max_temperature_c = 1500;
  const std::string e = error_of([&] { calibrate(Dataset::open(dir.path()), profile, options); });
  EXPECT_NE(e.find("manifest.csv line " + std::to_string(reference_line()) +
                   ": reference at 1738 degC is outside the model's range 500-1500 degC"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace pyrocam
