// Per-pixel estimation over band planes, the same code path for the ratiotemp element and
// `pyrocam-calib measure` (through FrameMeasurer).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/runtime/emissivity.h"
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
  // Around an estimator of `method` made for the model (EstimatorSelector: the lookup table on
  // the grid its prebuilt table names).
  PlaneEstimator(std::shared_ptr<const ThermalModel> model,
                 std::unique_ptr<TemperatureEstimator> estimator, Method method);
  void estimate(const std::vector<cv::Mat>& planes, cv::Mat& temperature_c,
                cv::Mat* uncertainty_c = nullptr) const;
  // The temperature codes (CV_16U, 0.1 K, 0 = no reading) straight from the planes: the same
  // values as encode_decikelvin(estimate()), without the float image in memory. `codes` may wrap
  // a caller's buffer (written in place when its size and type fit).
  void estimate_codes(const std::vector<cv::Mat>& planes, cv::Mat& codes) const;
  // What reads the pixels: the method's estimator, or with an emissivity slope its
  // EmissivitySlopeEstimator.
  const TemperatureEstimator& estimator() const {
    return sloped_ ? static_cast<const TemperatureEstimator&>(*sloped_) : *estimator_;
  }
  // See TemperatureEstimator::set_partial_bands (off by default). With the network or its
  // table, pixels they cannot read because a band is saturated, invalid or dim are read by the
  // likelihood fit with those rules (a grey surface only: with an emissivity slope they stay
  // without a reading). Not while an estimate runs; the fit is built when first needed.
  void set_partial_bands(TemperatureEstimator::PartialBands partial);
  void set_allow_partial(bool allow) {
    set_partial_bands(allow ? TemperatureEstimator::PartialBands::kAny
                            : TemperatureEstimator::PartialBands::kOff);
  }
  // Not while an estimate runs. Throws InputError outside 0 or (0, 1).
  void set_misfit_probability(double probability);
  // The surface's emissivity slope, per 100 nm (0.01 = 1 %/100 nm, positive rising with
  // wavelength; 0 = grey, the default), and that slope's standard uncertainty for the
  // uncertainty output (per 100 nm; negative: the model's). See EmissivitySlopeEstimator; the
  // band-consistency check then sees the corrected signals. Not while an estimate runs; rebuilt
  // only when a value changes (a few ms). Throws InputError for a value it refuses and keeps
  // the previous ones.
  void set_emissivity_slope(double alpha, double alpha_u = -1);
  double emissivity_slope() const { return sloped_ ? sloped_->alpha() : 0.0; }
  // The analogue gain the planes were taken with, as a factor over the profile's (10^(dB / 20);
  // 1 by default): see TemperatureEstimator::set_analogue_gain. Weights of the likelihood fit
  // and of the band-consistency check, and the uncertainty, follow it; called per frame, it
  // does nothing while the factor stays. Not while an estimate runs. Throws InputError unless
  // positive.
  void set_analogue_gain(double factor);
  double analogue_gain() const { return analogue_gain_; }

 private:
  // The planes' common size; throws InputError unless they are the model's bands, CV_32F, of
  // one size.
  cv::Size checked_size(const std::vector<cv::Mat>& planes) const;
  // Both estimates: the rows' temperatures into `out` (and the misfit check).
  void estimate_row(const float* const* rows, std::size_t n, float* out) const;

  std::shared_ptr<const ThermalModel> model_;
  std::shared_ptr<TemperatureEstimator> estimator_;
  std::unique_ptr<EmissivitySlopeEstimator> sloped_;  // null for a grey surface
  double alpha_u_ = -1;                               // as set
  // Made when the check is first turned on (its tables cost a locus).
  std::unique_ptr<MisfitCheck> misfit_;
  Method method_;
  // The likelihood fit for the pixels the network or its table cannot read (set_partial_bands).
  std::unique_ptr<TemperatureEstimator> partial_fit_;
  TemperatureEstimator::PartialBands partial_ = TemperatureEstimator::PartialBands::kOff;
  bool partial_set_ = false;
  double analogue_gain_ = 1.0;
};

}  // namespace pyrocam
