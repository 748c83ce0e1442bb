// The curvature check (curvature_check.h): no reading where the matched kernels' blur of a
// curved temperature field alone would move it by more than the limit, on noiseless and noisy
// mosaics of known fields.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <random>

#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/curvature_check.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "test_support.h"

namespace pyrocam {
namespace {

constexpr int kSize = 24, kCentre = 12;

struct Scene {
  std::shared_ptr<ThermalModel> model = std::make_shared<ThermalModel>();
  Locus locus;
  cv::Mat signal, codes;  // the mosaic and the true temperatures' codes (0 below 700 degC)
  Scene() {
    const CameraProfile p = load_profile_by_name("rgb-reference");
    model->camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
    locus = make_locus(model->camera, model->min_temperature_c, model->max_temperature_c, 1);
  }
  // The field t(x, y), its brightest band at 150 DN at the centre, plus Gaussian noise of
  // `noise_dn` (seeded).
  template <class Field>
  void film(Field t, double noise_dn = 0) {
    const MosaicLayout& layout = model->profile().mosaic;
    // The locus' row at tc; below its first temperature (the cold background) there is no light.
    const auto rates = [&](double tc) {
      return locus.rates.row(std::clamp<long>(std::lround(tc - locus.temperature_c[0]), 0,
                                              static_cast<long>(locus.size()) - 1));
    };
    const double scale = 150 / rates(t(kCentre, kCentre)).maxCoeff();
    std::mt19937 rng(7);
    std::normal_distribution<double> normal(0, 1);
    signal.create(kSize, kSize, CV_32F);
    codes.create(kSize, kSize, CV_16U);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const double tc = t(x, y);
        const double light = tc >= locus.temperature_c[0] ? rates(tc)(layout.band_at(x, y)) : 0.0;
        signal.at<float>(y, x) = static_cast<float>(scale * light + noise_dn * normal(rng));
        codes.at<std::uint16_t>(y, x) = tc >= 700 ? temperature_code(tc) : kNoReadingCode;
      }
  }
  // The log-signal Laplacian of the centre's own band from its samples 2 pixels away.
  double centre_laplacian() const {
    const auto s = [&](int dx, int dy) {
      return std::log(signal.at<float>(kCentre + dy, kCentre + dx));
    };
    return (s(2, 0) + s(-2, 0) + s(0, 2) + s(0, -2) - 4 * s(0, 0)) / 4;
  }
};

// A paraboloid T = peak - a r^2 about the centre pixel: Laplacian -4a, so the kernels (variance
// 1 pixel^2 along each axis) blur the peak's reading by -2a.
auto paraboloid(double peak, double a) {
  return [=](int x, int y) {
    const double r2 = (x - kCentre) * (x - kCentre) + (y - kCentre) * (y - kCentre);
    return std::max(20.0, peak - a * r2);
  };
}

TEST(CurvatureCheck, AHotSpotAFewPixelsAcrossHasNoReadingAtItsPeak) {
  // A spot 5 pixels across at 2000 degC (1300 degC at 2.5 pixels): a = 112 degC / pixel^2, a
  // share of -224 degC; the log signal's own curvature adds about a fifth (ln m is concave).
  Scene scene;
  scene.film(paraboloid(2000, 112));
  const CurvatureCheck check(*scene.model, scene.model->profile().mosaic);
  const int band = scene.model->profile().mosaic.band_at(kCentre, kCentre);
  const double share = check.share_c(scene.codes.at<std::uint16_t>(kCentre, kCentre), band,
                                     scene.centre_laplacian());
  EXPECT_NEAR(share, -224, 0.3 * 224);
  cv::Mat codes = scene.codes.clone();
  check.apply_codes(scene.signal, codes);
  EXPECT_EQ(codes.at<std::uint16_t>(kCentre, kCentre), kNoReadingCode);
  // The float form takes the same pixels.
  cv::Mat t = decode_decikelvin(scene.codes);
  check.apply(scene.signal, t);
  EXPECT_EQ(cv::norm(encode_decikelvin(t), codes, cv::NORM_INF), 0.0);
}

TEST(CurvatureCheck, SmoothFieldsKeepEveryReading) {
  Scene scene;
  const MosaicLayout& layout = scene.model->profile().mosaic;
  const CurvatureCheck check(*scene.model, layout);
  // A pool's gentle peak (a = 10: a share of about -20 degC) keeps its readings.
  scene.film(paraboloid(2000, 10));
  EXPECT_NEAR(check.share_c(scene.codes.at<std::uint16_t>(kCentre, kCentre),
                            layout.band_at(kCentre, kCentre), scene.centre_laplacian()),
              -20, 0.3 * 20);
  cv::Mat codes = scene.codes.clone();
  check.apply_codes(scene.signal, codes);
  EXPECT_EQ(cv::norm(codes, scene.codes, cv::NORM_INF), 0.0);
  // A steep ramp (60 degC a pixel, which the blur correction is for) and a noisy plate: the
  // noise of 1 DN moves the share by about 0.5 degC rms at 150 DN and 5 at 15 DN (the dimmest
  // band at 1000 degC), against a limit of 100 (over 20 standard deviations).
  for (const double t0 : {1000.0, 2000.0}) {
    scene.film([&](int x, int) { return t0 + 60.0 * (x - kCentre); });
    codes = scene.codes.clone();
    check.apply_codes(scene.signal, codes);
    EXPECT_EQ(cv::norm(codes, scene.codes, cv::NORM_INF), 0.0) << "ramp at " << t0;
    scene.film([&](int, int) { return t0; }, 1.0);
    codes = scene.codes.clone();
    check.apply_codes(scene.signal, codes);
    EXPECT_EQ(cv::norm(codes, scene.codes, cv::NORM_INF), 0.0) << "plate at " << t0;
  }
}

// measure (FrameMeasurer) takes the check on the fused path's demosaicking: a Gaussian spot
// (2000 degC, 3 pixels rms: a share of about -240 degC), whose peak the ratio reads about 420
// degC low, has no reading there.
TEST(CurvatureCheck, TheMeasurerAppliesIt) {
  Scene scene;
  scene.film([](int x, int y) {
    const double r2 = (x - kCentre) * (x - kCentre) + (y - kCentre) * (y - kCentre);
    return 20 + 1980 * std::exp(-r2 / 18);
  });

  // The spot's blue band is below the dim threshold (its brightest band is at 150 DN): read from
  // any two bands, so that what takes the reading is the curvature and not the dim band.
  MeasureOptions options;
  options.method = Method::kLikelihood;
  options.allow_partial = true;
  FrameMeasurer measurer(scene.model, options);
  cv::Mat t;
  measurer.measure_signal(scene.signal, t);
  EXPECT_TRUE(std::isnan(t.at<float>(kCentre, kCentre))) << t.at<float>(kCentre, kCentre);
  // Off the fused path (a footprint check that marks nothing) the same kernels read it, wild.
  options.footprint_spread = 1e6;
  FrameMeasurer planes(scene.model, options);
  planes.measure_signal(scene.signal, t);
  EXPECT_LT(t.at<float>(kCentre, kCentre), 2000 - 150);
}

TEST(CurvatureCheck, ASnapshotMosaicOrOtherTypesAreRefused) {
  const std::shared_ptr<ThermalModel> model = std::make_shared<ThermalModel>();
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  model->camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  EXPECT_THROW(CurvatureCheck(*model, p.mosaic), InputError);
  Scene scene;
  const CurvatureCheck check(*scene.model, scene.model->profile().mosaic);
  cv::Mat wrong(4, 4, CV_32S, cv::Scalar(0)), codes(4, 4, CV_16U, cv::Scalar(0));
  EXPECT_THROW(check.apply_codes(wrong, codes), InputError);
  EXPECT_THROW(check.apply(cv::Mat(4, 4, CV_32F, cv::Scalar(1)), wrong), InputError);
}

}  // namespace
}  // namespace pyrocam
