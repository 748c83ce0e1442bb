// Planck's law and the photon integral against independent references.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "pyrocam/core/physics.h"
#include "pyrocam/core/profile.h"
#include "test_support.h"

namespace pyrocam {
namespace {

TEST(Planck, matches_colour_science_test_vectors) {
  std::ifstream in(test::shared_data_dir() / "colour_science_test_vectors_planck_ohno2013.json");
  ASSERT_TRUE(in) << "test vectors not found in " << test::shared_data_dir();
  const auto vectors = nlohmann::json::parse(in).at("planck_law");
  const auto wavelengths = vectors.at("wavelengths_m").get<std::vector<double>>();
  // The vectors use c1 = 3.741771e-16 (5 digits) where we use 2 h c^2 from exact constants.
  const double c1_ratio = (vectors.at("c1_W_m2").get<double>() / M_PI) / kC1L;
  int compared = 0;
  for (const auto& [temperature, radiances] : vectors.at("radiance_by_temperature_K").items()) {
    const double t = std::stod(temperature);
    if (t > 1e6) continue;  // 1e19 K overflows the double exponent chain; outside any use
    for (std::size_t i = 0; i < wavelengths.size(); ++i) {
      const double expected = radiances[i].get<double>();
      const double ours = planck_energy_radiance(wavelengths[i], t) * c1_ratio;
      if (expected < 1e-300) {
        EXPECT_LT(ours, 1e-290) << wavelengths[i] << " m, " << t << " K";
        continue;
      }
      EXPECT_NEAR(ours / expected, 1.0, 1e-9) << wavelengths[i] << " m, " << t << " K";
      ++compared;
    }
  }
  EXPECT_GT(compared, 40);
  const double example = vectors.at("extra_examples").at("planck_law(500e-9, 5500)").get<double>();
  EXPECT_NEAR(planck_energy_radiance(500e-9, 5500) * c1_ratio / example, 1.0, 1e-9);
}

TEST(Planck, photon_form_is_energy_form_over_photon_energy) {
  for (double t : {800.0, 1500.0, 3000.0})
    for (double wl : {400e-9, 700e-9, 1000e-9}) {
      const double photon_energy = kPlanck * kSpeedOfLight / wl;
      EXPECT_NEAR(planck_photon_radiance(wl, t) * photon_energy / planck_energy_radiance(wl, t),
                  1.0, 1e-12);
    }
}

TEST(Planck, emissivity_scales_linearly) {
  EXPECT_DOUBLE_EQ(planck_photon_radiance(650e-9, 1800, 0.35),
                   0.35 * planck_photon_radiance(650e-9, 1800));
}

TEST(Planck, wien_displacement_locates_the_peak) {
  for (double t : {1000.0, 1773.15, 3000.0}) {
    const double peak = wien_peak_wavelength_m(t);
    const double h = peak * 1e-4;
    const double at_peak = planck_energy_radiance(peak, t);
    EXPECT_GT(at_peak, planck_energy_radiance(peak - h, t));
    EXPECT_GT(at_peak, planck_energy_radiance(peak + h, t));
    // Numerical maximum by golden-section search agrees to 1e-6.
    double a = 0.5 * peak, b = 2 * peak;
    const double g = (std::sqrt(5.0) - 1) / 2;
    for (int i = 0; i < 200; ++i) {
      const double c = b - g * (b - a), d = a + g * (b - a);
      if (planck_energy_radiance(c, t) > planck_energy_radiance(d, t))
        b = d;
      else
        a = c;
      if (b - a < 1e-15) break;
    }
    EXPECT_NEAR((a + b) / 2 / peak, 1.0, 1e-6);
  }
}

TEST(PhotonIntegral, flat_qe_over_wide_grid_gives_the_closed_form) {
  // Total photon radiance of a blackbody: 2 zeta(3) Gamma(3) (kT/hc)^3 c ... in closed form
  // L_p = 4 zeta(3) k^3 T^3 / (h^3 c^2) photons s^-1 m^-2 sr^-1.
  const double zeta3 = 1.2020569031595942;
  for (double t : {1500.0, 2500.0}) {
    const WavelengthGrid grid(50, 200000, 1);
    Eigen::MatrixXd flat = Eigen::MatrixXd::Constant(1, grid.size(), 0.5);
    const double integral = band_photon_integrals(flat, grid, t)[0];
    const double closed = 0.5 * 4 * zeta3 * std::pow(kBoltzmann * t, 3) /
                          (std::pow(kPlanck, 3) * kSpeedOfLight * kSpeedOfLight);
    EXPECT_NEAR(integral / closed, 1.0, 2e-3) << t << " K";  // tail beyond 200 um is cut
  }
}

// weighted_photon_radiance takes four wavelengths at a time where it can; every value must be
// planck_photon_radiance's times the weight to the bit, on the fast path and off it (exponents
// beyond exp's range at 20 K, below 0.5 in the far infrared and at 10^5 K), on grids whose size
// is not a multiple of four.
TEST(PhotonIntegral, weighted_radiance_is_the_scalar_formula_to_the_bit) {
  const WavelengthGrid grids[] = {{350, 1100, 5}, {400, 1000, 1}, {50, 200000, 3}, {400, 402, 1}};
  for (const WavelengthGrid& grid : grids)
    for (double t : {20.0, 373.15, 773.15, 1773.15, 2500.0, 3773.15, 1e5})
      for (double emissivity : {1.0, 0.37}) {
        const Eigen::VectorXd w = weighted_photon_radiance(grid, t, emissivity);
        ASSERT_EQ(w.size(), grid.size());
        for (Eigen::Index i = 0; i < grid.size(); ++i)
          ASSERT_EQ(w[i], planck_photon_radiance(grid.nm()[i] * 1e-9, t, emissivity) *
                              grid.weights_m()[i])
              << grid.nm()[i] << " nm, " << t << " K, emissivity " << emissivity;
      }
}

TEST(PhotonIntegral, energy_integral_gives_stefan_boltzmann) {
  const double t = 2000;
  const WavelengthGrid grid(50, 100000, 1);
  double sum = 0;
  for (Eigen::Index i = 0; i < grid.size(); ++i)
    sum += planck_energy_radiance(grid.nm()[i] * 1e-9, t) * grid.weights_m()[i];
  EXPECT_NEAR(M_PI * sum / (kStefanBoltzmann * std::pow(t, 4)), 1.0, 1e-3);
}

TEST(WavelengthGrid, rejects_bad_ranges_n) {
  EXPECT_THROW(WavelengthGrid(500, 400, 1), std::invalid_argument);
  EXPECT_THROW(WavelengthGrid(400, 500, 0), std::invalid_argument);
  EXPECT_THROW(WavelengthGrid(400, 500, 3), std::invalid_argument);
  // 10^14 samples: refused before lround (undefined beyond a long) and before allocating.
  EXPECT_THROW(WavelengthGrid(400, 500, 1e-12), std::invalid_argument);
  EXPECT_THROW(WavelengthGrid(400, 1e300, 1e-300), std::invalid_argument);
  const WavelengthGrid g(400, 500, 5);
  EXPECT_EQ(g.size(), 21);
  EXPECT_EQ(g.index_of(451), 10);
}

TEST(Normalisation, ratios_cancel_a_common_scale) {
  Normalisation n{{0, 2}, {1}};
  Eigen::Vector3d s(30, 60, 15);
  const Eigen::VectorXd x = normalised_ratios(n, s);
  EXPECT_DOUBLE_EQ(x[0], 0.5);
  EXPECT_DOUBLE_EQ(x[1], 0.25);
  EXPECT_TRUE(normalised_ratios(n, 7.0 * s).isApprox(x, 1e-15));
}

}  // namespace
}  // namespace pyrocam
