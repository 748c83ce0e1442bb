#include "pyrocam/runtime/frame_measurer.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/core/temperature_codes.h"
#include "pyrocam/runtime/darksub.h"
#include "pyrocam/runtime/dim_edge.h"
#include "pyrocam/runtime/region_stats.h"

namespace pyrocam {
namespace {

// As darksub's phase check: lit cells of every 4th cell row, a verdict from 256 of them. The fit
// audit samples every row, every 64th reading of it (frames are few here, time is not short),
// and decides from 16 readings: with a few percent of a scene's readings misfit (edges,
// reflections), more than half of 16 is a chance of about 1e-8 (binomial, p = 0.05).
constexpr int kPhaseCellRowStep = 4;
constexpr std::size_t kPhaseCells = 256, kAuditReadings = 16, kAuditStride = 64;

}  // namespace

FrameMeasurer::FrameMeasurer(std::shared_ptr<const ThermalModel> model,
                             const MeasureOptions& options)
    : model_(std::move(model)),
      options_(options),
      layout_(model_ ? model_->profile().mosaic : MosaicLayout{}),
      planes_estimator_(model_, options.method, options.misfit_probability) {
  if (!options.bayer_pattern.empty()) {
    if (layout_.kind != MosaicLayout::Kind::kBayer)
      throw InputError("a Bayer pattern (" + options.bayer_pattern + ") for a model of " +
                       model_->profile().name + ", whose camera has a snapshot mosaic");
    layout_ = MosaicLayout::bayer(options.bayer_pattern);
  }
  planes_estimator_.set_partial_bands(
      options.allow_partial  ? TemperatureEstimator::PartialBands::kAny
      : options.safe_partial ? TemperatureEstimator::PartialBands::kSafe
                             : TemperatureEstimator::PartialBands::kOff);
  planes_estimator_.set_emissivity_slope(options.emissivity_slope, options.emissivity_slope_u);
  planes_estimator_.set_analogue_gain(analogue_gain_factor(options.gain_db));
  planes_estimator_.set_demosaic_noise(demosaic_noise(layout_, options.demosaic));
  planes_estimator_.set_above_range_check(true);
  if (options.blur_correction) blur_correction_.emplace(*model_, options.demosaic);
  if (options.brightness_radius != 0 && layout_.kind == MosaicLayout::Kind::kSnapshot) {
    snapshot_brightness_.emplace(*model_, options.brightness_radius);
    snapshot_brightness_->set_analogue_gain(analogue_gain_factor(options.gain_db));
  } else if (options.brightness_radius != 0) {
    if (resolve_demosaic_method(options.demosaic, layout_) == DemosaicMethod::kBinCells)
      throw InputError(
          "brightness readings of a Bayer mosaic need it demosaicked at full resolution (not "
          "binned)");
    brightness_.emplace(*model_, options.brightness_radius, layout_);
  }
  // NaN would mark no sample saturated, and a saturated band would read.
  if (!std::isfinite(options_.saturation_level_dn))
    throw InputError(
        "the saturation level must be a finite number of DN (negative: the "
        "model's), not " +
        std::to_string(options_.saturation_level_dn));
  if (options_.saturation_level_dn < 0)
    options_.saturation_level_dn = model_->profile().thresholds.inference_saturation_dn;
  // Above the full scale no sample is saturated, and a saturated band reads (too hot).
  if (options_.saturation_level_dn > model_->profile().max_dn())
    throw InputError("the saturation level " + std::to_string(options_.saturation_level_dn) +
                     " DN is above the " + std::to_string(model_->profile().bit_depth) +
                     "-bit camera's full scale, " + std::to_string(model_->profile().max_dn()) +
                     " DN: no sample would count as saturated");
  planes_estimator_.set_saturation_level(options_.saturation_level_dn);
  if (options.check_layout) {
    planes_estimator_.set_fit_audit_sampling(1, kAuditStride);
    planes_estimator_.take_fit_audit(true);  // its tables, now
  }
}

cv::Size FrameMeasurer::output_size(cv::Size raw) const {
  return demosaic_output_size(layout_, options_.demosaic, raw);
}

FrameMeasurer::Unread FrameMeasurer::unread(const cv::Mat& temperature_c,
                                            const cv::Mat& mask) const {
  Unread u;
  // Dim: below the threshold, or near it where the dim-edge check refuses what reaches it.
  const DimEdgeCheck near(model_->profile(), analogue_gain_factor(options_.gain_db),
                          demosaic_noise(layout_, options_.demosaic));
  const bool checked = planes_estimator_.checks_dim_edges();
  // Saturated: marked so, or near the level, where the saturation-edge check may mark it.
  const SaturationEdgeCheck near_level(model_->profile(), analogue_gain_factor(options_.gain_db),
                                       options_.saturation_level_dn);
  const float dim_dn = static_cast<float>(model_->profile().thresholds.inference_dim_dn);
  for (int y = 0; y < temperature_c.rows; ++y)
    for (int x = 0; x < temperature_c.cols; ++x) {
      if (std::isfinite(temperature_c.at<float>(y, x))) continue;
      if (!mask.empty() && mask.at<std::uint8_t>(y, x) == 0) continue;
      bool saturated = false, dim_band = false;
      for (std::size_t b = 0; b < planes_.size(); ++b) {
        const cv::Mat& plane = planes_[b];
        if (plane.size() != temperature_c.size()) continue;
        const float v = plane.at<float>(y, x);
        saturated |= v >= near_level.checked_dn(static_cast<int>(b));
        dim_band |= v < (checked ? near.checked_dn(static_cast<int>(b)) : dim_dn);
      }
      u.saturated += saturated && !dim_band;
      u.dim += !saturated && dim_band;
      u.both += saturated && dim_band;
    }
  return u;
}

double FrameMeasurer::median_uncertainty_c(const cv::Mat& temperature_c,
                                           const cv::Mat& uncertainty_c,
                                           const cv::Mat& mask) const {
  const TemperatureEstimator& estimator = planes_estimator_.estimator();
  const double k = model_->uncertainty.coverage_factor;
  std::vector<double> readings, noise;
  cv::Mat used = cv::Mat::zeros(temperature_c.size(), CV_8U);
  for (int y = 0; y < temperature_c.rows; ++y)
    for (int x = 0; x < temperature_c.cols; ++x) {
      const double t = temperature_c.at<float>(y, x), u = uncertainty_c.at<float>(y, x);
      if (!std::isfinite(t) || !std::isfinite(u)) continue;
      if (!mask.empty() && mask.at<std::uint8_t>(y, x) == 0) continue;
      const double systematic = estimator.systematic_u_c(t);
      readings.push_back(t);
      noise.push_back(std::sqrt(std::max(0.0, (u / k) * (u / k) - systematic * systematic)));
      used.at<std::uint8_t>(y, x) = 1;
    }
  if (readings.empty()) return NAN;
  const auto median = [](std::vector<double>& v) {
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
  };
  const auto n = static_cast<double>(readings.size());
  const double t_median = median(readings), u_noise = median(noise);
  // Neighbouring readings share their demosaicking footprints' samples, so n readings are worth
  // fewer independent ones. A brightness reading's scale is a mean over its window of ratio
  // readings, each reaching its footprint's samples: counted as one per window widened by the
  // footprint (5 x 5 pixels), an upper bound on the sharing, with a median's sqrt(pi/2).
  // A snapshot cell's window is widened by the matched kernels' 3 x 3 cells.
  const double window = brightness_            ? brightness_->window_pixels() + 4
                        : snapshot_brightness_ ? snapshot_brightness_->window_cells() + 2
                                               : 0;
  const double share =
      window > 0 ? (n > 2 ? M_PI / 2 : 1.0) / std::max(1.0, n / (window * window))
                 : median_noise_share(used, demosaic_noise_area(layout_, options_.demosaic));
  const double systematic = estimator.systematic_u_c(t_median);
  return k * std::sqrt(systematic * systematic + share * u_noise * u_noise);
}

void FrameMeasurer::measure(const cv::Mat& raw, const cv::Mat& dark, cv::Mat& temperature_c,
                            cv::Mat* uncertainty_c) {
  // A frame of another camera would still give numbers, and plausible ones: refuse what can be
  // told from the frame alone.
  const CameraProfile& profile = model_->profile();
  layout_.check_whole_periods(raw.cols, raw.rows, "raw frame for a model of " + profile.name);
  const int depth = profile.bit_depth <= 8 ? CV_8U : CV_16U;
  if (raw.channels() != 1 || raw.depth() != depth)
    throw InputError("raw frame: " +
                     std::string(raw.depth() == CV_8U    ? "8-bit"
                                 : raw.depth() == CV_16U ? "16-bit"
                                                         : cv::depthToString(raw.depth())) +
                     " " + std::to_string(raw.channels()) +
                     "-channel image, but the model's camera (" + profile.name + ") gives " +
                     std::to_string(profile.bit_depth) + "-bit single-channel frames");
  check_within_bit_depth(raw, profile.bit_depth, "raw frame for " + profile.name);
  if (dark.type() != CV_32F)
    check_within_bit_depth(dark, profile.bit_depth, "dark frame for " + profile.name);
  const cv::Mat dark_f = dark.type() == CV_32F ? dark : dark_from_image(dark);
  subtract_dark(raw, dark_f, options_.saturation_level_dn, signal_);
  measure_signal(signal_, temperature_c, uncertainty_c);
}

void FrameMeasurer::measure_signal(const cv::Mat& signal, cv::Mat& temperature_c,
                                   cv::Mat* uncertainty_c) {
  const CameraProfile& profile = model_->profile();
  if (signal.type() != CV_32F)
    throw InputError("dark-subtracted mosaic: must be float32, one value per sensor pixel");
  layout_.check_whole_periods(signal.cols, signal.rows, "mosaic for a model of " + profile.name);
  std::vector<SignalNoise> noise;
  for (int b = 0; b < profile.band_count(); ++b) noise.push_back(signal_noise(profile, b));
  const auto no_signal_dn = static_cast<float>(no_signal_level_dn(noise));
  if (options_.footprint_spread > 0) {
    FootprintCheck check;
    check.relative_spread = options_.footprint_spread;
    check.noise = noise;
    demosaic_marking_mixed(signal, layout_, options_.demosaic, check, planes_, no_signal_dn);
  } else {
    demosaic(signal, layout_, options_.demosaic, planes_, no_signal_dn);
  }
  // Where ratiotemp would take the fused path, the dim-edge check reads the mosaic as it does.
  const bool fused =
      options_.footprint_spread <= 0 && layout_.kind == MosaicLayout::Kind::kBayer &&
      resolve_demosaic_method(options_.demosaic, layout_) == DemosaicMethod::kMatched;
  const PlaneEstimator::MatchedMosaic source{signal, layout_, no_signal_dn};
  struct Unset {  // the mosaic is this call's
    PlaneEstimator& estimator;
    ~Unset() { estimator.set_dim_edge_mosaic(nullptr); }
  } unset{planes_estimator_};
  planes_estimator_.set_dim_edge_mosaic(fused ? &source : nullptr);
  planes_estimator_.estimate(planes_, temperature_c, uncertainty_c);
  above_range_ =
      above_range_spots(planes_estimator_.take_above_range(), temperature_c.size()).count;
  if (options_.check_layout) {
    if (layout_.kind == MosaicLayout::Kind::kBayer) {
      SignalNoise noisiest{0, 0};
      for (int b = 0; b < profile.band_count(); ++b) {
        const SignalNoise n = signal_noise(profile, b, analogue_gain_factor(options_.gain_db));
        noisiest = {std::max(noisiest.shot_gain, n.shot_gain),
                    std::max(noisiest.floor_dn2, n.floor_dn2)};
      }
      add_bayer_cell_sums(signal, std::max(4.0f, 0.02f * static_cast<float>(profile.max_dn())),
                          0.2f * static_cast<float>(profile.max_dn()), 0, kPhaseCellRowStep,
                          noisiest, phase_sums_);
    }
    DarkCheck& check = dark_checks_[dark_name_];
    if (!check.said) {
      const int period = layout_.kind == MosaicLayout::Kind::kSnapshot ? layout_.period_width : 2;
      const std::optional<DarkLevelVerdict> v = check.watch.add(signal, period, profile.bit_depth);
      if (v && v->offset_dn != 0) {
        check.said = true;
        dark_level_problems_.push_back(dark_level_message(*v, dark_name_, "the frames'"));
      }
    }
    const PlaneEstimator::FitAudit audit = planes_estimator_.take_fit_audit();
    audit_checked_ += audit.checked;
    audit_misfit_ += audit.misfit;
    audit_too_bright_ += audit.too_bright;
  }
  // As ratiotemp on the fused path: no reading where the field curves beyond the kernels.
  if (fused) {
    if (!curvature_) curvature_.emplace(*model_, layout_);
    curvature_->apply(signal, temperature_c);
    if (uncertainty_c) uncertainty_c->setTo(NAN, temperature_c != temperature_c);
  }
  if (blur_correction_ || brightness_ || snapshot_brightness_) {
    // On the codes, as ratiotemp reads them: a recording measured again gives its codes (the
    // blur correction on floats differed from ratiotemp's by a code on a quarter of a plate).
    encode_decikelvin(temperature_c, codes_);
    if (blur_correction_) blur_correction_->apply_codes(codes_);
    if (brightness_) brightness_->apply_codes(signal, codes_);
    if (snapshot_brightness_) snapshot_brightness_->apply_codes(planes_, codes_);
    decode_decikelvin(codes_).copyTo(temperature_c);
  }
}

std::vector<std::string> FrameMeasurer::layout_problems() const {
  std::vector<std::string> problems;
  std::string pattern = layout_.pattern;  // upper case in layouts, lower in the check
  std::transform(pattern.begin(), pattern.end(), pattern.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (phase_sums_.cells >= kPhaseCells && bayer_greens_elsewhere(phase_sums_, pattern)) {
    problems.push_back(
        "the frames' green samples sit on the other diagonal of the 2x2 cell than " + pattern +
        " puts them: the mosaic starts one row or one column further on (a readout window or "
        "crop at an odd row or column); its temperatures would look right and be wrong. Give "
        "the pattern the frames have (--pattern)");
  } else if (bayer_greens_disagree(phase_sums_, pattern)) {
    const int k = pattern == "rggb" || pattern == "bggr" ? 1 : 0;
    problems.push_back(
        "in " + std::to_string(phase_sums_.apart[k]) + " of " +
        std::to_string(phase_sums_.bright[k]) + " bright cells the two samples where " + pattern +
        " puts its greens differ by more than 12 % (a Bayer sensor's two greens agree within "
        "their noise): the frames are not a Bayer mosaic (a snapshot mosaic?) and its "
        "temperatures would look right and be wrong. Is the model (" +
        model_->profile().name + ") for this camera?");
  }
  const auto of_checked = [&](std::size_t n) {
    return std::to_string(n) + " of " + std::to_string(audit_checked_) + " readings checked ";
  };
  const std::string model_question =
      " Is the model (" + model_->profile().name + ") for this camera?";
  if (audit_checked_ >= kAuditReadings && 2 * audit_too_bright_ > audit_checked_ &&
      layout_.kind == MosaicLayout::Kind::kBayer)
    problems.push_back(of_checked(audit_too_bright_) +
                       "are over a thousand times as bright as a black body at the temperature "
                       "read (at the frames' exposure): the temperatures are far too cold. Are red "
                       "and blue traded (a bggr sensor given as rggb)? Give the pattern the "
                       "camera's documentation gives (--pattern)." +
                       model_question);
  if (audit_checked_ >= kAuditReadings && 2 * audit_misfit_ > audit_checked_)
    problems.push_back(of_checked(audit_misfit_) +
                       "do not fit the model's band spectra (at a false-rejection probability of "
                       "1e-9): the temperatures are likely wrong. Is the mosaic's phase right (a "
                       "readout window or crop that starts other than on a whole mosaic period)?" +
                       model_question);
  return problems;
}

}  // namespace pyrocam
