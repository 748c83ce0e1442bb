// Helpers of the estimator tests (lookup table, likelihood fit, plane estimator): the small
// calibrated models the build makes (tests/data), noisy simulated pixels and how two estimators'
// images agree.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam::test {

// $PYROCAM_TEST_MODEL_DIR (set by meson test), else the build tree's tests/data; loaded once.
std::shared_ptr<const ThermalModel> test_model(const std::string& name);

// The signal above the dark offset at which the model's camera saturates.
double saturation_signal_dn(const ThermalModel& m);

// Noisy band signals of a graybody: the brightest band at a random level, EMVA 1288 noise, bands
// at or above `saturation_dn` saturated (+INF), and now and then a band made NaN or dim.
struct NoisyPixels {
  int bands = 0;
  std::vector<double> signals;  // pixel after pixel
  std::size_t size() const { return signals.size() / static_cast<std::size_t>(bands); }
  const double* pixel(std::size_t i) const { return &signals[i * static_cast<std::size_t>(bands)]; }
};

NoisyPixels noisy_pixels(const ThermalModel& m, const std::vector<double>& temperatures_c,
                         int per_temperature, double peak_lo_dn, double peak_hi_dn,
                         double saturation_dn, double damaged_fraction, std::uint64_t seed);

// Band planes (one row) holding the pixels, as the elements pass them.
std::vector<cv::Mat> as_planes(const NoisyPixels& px);

struct Agreement {
  std::size_t both = 0, neither = 0, only_reference = 0, only_fast = 0, over_tolerance = 0;
  double max_difference_c = 0;
};

Agreement compare(const cv::Mat& reference, const cv::Mat& fast, double tolerance_c);

inline const std::vector<double> kSweepC = {650, 900, 1200, 1500, 1800, 2200, 2700, 3200, 3450};

// Whether every band of pixel s reads (a number at or above the dim threshold).
bool every_band_reads(const ThermalModel& m, const double* s);

// A fixed, portable sequence of numbers in [0, 1) from `state` (a 64-bit linear congruential
// generator's top 53 bits): the same pixels on every machine.
struct Uniform {
  std::uint64_t state;
  double operator()() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) / 9007199254740992.0;
  }
};

// The fast and the exhaustive likelihood fit of a model, both reading partial pixels (any two
// bands) where asked.
struct BothFits {
  std::unique_ptr<TemperatureEstimator> fast, exhaustive;
};
BothFits both_fits(const std::shared_ptr<const ThermalModel>& model, bool partial);

}  // namespace pyrocam::test
