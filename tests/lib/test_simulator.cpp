// The simulated camera against the EMVA 1288 model it claims to follow.
#include <gtest/gtest.h>

#include "pyrocam/dataset.h"
#include "pyrocam/image_io.h"
#include "pyrocam/scenes.h"
#include "pyrocam/simulator.h"
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

}  // namespace
}  // namespace pyrocam
