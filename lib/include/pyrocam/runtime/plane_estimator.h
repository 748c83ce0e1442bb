// Per-pixel estimation over band planes, the same code path for the ratiotemp element and
// `pyrocam-calib measure` (through FrameMeasurer).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/mosaic.h"
#include "pyrocam/runtime/above_range.h"
#include "pyrocam/runtime/curvature_check.h"
#include "pyrocam/runtime/demosaic.h"
#include "pyrocam/runtime/dim_edge.h"
#include "pyrocam/runtime/emissivity.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/misfit.h"
#include "pyrocam/runtime/saturation_edge.h"

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

  // The fused path (demosaic25 linked to ratiotemp): the band planes of a dark-subtracted Bayer
  // mosaic (CV_32F, DN, the darksub marks) demosaicked with kMatched and `no_signal_dn` a strip
  // of rows at a time, each strip read while it is in the cache, so that the planes never cross
  // memory: the results of demosaic(mosaic, layout, kMatched, planes, no_signal_dn) followed by
  // estimate() or estimate_codes() with set_dim_edge_mosaic(&source), bit for bit. Blocks of
  // columns without light (every band 0, dim) get no reading without being read. Throws InputError
  // unless the layout is Bayer with the model's band count and the mosaic CV_32F.
  struct MatchedMosaic {
    cv::Mat mosaic;
    MosaicLayout layout;
    float no_signal_dn = 0;
  };
  void estimate(const MatchedMosaic& source, cv::Mat& temperature_c,
                cv::Mat* uncertainty_c = nullptr) const;
  void estimate_codes(const MatchedMosaic& source, cv::Mat& codes) const;
  // What reads the pixels: the method's estimator, or with an emissivity slope its
  // EmissivitySlopeEstimator.
  const TemperatureEstimator& estimator() const {
    return sloped_ ? static_cast<const TemperatureEstimator&>(*sloped_) : *estimator_;
  }
  // See TemperatureEstimator::set_partial_bands (off by default). With the network or its
  // table, pixels they cannot read because a band is saturated, invalid or dim are read by the
  // likelihood fit with those rules (with an emissivity slope, the fit corrected for it). Not
  // while an estimate runs; the fit is built when first needed.
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
  // The frames' exposure, microseconds, for the fit audit's brightness count; 0 (the default)
  // or not finite: unknown, not counted. Not while an estimate runs.
  void set_exposure_us(double exposure_us) {
    exposure_s_ = exposure_us > 0 && std::isfinite(exposure_us) ? exposure_us * 1e-6 : 0;
  }
  // What demosaicking did to the band values' noise (demosaic_noise of the layout and method
  // that made the planes), for the uncertainty; by default none (each value one sample's, an
  // overestimate after averaging kernels). The fused path always uses kMatched's. Not while an
  // estimate runs; cheap where it does not change (called per frame by ratiotemp).
  void set_demosaic_noise(const DemosaicNoise& noise) { noise_ = noise; }
  // The mosaic the planes were demosaicked from, where it is a fused path's (a Bayer mosaic,
  // kMatched, no mixed-pixel marks), for the dim-edge check (dim_edge.h): the planes path then
  // takes its ring from the mosaic, as the fused path does, and reads what it reads bit for bit;
  // null (the default): from the planes. Held until set again; not while an estimate runs.
  void set_dim_edge_mosaic(const MatchedMosaic* source) { dim_edge_mosaic_ = source; }
  // A curvature check (curvature_check.h) that estimate_codes() of a matched mosaic applies to
  // each run of codes while its rows are in the cache: the codes CurvatureCheck::apply_codes
  // gives afterwards, without a pass of its own over the frame. Null (the default): none. Held
  // until set again; not while an estimate runs.
  void set_curvature_check(const CurvatureCheck* check) { curvature_ = check; }
  // Whether the dim-edge check applies: where every band must read (no partial fit).
  bool checks_dim_edges() const { return !reads_partial(); }
  // The raw level (DN) from which the planes' samples were marked saturated (darksub's
  // saturation-level), for the saturation-edge check (saturation_edge.h), which runs on every
  // path; 0 or less: the model profile's inference saturation threshold (the default); +INF: no
  // check (planes that are not images, such as rows of unrelated pixels). Not while an estimate
  // runs.
  void set_saturation_level(double raw_dn) { saturation_level_dn_ = raw_dn; }

  // The above-range check (above_range.h) on the pixels the estimator leaves without a reading
  // although every band reads: off by default. Turned on, it is built on a thread of its own
  // (tens of ms; an estimate waits for it only where a pixel needs it) and every estimate collects
  // the pixels it finds hotter than the model's range (with the grey fit, whatever the emissivity
  // slope), which take_above_range() hands over: pixel positions of the planes (of the mosaic on
  // the fused path), in no particular order. Costs nothing where every pixel with all its bands
  // reads; about 0.5 us of CPU for each pixel checked, at most kAboveRangeBudget pixels an
  // estimate (which of them then depends on the threads). Not while an estimate runs.
  void set_above_range_check(bool on);
  bool above_range_check() const { return above_build_.valid() || above_ != nullptr; }
  std::vector<cv::Point> take_above_range() const;

  // How well the readings fit the model's band spectra, whatever the misfit setting: a few
  // readings of every kFitAuditRows-th row (run on the fused path) go through the band-consistency
  // check at kFitAuditProbability with kFitAuditModelError, and are counted. Most of them
  // failing means the bands are not what the model expects: a mosaic read with the wrong phase
  // or layout (a crop by an odd number of rows or columns at the top or left, or a flip, before
  // darksub), or a model of another camera. The readings then look right and are not, which
  // only such a check can tell (ratiotemp warns). The counts since the last take_fit_audit;
  // the first call starts making the check's tables on a thread of its own, and nothing is
  // counted until a later call finds them made (an estimator never asked costs nothing), or
  // with `wait` until the call itself has waited for them. Not while an estimate runs.
  static constexpr double kFitAuditProbability = 1e-9, kFitAuditModelError = 0.05;
  // Readings between checked ones in a row: one per row of a 2048-wide plate. (Eight, at 256, of
  // every 4th row took 3 % of the colour chain's CPU on a 90 % plate; the verdict needs 32.)
  static constexpr std::size_t kFitAuditStride = 2048;
  static constexpr std::size_t kFitAuditRows = 16;  // of the rows, those checked
  // With the frames' exposure known (set_exposure_us), the audit also counts the checked
  // readings whose signals are more than kImpossibleBrightness times those of a black body at
  // the reading (at the analogue gain set): no surface emits more than a black body, and the
  // calibration's optics differ from the camera's now by an aperture or a filter, not by a
  // thousand. A reading that far too cold is wrong: a colour camera's red and blue traded
  // (a bggr sensor read as rggb) read a 1300 degC plate near 630 degC, about 10 000 times too
  // bright, and land on the locus, so the band check cannot tell (below about 1200 degC the factor
  // falls under a thousand and near the bands' crossing, about 900 degC, the trade reads right).
  static constexpr double kImpossibleBrightness = 1000;
  struct FitAudit {
    std::size_t checked = 0, misfit = 0;
    std::size_t too_bright = 0;  // of the checked, with the exposure known; 0 otherwise
  };
  FitAudit take_fit_audit(bool wait = false) const;
  // A denser sample for offline use, where frames are few and time is not short: every
  // `every_rows`-th row, every `stride`-th of a row's readings (both at least 1). Not while an
  // estimate runs.
  void set_fit_audit_sampling(std::size_t every_rows, std::size_t stride) {
    audit_rows_ = std::max<std::size_t>(every_rows, 1);
    audit_stride_ = std::max<std::size_t>(stride, 1);
  }

 private:
  // The planes' common size; throws InputError unless they are the model's bands, CV_32F, of
  // one size.
  cv::Size checked_size(const std::vector<cv::Mat>& planes) const;
  // Both estimates: the rows' temperatures into `out` (and the misfit check).
  void estimate_row(const float* const* rows, std::size_t n, float* out) const;
  // Uncertainties of the n readings `t` of the rows into `out` (NaN where no reading): output
  // pixels x0 .. x0 + n - 1 of row y, with `noise`.
  void uncertainty_row(const float* const* rows, std::size_t n, const float* t, float* out, int x0,
                       int y, const DemosaicNoise& noise) const;
  // The dim-edge check (dim_edge.h) for planes of that noise, or null where pixels with a band
  // below the dim threshold go to the likelihood fit (partial bands).
  std::unique_ptr<const DimEdgeCheck> dim_edge_check(const DemosaicNoise& noise) const;
  SaturationEdgeCheck saturation_edge_check() const;
  bool reads_partial() const;
  // The ring means the checks read: of the mosaic, or of the planes (set_dim_edge_mosaic), with
  // saturated values counted as `saturated` and NaN where one lies above `foreign_above`.
  static RingMeans mosaic_window_mean_of(const MatchedMosaic& source, double saturated = INFINITY,
                                         double foreign_above = INFINITY);
  RingMeans planes_ring_mean_of(const std::vector<cv::Mat>& planes, double saturated = INFINITY,
                                double foreign_above = INFINITY) const;
  // Throws InputError for a source the fused path cannot read with this model.
  void check_matched_mosaic(const MatchedMosaic& source) const;
  // The fused path's strips: for each row of each strip, `lit_run(y, x0, x1, rows, scratch,
  // band_scratch)` for runs of blocks with light (rows: the bands' values at x0; scratch: room
  // for a row of floats; band_scratch: the thread's for SaturationEdgeCheck::apply) and
  // `dark_run(y, x0, x1)` for the others.
  template <class LitRun, class DarkRun>
  void for_each_strip(const MatchedMosaic& source, const LitRun& lit_run,
                      const DarkRun& dark_run) const;

  std::shared_ptr<const ThermalModel> model_;
  std::shared_ptr<TemperatureEstimator> estimator_;
  // Null for a grey surface; at a slope of 0 it carries the slope's uncertainty only, and the
  // readings are the grey ones (reads_sloped()).
  std::unique_ptr<EmissivitySlopeEstimator> sloped_;
  bool reads_sloped() const { return sloped_ && sloped_->alpha() != 0; }
  void make_sloped_partial_fit();
  double alpha_u_ = -1;  // as set
  // Made when the check is first turned on (its tables cost a locus).
  std::unique_ptr<MisfitCheck> misfit_;
  Method method_;
  // The likelihood fit for the pixels the network or its table cannot read (set_partial_bands).
  std::shared_ptr<TemperatureEstimator> partial_fit_;
  // partial_fit_ corrected for a non-zero emissivity slope (set_emissivity_slope).
  std::unique_ptr<EmissivitySlopeEstimator> sloped_partial_fit_;
  TemperatureEstimator::PartialBands partial_ = TemperatureEstimator::PartialBands::kOff;
  bool partial_set_ = false;
  double analogue_gain_ = 1.0;
  double exposure_s_ = 0;  // 0: unknown
  DemosaicNoise noise_;
  const MatchedMosaic* dim_edge_mosaic_ = nullptr;
  const CurvatureCheck* curvature_ = nullptr;
  double saturation_level_dn_ = 0;  // 0 or less: the profile's
  // The audit's check (its own tables; made by the first take_fit_audit) and counts, shared by
  // the rows' threads.
  mutable std::unique_ptr<MisfitCheck> audit_;
  mutable std::future<std::unique_ptr<MisfitCheck>> audit_build_;
  mutable bool audit_refused_ = false;
  struct AuditCounts {
    std::atomic<std::size_t> checked{0}, misfit{0}, too_bright{0}, rows{0};
  };
  std::unique_ptr<AuditCounts> audit_counts_ = std::make_unique<AuditCounts>();
  std::size_t audit_rows_ = kFitAuditRows, audit_stride_ = kFitAuditStride;
  // The above-range check, once built, and what it found since the last take_above_range.
  mutable std::future<std::shared_ptr<const AboveRangeCheck>> above_build_;
  mutable std::shared_ptr<const AboveRangeCheck> above_;
  mutable std::mutex above_mutex_;
  mutable std::vector<cv::Point> above_found_;
  mutable std::atomic<std::size_t> above_checked_{0};  // this estimate's, up to kAboveRangeBudget
  // Pixels that needed the check before it was built, and their signals (bands each).
  mutable std::vector<cv::Point> above_pending_points_;
  mutable std::vector<double> above_pending_signals_;
  // Before an estimate's rows run: a new frame's budget, and the check if it is built by now.
  void ready_above_range() const;
  // Waits for the build and takes the check (with the analogue gain).
  void adopt_above_range() const;
  // After the rows: the pending pixels checked (waiting for the build only if there are any).
  void finish_above_range() const;
  // The check on the readings `out` of the rows (n pixels from x0 of row y) that have none.
  void above_range_row(const float* const* rows, std::size_t n, const float* out, int x0,
                       int y) const;
  // Checks a few of the n readings `out` of the rows (signals as the reading saw them).
  void audit_row(const float* const* rows, std::size_t n, const float* out) const;
};

}  // namespace pyrocam
