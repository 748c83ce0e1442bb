// Noisy copies of the locus (what single pixels read) and the network trained on them besides the
// noise-free locus: its readings of noisy pixels against the truth and the likelihood fit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <numeric>
#include <vector>

#include "pyrocam/calibration/noisy_locus.h"

namespace pyrocam {
namespace {

// A shipped camera as its datasheet describes it; no network.
ThermalModel datasheet_model(const std::string& profile_name) {
  ThermalModel m;
  const CameraProfile p = load_profile_by_name(profile_name);
  m.camera = CameraModel{p, p.system_qe(), Eigen::VectorXd::Ones(p.band_count())};
  return m;
}

std::vector<Eigen::Index> every_row(const Locus& locus) {
  std::vector<Eigen::Index> rows(static_cast<std::size_t>(locus.size()));
  std::iota(rows.begin(), rows.end(), 0);
  return rows;
}

double median(std::vector<double> v) {
  const auto middle = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), middle, v.end());
  return *middle;
}

TEST(NoisyLocus, without_noise_copies_are_the_locus_and_read_its_temperature) {
  const ThermalModel m = datasheet_model("nir5x5-reference");
  const Locus locus = make_locus(m.camera, 500, 3500, 100);
  NoisyLocusOptions options;
  options.copies = 2;
  options.max_noise_scale = 0;
  const NoisyLocus noisy(m, locus, options);
  Eigen::VectorXd drawn_at;
  const MlpSamples s = noisy.sample(every_row(locus), 1, &drawn_at);
  ASSERT_EQ(s.targets.size(), 2 * locus.size()) << "every 5x5 locus point fits the window";
  for (Eigen::Index i = 0; i < s.targets.size(); ++i) {
    const Eigen::Index row = i / 2;
    EXPECT_EQ(drawn_at[i], locus.temperature_c[row]);
    EXPECT_TRUE(s.inputs.row(i).isApprox(locus.ratios.row(row), 1e-12)) << i;
    // The likelihood fit's target: the locus temperature (its 1 degC grid and parabola).
    EXPECT_NEAR(s.targets[i], locus.temperature_c[row], 0.05) << i;
  }
}

TEST(NoisyLocus, copies_are_seeded_inside_the_window_and_scatter_like_single_pixels) {
  const ThermalModel m = datasheet_model("rgb-reference");
  const Locus locus = make_locus(m.camera, 1000, 1000, 1);
  NoisyLocusOptions options;
  options.copies = 400;
  options.min_noise_scale = options.max_noise_scale = 1;
  const NoisyLocus noisy(m, locus, options);
  Eigen::VectorXd drawn_at;
  const MlpSamples a = noisy.sample({0}, 7, &drawn_at), b = noisy.sample({0}, 7),
                   c = noisy.sample({0}, 8);
  ASSERT_EQ(a.targets.size(), 400);
  EXPECT_TRUE(a.inputs == b.inputs && a.targets == b.targets) << "same seed, same copies";
  EXPECT_FALSE(a.inputs == c.inputs);
  EXPECT_TRUE((drawn_at.array() == 1000).all());
  // Single 8-bit pixels at 20-170 DN scatter their readings by tens of degrees at 1000 degC (the
  // likelihood fit of the measured scenes: 13-20 degC rms per pixel); the fit is unbiased.
  const Eigen::ArrayXd error = a.targets.array() - 1000;
  const double rms = std::sqrt(error.square().mean());
  EXPECT_GT(rms, 5);
  EXPECT_LT(rms, 60);
  // The median of 400 draws scatters by 1.25 sd / sqrt(400) (normal errors): 4.5 of those,
  // P = 7e-6 for any seed.
  EXPECT_LT(std::abs(median(std::vector<double>(error.data(), error.data() + error.size()))),
            4.5 * 1.25 * rms / std::sqrt(400.0));
  // The copies' ratios leave the locus: R/G and B/G vary independently.
  const Eigen::ArrayXd log_r = a.inputs.col(0).array().log(), log_b = a.inputs.col(1).array().log();
  const double correlation =
      ((log_r - log_r.mean()) * (log_b - log_b.mean())).mean() /
      std::sqrt((log_r - log_r.mean()).square().mean() * (log_b - log_b.mean()).square().mean());
  EXPECT_LT(std::abs(correlation), 0.9);
}

TEST(NoisyLocus, gives_no_copies_where_no_exposure_fits_every_band_in_the_window) {
  // A sample whose blue is 20 times dimmer than its red (the shipped colour camera's gains keep
  // its bands within a factor 2.2 at 500 degC) has no exposure with every band inside 20-170 DN:
  // the estimators read no such pixel, and no copy is made. The other sample still gets its own.
  const ThermalModel m = datasheet_model("rgb-reference");
  Locus locus = make_locus(m.camera, 1000, 1001, 1);
  locus.rates(0, 2) = locus.rates(0, 0) / 20;
  const Eigen::VectorXd rates = locus.rates.row(0).transpose();
  const CameraProfile& p = m.profile();
  ASSERT_GT(
      rates.maxCoeff() / rates.minCoeff(),
      (p.thresholds.inference_saturation_dn - p.dark_offset_dn) / p.thresholds.inference_dim_dn);
  const NoisyLocus noisy(m, locus, NoisyLocusOptions{});
  EXPECT_EQ(noisy.sample({0}, 1).targets.size(), 0);
  EXPECT_EQ(noisy.sample({1}, 1).targets.size(), NoisyLocusOptions{}.copies);
}

