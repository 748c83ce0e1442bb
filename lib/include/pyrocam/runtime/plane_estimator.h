// Per-pixel estimation over band planes, the same code path for the ratiotemp element and
// `pyrocam-calib measure` (through FrameMeasurer).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/misfit.h"

namespace pyrocam {

// Temperature (CV_32F degC, NaN = no reading) and, when asked, its expanded uncertainty (CV_32F
// degC, NaN where no reading) from band planes (CV_32F DN, +INF saturated, NaN invalid). With a
// misfit probability above 0, every reading then goes through the band-consistency check
// (misfit.h): a pixel whose bands fit no graybody near its temperature gets no reading.
class PlaneEstimator {
 public:
  // Shares the model; throws InputError without one.
  // misfit_probability: the check's false-rejection probability, 0 = no check.
  PlaneEstimator(std::shared_ptr<const ThermalModel> model, Method method,
                 double misfit_probability = 0);
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
  // The planes' common size; throws InputError unless they are the model's bands, CV_32F, of
  // one size.
  cv::Size checked_size(const std::vector<cv::Mat>& planes) const;
  std::shared_ptr<const ThermalModel> model_;
  std::unique_ptr<TemperatureEstimator> estimator_;
  // Made when the check is first turned on (its tables cost a locus).
  std::unique_ptr<MisfitCheck> misfit_;
};

}  // namespace pyrocam
