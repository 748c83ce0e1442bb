// The simulated camera against the EMVA 1288 model it claims to follow.
#include <gtest/gtest.h>

#include "pyrocam/core/dataset.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"
#include "test_support.h"

namespace pyrocam {
namespace {

struct BandStats {
  double mean = 0, var = 0;
  int n = 0;
};

// Per-band mean of a frame and temporal variance from the difference of two frames (EMVA 1288
// section 6: the difference cancels fixed-pattern noise).
std::vector<BandStats> band_stats(const MosaicLayout& m, int bands, const cv::Mat& a,
                                  const cv::Mat& b) {
  std::vector<BandStats> s(bands);
  std::vector<double> sum_d(bands), sum_d2(bands);
  for (int y = 0; y < a.rows; ++y)
    for (int x = 0; x < a.cols; ++x) {
      const int band = m.band_at(x, y);
      const double va = a.at<std::uint8_t>(y, x), vb = b.at<std::uint8_t>(y, x);
      s[band].mean += va;
      sum_d[band] += va - vb;
      sum_d2[band] += (va - vb) * (va - vb);
      ++s[band].n;
    }
  for (int band = 0; band < bands; ++band) {
    s[band].mean /= s[band].n;
    const double md = sum_d[band] / s[band].n;
    s[band].var = (sum_d2[band] / s[band].n - md * md) / 2;
  }
  return s;
}

class SimulatedRgb : public ::testing::Test {
 protected:
  CameraProfile profile = load_profile_by_name("rgb-reference");
};

TEST_F(SimulatedRgb, flat_frames_follow_the_emva_model) {
  Simulator camera(profile, UnitPerturbation{"datasheet", 1});
  const double t_c = 1000;
  const double exposure = camera.exposure_for(t_c, 120);  // brightest band 120 DN above dark
  const cv::Mat plate(200, 200, CV_32F, cv::Scalar(static_cast<float>(t_c)));
  const cv::Mat a = camera.render(plate, exposure), b = camera.render(plate, exposure);
  const auto stats = band_stats(profile.mosaic, 3, a, b);
  const Eigen::VectorXd signal = camera.mean_signal_dn(t_c, exposure);
  const Eigen::VectorXd k = profile.dn_per_electron();
  const NoiseModel& nm = profile.noise;
  for (int band = 0; band < 3; ++band) {
    const double dark_e = nm.dark_current_e_per_s * exposure * 1e-6;
    const double mu_e = signal[band] / k[band];
    const double expected_mean = profile.dark_offset_dn + signal[band] + k[band] * dark_e;
    // sigma_y^2 = K^2 (mu_e + mu_d + sigma_read^2) + 1/12 (EMVA 1288 eq. 9)
    const double expected_var =
        k[band] * k[band] * (mu_e + dark_e + nm.read_noise_e * nm.read_noise_e) + 1.0 / 12;
    SCOPED_TRACE(profile.band_names[band]);
    EXPECT_NEAR(stats[band].mean, expected_mean, 0.01 * signal[band] + 0.3);
    // The variance of n >= 10^4 differences has a relative standard error of about sqrt(2/n)
    // = 0.014 (chi-squared with n degrees of freedom): 0.08 is 5.6 of them, whatever the draws.
    EXPECT_NEAR(stats[band].var / expected_var, 1.0, 0.08);
  }
  // The brightest band sits where exposure_for put it.
  EXPECT_NEAR(signal.maxCoeff(), 120, 1e-6);
}

TEST_F(SimulatedRgb, dark_frames_sit_at_the_offset_plus_dark_current) {
  Simulator camera(profile, UnitPerturbation{"datasheet", 1});
  const double exposure = 50000;
  const cv::Mat dark = camera.render_dark(100, 100, exposure);
  const double dark_dn_green =
      profile.dn_per_electron()[1] * profile.noise.dark_current_e_per_s * exposure * 1e-6;
  EXPECT_NEAR(cv::mean(dark)[0], profile.dark_offset_dn + 7.0 / 4 * dark_dn_green, 0.3);
  // A cold scene renders as the dark frame of the same exposure.
  cv::Mat cold(100, 100, CV_32F, cv::Scalar(20.f));
  EXPECT_NEAR(cv::mean(camera.render(cold, exposure))[0], cv::mean(dark)[0], 0.3);
}

// A clamped black level (pyrocamsrc's sensor): at a long exposure the dark current adds its
// noise and not its mean. 10 s of the profile's dark current is tens of DN unclamped.
TEST_F(SimulatedRgb, a_clamped_black_level_stays_at_the_offset_at_any_exposure) {
  Simulator camera(profile, UnitPerturbation{"datasheet", 1}, 4);
  const double exposure = 10e6;
  const double unclamped = cv::mean(camera.render_dark(100, 100, exposure))[0];
  camera.set_black_level_clamp(true);
  const cv::Mat dark = camera.render_dark(100, 100, exposure);
  EXPECT_GT(unclamped, profile.dark_offset_dn + 10);
  EXPECT_NEAR(cv::mean(dark)[0], profile.dark_offset_dn, 0.3);
  // The dark current's shot noise stays: a spread well beyond the read noise's.
  cv::Mat mean, spread;
  cv::meanStdDev(dark, mean, spread);
  const double read_dn = profile.dn_per_electron()[1] * profile.noise.read_noise_e;
  EXPECT_GT(spread.at<double>(0), 2 * read_dn);
}

TEST_F(SimulatedRgb, a_black_level_shift_moves_every_frame_after_it) {
  Simulator camera(profile, UnitPerturbation{"datasheet", 1}, 3);
  Simulator shifted(profile, UnitPerturbation{"datasheet", 1}, 3);
  shifted.set_black_level_shift(2.4);
  const double exposure = 5000;
  // The same noise draws: the frames differ by the shift, rounded pixel by pixel (the fixed
  // pattern spreads the rounding, so the mean moves by the shift itself).
  const double moved = cv::mean(shifted.render_dark(100, 100, exposure))[0] -
                       cv::mean(camera.render_dark(100, 100, exposure))[0];
  EXPECT_NEAR(moved, 2.4, 0.1);
  shifted.set_black_level_shift(0);
  EXPECT_EQ(cv::norm(shifted.render_dark(100, 100, exposure),
                     camera.render_dark(100, 100, exposure), cv::NORM_L1),
            0);
}

TEST_F(SimulatedRgb, saturation_clips_at_full_scale) {
  Simulator camera(profile, UnitPerturbation{"datasheet", 1});
  const cv::Mat plate(20, 20, CV_32F, cv::Scalar(2500.f));
  const cv::Mat frame = camera.render(plate, camera.exposure_for(2500, 10000));
  double lo, hi;
  cv::minMaxLoc(frame, &lo, &hi);
  EXPECT_EQ(lo, 255);
  EXPECT_EQ(hi, 255);
}

TEST_F(SimulatedRgb, sixteen_bit_profiles_render_sixteen_bit_frames) {
  CameraProfile p16 = profile;
  p16.bit_depth = 12;
  Simulator camera(p16, UnitPerturbation{"datasheet", 1});
  const cv::Mat frame = camera.render(cv::Mat(16, 16, CV_32F, cv::Scalar(2500.f)), 1e6);
  EXPECT_EQ(frame.type(), CV_16U);
  double hi;
  cv::minMaxLoc(frame, nullptr, &hi);
  // Blue (gain 4) reaches the full well before the 12-bit converter's full scale.
  const double full_well_dn = p16.dn_per_electron()[2] * p16.noise.full_well_e + p16.dark_offset_dn;
  EXPECT_NEAR(hi, full_well_dn, 4);
  EXPECT_GT(hi, 255);
}

TEST_F(SimulatedRgb, noise_is_deterministic_per_seed) {
  const cv::Mat plate(64, 64, CV_32F, cv::Scalar(950.f));
  Simulator a(profile, UnitPerturbation{"typical", 1}, 11),
      b(profile, UnitPerturbation{"typical", 1}, 11),
      c(profile, UnitPerturbation{"typical", 1}, 12);
  const cv::Mat fa = a.render(plate, 2000), fb = b.render(plate, 2000), fc = c.render(plate, 2000);
  EXPECT_EQ(cv::norm(fa, fb, cv::NORM_INF), 0);
  EXPECT_GT(cv::norm(fa, fc, cv::NORM_INF), 0);
}

TEST_F(SimulatedRgb, typical_unit_leaks_in_the_near_infrared) {
  const Eigen::MatrixXd datasheet = true_system_qe(profile, UnitPerturbation{"datasheet", 1});
  EXPECT_TRUE(datasheet.isApprox(profile.system_qe()));
  const Eigen::MatrixXd unit = true_system_qe(profile, UnitPerturbation{"typical", 5});
  EXPECT_TRUE(unit.isApprox(true_system_qe(profile, UnitPerturbation{"typical", 5})));
  EXPECT_FALSE(unit.isApprox(true_system_qe(profile, UnitPerturbation{"typical", 6})));
  // About 1 % absolute system QE added at 800 nm, far above the filter's OD3 blocking.
  const auto i800 = profile.grid.index_of(800);
  const double added = (unit.col(i800) - datasheet.col(i800)).maxCoeff();
  EXPECT_GT(added, 0.004);
  EXPECT_LT(added, 0.02);
  // Inside the pass band the change is a few percent of scale and tilt.
  const auto i550 = profile.grid.index_of(550);
  for (int b = 0; b < 3; ++b) EXPECT_NEAR(unit(b, i550) / datasheet(b, i550), 1.0, 0.15);
  // The leak raises the furnace-range signal of every band: the datasheet underestimates it.
  const Eigen::VectorXd s_unit = signal_rates(profile, unit, celsius_to_kelvin(900));
  const Eigen::VectorXd s_sheet = signal_rates(profile, datasheet, celsius_to_kelvin(900));
  for (int b = 0; b < 3; ++b) EXPECT_GT(s_unit[b], 1.1 * s_sheet[b]);
}

TEST_F(SimulatedRgb, typical_unit_deviates_outside_the_solvers_model_family) {
  // Ripple and filter-edge shift come on top of the modelled shapes, from their own stream.
  CameraProfile plain = profile;
  plain.unit_variation.ripple_rms = 0;
  plain.unit_variation.filter_shift_sigma_nm = 0;
  const Eigen::MatrixXd modelled = true_system_qe(plain, UnitPerturbation{"typical", 5});
  CameraProfile rippled = plain;
  rippled.unit_variation.ripple_rms = 0.01;
  const Eigen::MatrixXd with_ripple = true_system_qe(rippled, UnitPerturbation{"typical", 5});
  // Inside the pass band: common x per-band ripple, each 1 % rms, about 1.4 % together.
  const auto from = profile.grid.index_of(450), to = profile.grid.index_of(650);
  for (int b = 0; b < 3; ++b) {
    const Eigen::ArrayXd ratio = with_ripple.row(b).segment(from, to - from).array() /
                                 modelled.row(b).segment(from, to - from).array();
    const double rms = std::sqrt((ratio - 1).square().mean());
    EXPECT_GT(rms, 0.004) << "band " << b;
    EXPECT_LT(rms, 0.04) << "band " << b;
  }
  CameraProfile shifted = plain;
  shifted.unit_variation.filter_shift_sigma_nm = 1.0;
  const Eigen::MatrixXd with_shift = true_system_qe(shifted, UnitPerturbation{"typical", 5});
  EXPECT_FALSE(with_shift.isApprox(modelled, 1e-6));
  // The modelled components (per-band shift, scale, tilt) stay those of the seed: in the flat
  // middle of the pass band the shifted filter changes the QE by a hair, not by a band's scale.
  const auto middle = profile.grid.index_of(550);
  for (int b = 0; b < 3; ++b)
    EXPECT_NEAR(with_shift(b, middle) / modelled(b, middle), 1.0, 2e-3) << "band " << b;
  // At a filter edge a shift changes the QE by far more than inside the band.
  const auto edge = profile.grid.index_of(profile.filter_pass_band_nm[1]);
  EXPECT_GT(std::abs(with_shift(0, edge) / modelled(0, edge) - 1), 0.005);
}

TEST(SimulatedCampaign, furnace_truth_differs_from_the_nominal_temperatures_it_records) {
  test::ScratchDir dir("furnace-truth");
  // 12 bits and a deep well, so that every step is well exposed and quantisation negligible.
  CameraProfile profile = load_profile_by_name("rgb-reference");
  profile.bit_depth = 12;
  profile.noise.full_well_e = 1e7;
  Simulator camera(profile, UnitPerturbation{"datasheet", 1});
  CampaignSettings s;
  s.exposure_count = 1;
  s.frames_per_setting = 1;
  s.width = s.height = 16;
  s.roi_area_px = 50;
  s.furnace_error_sigma_c = 2.0;
  camera.set_noise_enabled(false);
  s.first_exposure_us = camera.exposure_for(1110, 3500);
  write_furnace_campaign(dir.path(), camera, s);
  const CsvTable truth = read_csv_table(dir / "furnace-truth.csv");
  const auto& nominal = truth.columns[truth.column_index("nominal_c")];
  const auto& true_c = truth.columns[truth.column_index("true_c")];
  const std::vector<double> recorded = Dataset::open(dir.path()).temperatures_c();
  ASSERT_EQ(nominal.size(), 41u);
  ASSERT_EQ(recorded.size(), nominal.size());
  double sum2 = 0;
  for (std::size_t i = 0; i < nominal.size(); ++i) {
    EXPECT_DOUBLE_EQ(recorded[i], nominal[i]);
    sum2 += (true_c[i] - nominal[i]) * (true_c[i] - nominal[i]);
  }
  const double sd = std::sqrt(sum2 / static_cast<double>(nominal.size()));
  // 41 draws of sigma 2: 41 (sd / 2)^2 is chi-squared with 41 degrees of freedom, so sd lies
  // outside [1.0, 3.0] with probability 1e-5 (Wilson-Hilferty: z = -4.9 and +4.3) for any seed.
  EXPECT_GT(sd, 1.0);
  EXPECT_LT(sd, 3.0);
  // The frames show the true temperature, not the nominal one: take the step furthest off.
  std::size_t worst = 0;
  for (std::size_t i = 0; i < nominal.size(); ++i)
    if (std::abs(true_c[i] - nominal[i]) > std::abs(true_c[worst] - nominal[worst])) worst = i;
  const Dataset d = Dataset::open(dir.path());
  const FrameGroup& g = d.frames()[worst];
  ASSERT_DOUBLE_EQ(g.temperature_c, nominal[worst]);
  const cv::Mat frame = d.average(g);
  double red = 0;
  int n = 0;
  for (int y = 0; y < frame.rows; y += 2)
    for (int x = 0; x < frame.cols; x += 2) red += frame.at<double>(y, x), ++n;
  red = red / n - camera.profile().dark_offset_dn;
  const double expected_true = camera.mean_signal_dn(true_c[worst], g.exposure_us)[0];
  const double expected_nominal = camera.mean_signal_dn(nominal[worst], g.exposure_us)[0];
  EXPECT_LT(std::abs(red - expected_true), 0.3 * std::abs(expected_nominal - expected_true))
      << "red " << red << " DN; true " << expected_true << ", nominal " << expected_nominal;
}

TEST(SimulatedNir, five_by_five_units_shift_their_bands) {
  const CameraProfile p = load_profile_by_name("nir5x5-reference");
  const Eigen::MatrixXd unit = true_system_qe(p, UnitPerturbation{"typical", 2});
  const Eigen::MatrixXd sheet = p.system_qe();
  // Centroid of each band's main peak (+-8 nm around the datasheet's maximum).
  auto centroid = [](const Eigen::MatrixXd& q, int b, Eigen::Index centre) {
    double w = 0, wx = 0;
    for (Eigen::Index i = centre - 8; i <= centre + 8; ++i) w += q(b, i), wx += q(b, i) * i;
    return wx / w;
  };
  int moved = 0;
  for (int b = 0; b < 25; ++b) {
    Eigen::Index peak;
    sheet.row(b).segment(300, 290).maxCoeff(&peak);
    peak += 300;
    const double shift = centroid(unit, b, peak) - centroid(sheet, b, peak);
    EXPECT_LE(std::abs(shift), 5.0) << "band " << b;
    moved += std::abs(shift) > 0.3;
  }
  EXPECT_GT(moved, 5);
}

TEST(Scenes, melt_pool_sequence_is_a_readable_dataset_with_truth) {
  test::ScratchDir dir("scene");
  Simulator camera(load_profile_by_name("rgb-reference"), UnitPerturbation{"typical", 1});
  SceneSequenceSettings s;
  s.frames = 4;
  s.width = 64;
  s.height = 48;
  write_scene_sequence(dir.path(), camera, s);
  const Dataset d = Dataset::open(dir.path());
  ASSERT_EQ(d.rows().size(), 5u);   // 4 frames and one dark: one exposure for the sequence
  EXPECT_EQ(d.darks().size(), 1u);  // one exposure for the whole sequence
  for (int i = 0; i < 4; ++i) {
    const cv::Mat truth = read_raw_image(dir / ("truth/000" + std::to_string(i) + ".png"));
    ASSERT_EQ(truth.type(), CV_16U);
    double hi;
    cv::minMaxLoc(truth, nullptr, &hi);
    EXPECT_NEAR(hi / 10 - 273.15, melt_pool_peak_c(i, 4), 0.051);
    EXPECT_GE(melt_pool_peak_c(i, 4), 1500);
    EXPECT_LE(melt_pool_peak_c(i, 4), 2500);
  }
  EXPECT_THROW(parse_scene_kind("volcano"), InputError);
}

TEST(Scenes, filament_scene_has_a_hot_core_and_cooler_edges) {
  const cv::Mat m = filament_scene(96, 64, 2000);
  const int y = 32;
  float core = 0;
  int hot = 0;
  for (int x = 0; x < 96; ++x) {
    const float t = m.at<float>(y, x);
    if (std::isfinite(t)) core = std::max(core, t), hot += t == 2000.f;
  }
  EXPECT_EQ(core, 2000.f);
  EXPECT_GE(hot, 4);
  EXPECT_TRUE(std::isnan(m.at<float>(y, 0)));
}

TEST(Scenes, plate_scene_covers_the_asked_share_of_the_frame) {
  auto hot_share = [](const cv::Mat& m) {
    return static_cast<double>(cv::countNonZero(m == m)) / static_cast<double>(m.total());
  };
  // 0.36 is the three-argument plate, pixel for pixel, at sizes dividing by 5 and not.
  for (const cv::Size size : {cv::Size(2048, 2048), cv::Size(2048, 1088), cv::Size(2045, 1085),
                              cv::Size(320, 240), cv::Size(97, 61)}) {
    const cv::Mat old_plate = plate_scene(size.width, size.height, 1500);
    const cv::Mat plate = plate_scene(size.width, size.height, 1500, 0.36);
    EXPECT_EQ(cv::countNonZero((old_plate == old_plate) != (plate == plate)), 0) << size;
  }
  for (const double share : {0.05, 0.36, 0.9, 1.0})
    // Margins round down: at most a pixel more per side.
    EXPECT_NEAR(hot_share(plate_scene(2048, 1088, 1500, share)), share, 0.005) << share;
  EXPECT_THROW(plate_scene(64, 64, 1500, 0), InputError);
  EXPECT_THROW(plate_scene(64, 64, 1500, 1.5), InputError);
}

}  // namespace
}  // namespace pyrocam
