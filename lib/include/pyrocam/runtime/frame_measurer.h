// From raw mosaic frames to temperature images: dark subtraction, demosaicking and per-pixel
// estimation (PlaneEstimator), for `pyrocam-calib measure`.
#pragma once

#include <cmath>
#include <cstddef>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "pyrocam/runtime/blur_bias.h"
#include "pyrocam/runtime/curvature_check.h"
#include "pyrocam/runtime/dark_level_check.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/mixed_pixels.h"
#include "pyrocam/runtime/plane_estimator.h"
#include "pyrocam/runtime/scaled_brightness.h"
#include "pyrocam/runtime/snapshot_brightness.h"

namespace pyrocam {

struct MeasureOptions {
  Method method = Method::kMlp;
  DemosaicMethod demosaic = DemosaicMethod::kAuto;
  double saturation_level_dn = -1;  // raw DN; -1: the profile's inference saturation threshold
  bool uncertainty = false;
  double misfit_probability = 0;  // band-consistency check (misfit.h); 0: none
  bool allow_partial = false;     // TemperatureEstimator::set_allow_partial (any two bands)
  bool safe_partial = false;      // else PartialBands::kSafe: a monotonic pair among them
  // PlaneEstimator::set_emissivity_slope: per 100 nm (0 = grey), and its standard uncertainty
  // (negative: the model's).
  double emissivity_slope = 0;
  double emissivity_slope_u = -1;
  // mark_mixed_pixels (mixed_pixels.h) with this relative spread and the profile's noise; 0: off.
  double footprint_spread = 0;
  // The analogue gain the frames were taken with, dB (PlaneEstimator::set_analogue_gain).
  double gain_db = 0;
  // Subtract the matched kernel's bias on gradients (blur_bias.h); needs matched demosaicking.
  bool blur_correction = false;
  // Ratio-scaled brightness readings with this window radius: Bayer cells for a Bayer mosaic
  // (scaled_brightness.h), which must be demosaicked at full resolution; cells of a snapshot
  // mosaic (snapshot_brightness.h). 0: the ratio readings as they are. After
  // the blur correction, which then acts on the scales only. Read on the 0.1 K codes
  // (temperature_codes.h), as ratiotemp reads them, so a recording measured again gives its
  // codes bit for bit.
  int brightness_radius = 0;
  // The frames' Bayer pattern (rggb, bggr, grbg or gbrg) where it is not the model's: the same
  // filters, a readout window that starts on another cell. Empty: the model's layout.
  std::string bayer_pattern;
  // Check the frames' layout as darksub and ratiotemp do (layout_check).
  bool check_layout = false;
};

// One raw frame (CV_8U/CV_16U mosaic) and its dark (CV_32F, or a raw image) to temperature.
class FrameMeasurer {
 public:
  // Shares the model; throws InputError without one.
  FrameMeasurer(std::shared_ptr<const ThermalModel> model, const MeasureOptions& options);
  void measure(const cv::Mat& raw, const cv::Mat& dark, cv::Mat& temperature_c,
               cv::Mat* uncertainty_c = nullptr);
  // The same from a dark-subtracted mosaic (CV_32F, +INF saturated, NaN no reading, as
  // subtract_dark gives it, or fused from a bracket by MosaicBracketFusion).
  void measure_signal(const cv::Mat& signal, cv::Mat& temperature_c,
                      cv::Mat* uncertainty_c = nullptr);
  cv::Size output_size(cv::Size raw) const;
  // Why pixels of the last frame measured have no reading: of those under `mask` (CV_8U of the
  // output's size, non-zero = counted; empty: all) without a reading in `temperature_c`, how many
  // have a band saturated or near the saturation level (SaturationEdgeCheck::checked_dn), how
  // many a band below the model's dim threshold or near it (DimEdgeCheck::checked_dn), and how
  // many both at once (counted in neither of the others): no one exposure reads those.
  struct Unread {
    long saturated = 0, dim = 0, both = 0;
  };
  Unread unread(const cv::Mat& temperature_c, const cv::Mat& mask) const;
  // Pixels of the last frame measured without a reading because they are hotter than the
  // model's range (PlaneEstimator's above-range check, kept where above_range_spots keeps them).
  std::size_t above_range() const { return above_range_; }
  // The expanded uncertainty (the model's coverage factor k) of the median of the readings under
  // `mask` (as in unread), from the frame's temperatures and per-pixel expanded uncertainties
  // (measure's uncertainty_c): the systematic terms at the median (calibration, emissivity:
  // common to every pixel, so the median keeps them whole) and the readings' noise (the median
  // of the readings' own) times the square root of median_noise_share: neighbouring readings
  // share their demosaicking footprints' samples (demosaic_noise_area), so their median
  // scatters more than that of independent readings (a region much larger than the footprints
  // is worth about n / 13.9 readings with matched Bayer demosaicking, n / 3.3 with matched 5x5
  // cells). With brightness readings, pi/2 over n over the window widened by the footprint.
  // NaN without a reading.
  double median_uncertainty_c(const cv::Mat& temperature_c, const cv::Mat& uncertainty_c,
                              const cv::Mat& mask) const;
  // k times the systematic standard uncertainty of a reading at t_c (calibration, QE model,
  // emissivity slope; no noise): ratiotemp's peak-u-sys-c. NaN for NaN.
  double systematic_expanded_u_c(double t_c) const {
    return std::isfinite(t_c) ? model_->uncertainty.coverage_factor *
                                    planes_estimator_.estimator().systematic_u_c(t_c)
                              : NAN;
  }
  // With MeasureOptions::check_layout, what the frames measured so far say about their mosaic's
  // phase: a Bayer mosaic whose greens sit on the other diagonal (bayer_greens_elsewhere over
  // every frame's lit cells of every 4th cell row; decided from 256 such cells) or frames that
  // are no Bayer mosaic (bayer_greens_disagree: the pattern's greens differ), and the fit
  // audit (PlaneEstimator::take_fit_audit, one reading in 64 of every row: of those checked
  // against the model's band spectra, how many misfit; most of 16 or more misfitting: bands in
  // the wrong places or another camera; with the frames' exposure set, most of them over
  // PlaneEstimator::kImpossibleBrightness times as bright as a black body at their reading: red
  // and blue traded). A message for each that fails, none when they pass or cannot tell yet.
  std::vector<std::string> layout_problems() const;
  // The exposure of the next frames, microseconds (a dataset row's), for the fit audit's
  // brightness count; 0 or not finite: unknown (the default), not counted.
  void set_exposure_us(double exposure_us) { planes_estimator_.set_exposure_us(exposure_us); }
  // With MeasureOptions::check_layout, whether the darks subtracted looked off on the frames
  // measured so far (dark_level_check.h, as darksub checks it): a message for each that did.
  // Each dark named by set_dark_name is checked on its own frames (a dataset's darks are one
  // per exposure: one wrong among them was missed where one check took every frame), and named.
  const std::vector<std::string>& dark_level_problems() const { return dark_level_problems_; }
  // The dark the next frames are measured with (a file name, for the checks' messages); frames
  // measured without a name share one check.
  void set_dark_name(const std::string& name) { dark_name_ = name; }
  const MosaicLayout& layout() const { return layout_; }
  // How the method reads graybodies hotter than the model's range (fold_above_range): a network
  // trained only up to a narrow range's end reads them as temperatures inside it.
  AboveRangeFold above_range_fold() const {
    return fold_above_range(*model_, planes_estimator_.estimator());
  }

