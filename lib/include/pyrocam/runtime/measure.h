// From raw mosaic frames to temperature images: dark subtraction, demosaicking and per-pixel
// estimation, the same code path for the ratiotemp element and `pyrocam-calib measure`.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/misfit.h"

namespace pyrocam {

// Temperature (CV_32F degC, NaN = no reading) and, when asked, its expanded uncertainty (CV_32F
// degC, NaN where no reading) from band planes (CV_32F DN, +INF saturated, NaN invalid). With a
// misfit probability above 0, every reading then goes through the band-consistency check
// (misfit.h): a pixel whose bands fit no graybody near its temperature gets no reading.
class PlaneEstimator {
 public:
  // misfit_probability: the check's false-rejection probability, 0 = no check.
  PlaneEstimator(const ThermalModel& model, Method method, double misfit_probability = 0);
  void estimate(const std::vector<cv::Mat>& planes, cv::Mat& temperature_c,
                cv::Mat* uncertainty_c = nullptr) const;
  // The temperature codes (CV_16U, 0.1 K, 0 = no reading) straight from the planes: the same
  // values as encode_decikelvin(estimate()), without the float image in memory. `codes` may wrap
  // a caller's buffer (written in place when its size and type fit).
  void estimate_codes(const std::vector<cv::Mat>& planes, cv::Mat& codes) const;
  const TemperatureEstimator& estimator() const { return *estimator_; }
  // See TemperatureEstimator::set_allow_partial (off by default).
  void set_allow_partial(bool allow) { estimator_->set_allow_partial(allow); }
  // Not while an estimate runs. Throws InputError outside 0 or (0, 1).
  void set_misfit_probability(double probability);

 private:
  const ThermalModel& model_;
  std::unique_ptr<TemperatureEstimator> estimator_;
  // Made when the check is first turned on (its tables cost a locus).
  std::unique_ptr<MisfitCheck> misfit_;
};

struct MeasureOptions {
  Method method = Method::kMlp;
  DemosaicMethod demosaic = DemosaicMethod::kBilinear;
  double saturation_level_dn = -1;  // raw DN; -1: the profile's inference saturation threshold
  bool uncertainty = false;
  double misfit_probability = 0;  // band-consistency check (misfit.h); 0: none
  bool allow_partial = false;     // TemperatureEstimator::set_allow_partial
};

// One raw frame (CV_8U/CV_16U mosaic) and its dark (CV_32F, or a raw image) to temperature.
class FrameMeasurer {
 public:
  FrameMeasurer(const ThermalModel& model, const MeasureOptions& options);
  void measure(const cv::Mat& raw, const cv::Mat& dark, cv::Mat& temperature_c,
               cv::Mat* uncertainty_c = nullptr);
  cv::Size output_size(cv::Size raw) const;

 private:
  const ThermalModel& model_;
  MeasureOptions options_;
  PlaneEstimator planes_estimator_;
  cv::Mat signal_;
  std::vector<cv::Mat> planes_;
};

struct RegionStats {
  std::size_t pixels = 0, valid = 0;
  double valid_fraction = 0;
  double min_c = NAN, max_c = NAN, mean_c = NAN, median_c = NAN;
};
// Statistics of the finite pixels of a CV_32F temperature image inside mask (empty = all).
RegionStats region_stats(const cv::Mat& temperature_c, const cv::Mat& mask = cv::Mat());

}  // namespace pyrocam
