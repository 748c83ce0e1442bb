#include "runtime/estimator_test_support.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <random>

#include "pyrocam/core/noise_model.h"

namespace pyrocam::test {

std::shared_ptr<const ThermalModel> test_model(const std::string& name) {
  static std::map<std::string, std::shared_ptr<const ThermalModel>> loaded;
  std::shared_ptr<const ThermalModel>& m = loaded[name];
  if (!m) {
    const char* dir = std::getenv("PYROCAM_TEST_MODEL_DIR");
    m = std::make_shared<const ThermalModel>(load_model(
        std::filesystem::path(dir && *dir ? dir : PYROCAM_TEST_MODEL_DIR_DEFAULT) / name));
  }
  return m;
}

double saturation_signal_dn(const ThermalModel& m) {
  return m.profile().thresholds.inference_saturation_dn - m.profile().dark_offset_dn;
}

NoisyPixels noisy_pixels(const ThermalModel& m, const std::vector<double>& temperatures_c,
                         int per_temperature, double peak_lo_dn, double peak_hi_dn,
                         double saturation_dn, double damaged_fraction, std::uint64_t seed) {
  NoisyPixels px;
  px.bands = m.profile().band_count();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> peak(peak_lo_dn, peak_hi_dn), unit(0, 1);
  for (double t : temperatures_c) {
    const Eigen::VectorXd rates = m.camera.rates(t);
    for (int k = 0; k < per_temperature; ++k) {
      const double scale = peak(rng) / rates.maxCoeff();
      for (int b = 0; b < px.bands; ++b) {
        const double mean = rates[b] * scale;
        const double v = mean + std::sqrt(signal_variance_dn2(m.profile(), b, mean)) * gauss(rng);
        px.signals.push_back(mean >= saturation_dn ? INFINITY : v);
      }
      if (unit(rng) < damaged_fraction) {
        const auto b = static_cast<std::size_t>(unit(rng) * px.bands);
        px.signals[px.signals.size() - static_cast<std::size_t>(px.bands) + b] =
            unit(rng) < 0.5 ? NAN : 5.0;
      }
    }
  }
  return px;
}

std::vector<cv::Mat> as_planes(const NoisyPixels& px) {
  std::vector<cv::Mat> planes;
  for (int b = 0; b < px.bands; ++b) {
    cv::Mat p(1, static_cast<int>(px.size()), CV_32F);
    for (std::size_t i = 0; i < px.size(); ++i)
      p.at<float>(0, static_cast<int>(i)) = static_cast<float>(px.pixel(i)[b]);
    planes.push_back(p);
  }
  return planes;
}

Agreement compare(const cv::Mat& reference, const cv::Mat& fast, double tolerance_c) {
  Agreement a;
  for (int i = 0; i < reference.cols; ++i) {
    const float r = reference.at<float>(0, i), f = fast.at<float>(0, i);
    if (std::isfinite(r) && std::isfinite(f)) {
      ++a.both;
      const double d = std::abs(static_cast<double>(r) - f);
      a.max_difference_c = std::max(a.max_difference_c, d);
      if (d > tolerance_c) ++a.over_tolerance;
    } else if (std::isfinite(r)) {
      ++a.only_reference;
    } else if (std::isfinite(f)) {
      ++a.only_fast;
    } else {
      ++a.neither;
    }
  }
  return a;
}

bool every_band_reads(const ThermalModel& m, const double* s) {
  return std::all_of(s, s + m.profile().band_count(), [&](double v) {
    return std::isfinite(v) && v >= m.profile().thresholds.inference_dim_dn;
  });
}

BothFits both_fits(const std::shared_ptr<const ThermalModel>& model, bool partial) {
  BothFits fits{make_estimator(model, Method::kLikelihood),
                make_exhaustive_likelihood_estimator(model)};
  if (partial) {
    fits.fast->set_partial_bands(TemperatureEstimator::PartialBands::kAny);
    fits.exhaustive->set_partial_bands(TemperatureEstimator::PartialBands::kAny);
  }
  return fits;
}

}  // namespace pyrocam::test
