// The matched kernel's bias on gradients and its correction (blur_bias.h), on noiseless mosaics
// of known temperature fields.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/blur_bias.h"
#include "pyrocam/runtime/frame_measurer.h"
#include "test_support.h"

namespace pyrocam {
namespace {

constexpr int kSize = 24, kCentre = 12;

struct Camera {
  std::shared_ptr<ThermalModel> model = std::make_shared<ThermalModel>();
  Locus locus;
  explicit Camera(const char* profile) {
    const CameraProfile p = load_profile_by_name(profile);
    model->camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
    locus = make_locus(model->camera, model->min_temperature_c, model->max_temperature_c, 1);
  }
  // A noiseless Bayer mosaic of the field t(x, y) (whole degrees), its brightest band at
  // `level` DN where the field is `t0`.
  template <class Field>
  cv::Mat mosaic(Field t, double t0, double level) const {
    const MosaicLayout& layout = model->profile().mosaic;
    auto row = [&](double tc) {
      return static_cast<Eigen::Index>(std::lround(tc - locus.temperature_c[0]));
    };
    const double scale = level / locus.rates.row(row(t0)).maxCoeff();
    cv::Mat m(kSize, kSize, CV_32F);
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x)
        m.at<float>(y, x) =
            static_cast<float>(scale * locus.rates(row(t(x, y)), layout.band_at(x & 1, y & 1)));
    return m;
  }
  cv::Mat read(const cv::Mat& signal, bool correct) const {
    MeasureOptions options;
    options.method = Method::kLikelihood;
    options.blur_correction = correct;
    FrameMeasurer measurer(model, options);
    cv::Mat t;
    measurer.measure_signal(signal, t);
    return t;
  }
};

// The mean error of the readings of the 7x8 pixels around the centre.
double centre_error(const cv::Mat& t, double truth_at_centre, double gx) {
  double sum = 0;
  int n = 0;
  for (int y = kCentre - 4; y < kCentre + 4; ++y)
    for (int x = kCentre - 3; x <= kCentre + 3; ++x) {
      const double truth = truth_at_centre + gx * (x - kCentre);
      if (std::isfinite(t.at<float>(y, x))) sum += t.at<float>(y, x) - truth, ++n;
    }
  EXPECT_EQ(n, 56);
  return sum / std::max(n, 1);
}

TEST(BlurBias, ARampReadsHighAndTheCorrectionTakesItOut) {
  const Camera camera("rgb-reference");
  const BlurBiasCorrection correction(*camera.model, DemosaicMethod::kAuto);
  // kappa: the sum of two bands' log slopes (about c2 / (lambda T^2) each) less 2 / T.
  EXPECT_GT(correction.kappa_per_c(1400), 0.010);
  EXPECT_LT(correction.kappa_per_c(1400), 0.025);
  EXPECT_GT(correction.kappa_per_c(1400), correction.kappa_per_c(2400));
  for (const double g : {30.0, 60.0}) {  // degC per pixel along x, at 2000 degC
    const cv::Mat signal =
        camera.mosaic([&](int x, int) { return 2000 + g * (x - kCentre); }, 2000, 200);
    const double predicted = correction.bias_c(2000, g, 0);
    const double before = centre_error(camera.read(signal, false), 2000, g);
    const double after = centre_error(camera.read(signal, true), 2000, g);
    std::printf("g %g predicted %.2f before %.2f after %.2f\n", g, predicted, before, after);
    // Measured: g = 30: +4.05 before (predicted 4.20), -0.12 after; g = 60: +16.11 (16.82), -0.14.
    EXPECT_NEAR(before, predicted, 0.2 * predicted) << "g " << g;
    EXPECT_LT(std::abs(after), 0.1 * before) << "g " << g;
  }
}

TEST(BlurBias, AUniformSurfaceIsLeftAsItIs) {
  const Camera camera("rgb-reference");
  const cv::Mat signal = camera.mosaic([](int, int) { return 1500; }, 1500, 100);
  const cv::Mat before = camera.read(signal, false), after = camera.read(signal, true);
  // As 0.1 K codes, as the measurer corrects them (and ratiotemp).
  EXPECT_EQ(cv::norm(encode_decikelvin(before), encode_decikelvin(after), cv::NORM_INF), 0.0);
}

TEST(BlurBias, CodesAreCorrectedAsTemperatures) {
  const Camera camera("rgb-reference");
  const BlurBiasCorrection correction(*camera.model, DemosaicMethod::kMatched);
  cv::Mat t(5, 6, CV_32F);
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) t.at<float>(y, x) = 1500 + 80.f * x + 20.f * y;
  t.at<float>(2, 3) = NAN;  // no reading: stays so, and its neighbours take one-sided differences
  cv::Mat codes = encode_decikelvin(t), from_codes = decode_decikelvin(codes);
  correction.apply_codes(codes);
  correction.apply(from_codes);
  EXPECT_EQ(cv::norm(codes, encode_decikelvin(from_codes), cv::NORM_INF), 0.0);
  EXPECT_EQ(codes.at<std::uint16_t>(2, 3), kNoReadingCode);
  // Away from the hole and the borders the gradient is (80, 20): the bias of the formula, within
  // half a code (0.05) and the float rounding of the degrees.
  EXPECT_NEAR(from_codes.at<float>(1, 1), 1600 - correction.bias_c(1600, 80, 20), 0.06);
}

TEST(BlurBias, OtherDemosaickingIsRefused) {
  const Camera camera("rgb-reference");
  EXPECT_THROW(BlurBiasCorrection(*camera.model, DemosaicMethod::kBilinear), InputError);
  MeasureOptions options;
  options.demosaic = DemosaicMethod::kBinCells;
  options.blur_correction = true;
  EXPECT_THROW(FrameMeasurer(camera.model, options), InputError);
  cv::Mat wrong(3, 3, CV_32S, cv::Scalar(0));
  EXPECT_THROW(BlurBiasCorrection(*camera.model, DemosaicMethod::kAuto).apply(wrong), InputError);
}

}  // namespace
}  // namespace pyrocam
