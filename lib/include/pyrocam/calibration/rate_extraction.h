// Calibration preprocessing (METHOD.md section 3): rate extraction, from a furnace dataset to
// per-band signal rates s_b(T), streaming images one at a time.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "pyrocam/calibration/qe_fit.h"
#include "pyrocam/core/dataset.h"
#include "pyrocam/core/profile.h"

namespace pyrocam {

// One averaged (temperature, exposure) setting reduced to per-band ROI means.
struct SettingMeans {
  double temperature_c = 0;
  double exposure_us = 0;
  int frames = 0;
  Eigen::VectorXd raw_mean_dn;         // per band, before dark subtraction
  Eigen::VectorXd net_mean_dn;         // per band, dark subtracted
  Eigen::VectorXd saturated_fraction;  // per band, ROI pixels at full scale in any frame
};

// Why a point was left out of a slope fit.
enum class PointStatus { kUsed, kDim, kSaturated };

struct SlopeFit {
  double rate_dn_per_s = NAN;  // slope; NaN when fewer than 2 usable points
  double intercept_dn = NAN;
  double r_squared = NAN;
  int points = 0;
};

// One reference source (the manifest rows of kind reference at one temperature, in
// reference-roi.png when the dataset has one, else in the ROI): its settings over exposure, why
// points were left out, one slope per band. Its absolute scale is unknown.
struct ReferenceSweep {
  std::string name;  // "reference 1738 degC (manifest line 12)"
  double temperature_c = 0;
  double temperature_uncertainty_c = kDefaultReferenceUncertaintyC;  // k=1, degC
  int line = 0;                                  // the source's first manifest line
  std::vector<SettingMeans> settings;            // sorted by exposure
  std::vector<std::vector<PointStatus>> status;  // [setting][band]
  std::vector<SlopeFit> fits;                    // [band]; NaN rate below 2 usable points
};

// Where each furnace temperature's line of net signal against exposure meets zero exposure. The
// dark frames remove the sensor's offset; what they leave (a black level that moved between the
// darks and the frames, say) is one offset per band, the same at every temperature. A line with
// its own offset at each temperature absorbs that too, but its slope is two to three times as
// noisy.
enum class RateOffsets {
  kSelect,   // one offset per band unless the temperatures' own offsets differ beyond noise
  kCommon,   // one offset per band, shared by every temperature
  kPerStep,  // each temperature's line has its own offset
};

// The test behind RateOffsets::kSelect: chi2 = sum over bands of (RSS with one offset per band -
// RSS with one per temperature) / s_b^2, s_b^2 the band's residual variance about its own
// lines, on sum over bands of (temperatures - 1) degrees of freedom; one offset per band when
// chi2 is at most the chi2 quantile at `level`.
struct RateOffsetTest {
  bool common = false;  // the rates are those of one offset per band
  bool tested = true;   // false: the choice was asked for (ExtractOptions::offsets)
  double chi2 = NAN, threshold = NAN;
  int degrees_of_freedom = 0;
  Eigen::VectorXd common_offset_dn;  // per band; NaN where the band has no line
};

struct RateTable {
  std::vector<double> temperatures_c;
  std::vector<std::string> band_names;
  std::vector<SettingMeans> settings;            // every frame setting, sorted by T then exposure
  std::vector<std::vector<SlopeFit>> fits;       // [temperature][band]
  std::vector<std::vector<PointStatus>> status;  // [setting][band]
  std::vector<std::string> warnings;             // e.g. "1100 degC band R: 1 usable point"
  // The reference sources, sorted by temperature; apart from the furnace settings above, which
  // they never enter (temperatures_c, settings, fits and rates() are the furnace's alone).
  std::vector<ReferenceSweep> references;
  RateOffsetTest offsets;  // the furnace lines' offsets (references keep one per sweep)

  // temperatures x bands; NaN where a fit is missing.
  Eigen::MatrixXd rates() const;
  // The references as the QE fit takes them (CalibrationRates::references), in the same order.
  std::vector<ReferenceRates> reference_rates() const;
};

struct ExtractOptions {
  double saturated_pixel_fraction = 1e-3;  // more ROI pixels than this at full scale: saturated
  unsigned threads = 2;
  RateOffsets offsets = RateOffsets::kSelect;
  double offsets_test_level = 0.99;
};

using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

// Streams every image once (a dark twice when reference-roi.png needs its means there too).
// Throws InputError when the profile does not match the images (bit depth, mosaic period), a
// band has no usable furnace points at all, or a reference has fewer than 2 bands with 2 usable
// exposures (all dim or saturated, say), naming the reference's manifest line.
RateTable extract_rates(const Dataset& dataset, const CameraProfile& profile,
                        const ExtractOptions& options = {}, const ProgressFn& progress = {});

// Classifies a setting's band against the profile's calibration thresholds.
PointStatus classify_point(const CameraProfile& profile, double raw_mean_dn, double net_mean_dn,
                           double saturated_fraction, double saturated_limit);

// Least-squares line through (exposure_us, net DN); slope returned per second.
SlopeFit fit_line(const std::vector<double>& exposure_us, const std::vector<double>& net_dn);

// Least-squares lines through several sweeps (exposure_us[i], net_dn[i]) that share one offset:
// one slope per sweep (NaN below 2 points), each fit's intercept_dn the shared offset.
std::vector<SlopeFit> fit_lines_common_offset(const std::vector<std::vector<double>>& exposure_us,
                                              const std::vector<std::vector<double>>& net_dn);

// The words for a table's offsets, for the report: "one per band (chi2 712.3 <= 868.1 on 775
// degrees of freedom)" and the like.
std::string rate_offsets_summary(const RateOffsetTest& test);

}  // namespace pyrocam