  // Adds a table file's blocks (the model's prebuilt lookup table, prebuilt_tables.h) to the
  // estimator's table: the same readings, without filling those blocks on the first frames.
  // Returns how many it added (0 for a method without a table); throws InputError as
  // TemperatureEstimator::load_tables, adding none.
  std::size_t load_tables(const std::string& path) const {
    return planes_estimator_.estimator().load_tables(path);
  }

 private:
  std::shared_ptr<const ThermalModel> model_;
  MeasureOptions options_;
  MosaicLayout layout_;
  PlaneEstimator planes_estimator_;
  std::optional<BlurBiasCorrection> blur_correction_;
  std::optional<CurvatureCheck> curvature_;  // made on the first frame of the fused path
  std::optional<ScaledBrightness> brightness_;
  std::optional<SnapshotBrightness> snapshot_brightness_;
  cv::Mat signal_, codes_;
  std::vector<cv::Mat> planes_;
  BayerCellSums phase_sums_;
  struct DarkCheck {
    DarkLevelWatch watch;
    bool said = false;
  };
  std::map<std::string, DarkCheck> dark_checks_;  // by dark name
  std::string dark_name_;
  std::vector<std::string> dark_level_problems_;
  std::size_t audit_checked_ = 0, audit_misfit_ = 0, audit_too_bright_ = 0;
  std::size_t above_range_ = 0;
};

}  // namespace pyrocam