// Median error against the truth and rms difference from the likelihood fit of a network's
// readings of single-pixel copies drawn at one locus temperature; the fit's own rms error.
struct PixelReadings {
  double median_error = 0, rms_from_fit = 0, fit_rms_error = 0, fit_median_error = 0;
};

PixelReadings read_pixels(const Mlp& model, const NoisyLocus& pixels, Eigen::Index row,
                          double truth_c) {
  const MlpSamples s = pixels.sample({row}, 99);
  const Eigen::VectorXd reading = model.predict(s.inputs);
  std::vector<double> errors, fit_errors;
  double from_fit = 0, fit = 0;
  for (Eigen::Index i = 0; i < reading.size(); ++i) {
    errors.push_back(reading[i] - truth_c);
    fit_errors.push_back(s.targets[i] - truth_c);
    from_fit += (reading[i] - s.targets[i]) * (reading[i] - s.targets[i]);
    fit += (s.targets[i] - truth_c) * (s.targets[i] - truth_c);
  }
  const auto n = static_cast<double>(reading.size());
  return {median(errors), std::sqrt(from_fit / n), std::sqrt(fit / n), median(fit_errors)};
}

TEST(NoisyLocus, network_trained_on_copies_reads_noisy_5x5_pixels_as_the_likelihood_fit) {
  // The mechanism at a small scale (about a second): the 5x5 camera's 25 ratios, its locus every
  // 10 degC, a small network. Pixel noise leaves the one-dimensional locus in 24 directions; a
  // network fitted to the locus alone answers there whatever its fit left, one trained on noisy
  // copies as well reads them as the likelihood fit does.
  const ThermalModel m = datasheet_model("nir5x5-reference");
  const Locus locus = make_locus(m.camera, 500, 3500, 10);
  NoisyLocusOptions copies;
  copies.copies = 4;
  const NoisyLocus noisy(m, locus, copies);
  MlpTrainingOptions options;
  options.hidden = {64, 48, 32};
  options.epochs = 60;
  options.polish_iterations = 400;
  options.augmented_weight = 1;
  options.augment = [&noisy](const std::vector<Eigen::Index>& rows, std::uint64_t seed) {
    return noisy.sample(rows, seed);
  };
  const Mlp trained = Mlp::train(locus.ratios, locus.temperature_c, options);
  options.augment = nullptr;
  const Mlp locus_only = Mlp::train(locus.ratios, locus.temperature_c, options);

  NoisyLocusOptions single_pixels;
  single_pixels.copies = 200;
  single_pixels.min_noise_scale = single_pixels.max_noise_scale = 1;
  const NoisyLocus pixels(m, locus, single_pixels);
  for (const double t : {800.0, 1500.0, 2200.0, 3000.0}) {
    const auto row = static_cast<Eigen::Index>(std::lround((t - 500) / 10));
    const PixelReadings with = read_pixels(trained, pixels, row, t);
    const PixelReadings without = read_pixels(locus_only, pixels, row, t);
    std::cout << t << " degC: likelihood fit: rms error " << with.fit_rms_error << ", median "
              << with.fit_median_error << " degC; network with copies: median error "
              << with.median_error << ", rms from the fit " << with.rms_from_fit
              << " degC; locus only: " << without.median_error << ", " << without.rms_from_fit
              << " degC\n";
    // Single readings follow the fit (measured: within 2-3.5 degC rms of it where the fit
    // scatters by 8-51 degC) and the region's median reading is the fit's; the locus-only
    // network scatters 5 times as much as the fit itself.
    EXPECT_LT(with.rms_from_fit, 0.35 * with.fit_rms_error) << t;
    EXPECT_LT(with.rms_from_fit, 0.1 * without.rms_from_fit) << t;
    EXPECT_LT(std::abs(with.median_error - with.fit_median_error), 0.1 * with.fit_rms_error + 1)
        << t;
  }
  // The locus is still fitted.
  const Eigen::VectorXd error = trained.predict(locus.ratios) - locus.temperature_c;
  EXPECT_LT(error.cwiseAbs().maxCoeff(), 5);
}

TEST(NoisyLocus, rejects_bad_options_n) {
  const ThermalModel m = datasheet_model("rgb-reference");
  const Locus locus = make_locus(m.camera, 500, 3500, 100);
  NoisyLocusOptions options;
  options.copies = -1;
  EXPECT_THROW(NoisyLocus(m, locus, options), InputError);
  options.copies = 1;
  options.min_noise_scale = 2;
  EXPECT_THROW(NoisyLocus(m, locus, options), InputError);
}

}  // namespace
}  // namespace pyrocam
