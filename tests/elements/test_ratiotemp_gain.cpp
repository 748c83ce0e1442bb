// ratiotemp at an analogue gain: a plate taken at 12 dB with a quarter of the exposure reads the
// temperature it reads at 0 dB, and its uncertainty is larger (more shot noise per DN), because
// ratiotemp takes each frame's gain from its PyrocamExposureMeta.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "element_support.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/simulation/scenes.h"
#include "pyrocam/simulation/simulator.h"

namespace pyrocam::test {
namespace {

constexpr int kWidth = 80, kHeight = 60, kFrames = 4;

std::string rgb_model_path() {
  const char* dir = g_getenv("PYROCAM_TEST_MODEL_DIR");
  return std::string(dir ? dir : ".") + "/test-model-rgb.json";
}

// The decoded values (degC; output=uncertainty: degC of expanded uncertainty) of the plate's
// central 32x24 pixels in every frame, readings only.
std::vector<double> plate_values(const std::string& camera, const std::string& output) {
  const std::string description =
      "pyrocamsrc scene=plate temperature=1050 num-buffers=" + std::to_string(kFrames) + " " +
      camera + " ! video/x-bayer,width=" + std::to_string(kWidth) +
      ",height=" + std::to_string(kHeight) +
      " ! darksub dark-level=50 ! demosaic25 ! ratiotemp method=likelihood output=" + output +
      " model=" + rgb_model_path() + " ! fakesink name=sink";
  const auto frames = sink_frames(description, 60 * GST_SECOND);
  const bool uncertainty = output == "uncertainty";
  const int stride = GST_ROUND_UP_4(2 * kWidth);
  std::vector<double> values;
  for (const auto& bytes : frames) {
    if (bytes.size() < static_cast<std::size_t>(stride * kHeight)) continue;
    for (int y = kHeight / 2 - 12; y < kHeight / 2 + 12; ++y)
      for (int x = kWidth / 2 - 16; x < kWidth / 2 + 16; ++x) {
        std::uint16_t code;
        std::memcpy(&code, &bytes[static_cast<std::size_t>(y * stride + 2 * x)], 2);
        if (code == 0) continue;  // no reading
        values.push_back(uncertainty ? difference_code_to_celsius(code) : code_to_celsius(code));
      }
  }
  return values;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// A robust standard deviation: 1.4826 median absolute deviations.
double robust_sd(const std::vector<double>& v) {
  const double m = median(v);
  std::vector<double> d;
  for (double x : v) d.push_back(std::abs(x - m));
  return 1.4826 * median(d);
}

class RatioTempGain : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* e : {"pyrocamsrc", "darksub", "demosaic25", "ratiotemp"}) REQUIRE_ELEMENT(e);
    // The exposure that puts the 1050 degC plate's red band at 140 DN above dark at 0 dB; at
    // 12 dB (x3.98) a quarter of it gives 0.995 of the same DN.
    const Simulator camera(load_profile_by_name("rgb-reference"),
                           UnitPerturbation::parse("typical", 1));
    exposure_ = camera.exposure_for(1050, 140, kSceneDefaults.plate_emissivity);
  }
  std::string at_0db() const { return "exposure=" + std::to_string(exposure_); }
  std::string at_12db() const { return "gain=12 exposure=" + std::to_string(exposure_ / 4); }
  double exposure_ = 0;
};

TEST_F(RatioTempGain, a_plate_at_12_db_reads_the_temperature_it_reads_at_0_db) {
  const std::vector<double> plain = plate_values(at_0db(), "temperature");
  const std::vector<double> gained = plate_values(at_12db(), "temperature");
  ASSERT_GT(plain.size(), 2000u);
  ASSERT_GT(gained.size(), 2000u);
  const double sd0 = robust_sd(plain), sd12 = robust_sd(gained);
  // The standard error of a median is 1.25 sd / sqrt(n); demosaicking shares each raw sample
  // among about 4 output pixels, so n counts a quarter of the readings. The bound is 4 of
  // those standard errors of the difference: a wrong gain in the noise model (the likelihood
  // weights) or in the simulator (DN not scaled by the gain) shifts it by far more.
  const double n0 = plain.size() / 4.0, n12 = gained.size() / 4.0;
  const double bound = 4 * 1.25 * std::sqrt(sd0 * sd0 / n0 + sd12 * sd12 / n12);
  const double m0 = median(plain), m12 = median(gained);
  std::printf(
      "[ figures  ] median %.2f degC (sd %.2f) at 0 dB, %.2f degC (sd %.2f) at 12 dB; "
      "bound %.2f degC\n",
      m0, sd0, m12, sd12, bound);
  EXPECT_NEAR(m12, m0, bound);
  // The readings are noisier at 12 dB: twice the shot noise per DN.
  EXPECT_GT(sd12, 1.3 * sd0);
}

TEST_F(RatioTempGain, uncertainty_at_12_db_is_larger_for_the_same_dn) {
  // Same DN, but each DN holds a quarter of the electrons: the shot-noise variance per DN is
  // 3.98 times as large, so the noise term of the uncertainty doubles; the calibration and
  // emissivity terms stay. Were the gain ignored, both would be equal within a few %.
  const double u0 = median(plate_values(at_0db(), "uncertainty"));
  const double u12 = median(plate_values(at_12db(), "uncertainty"));
  std::printf("[ figures  ] median expanded uncertainty %.2f degC at 0 dB, %.2f degC at 12 dB\n",
              u0, u12);
  EXPECT_GT(u12, 1.3 * u0);  // measured 1.86: the noise term dominates at 1050 degC
  EXPECT_LT(u12, 2.1 * u0);  // at most the noise term doubled
}

}  // namespace
}  // namespace pyrocam::test
