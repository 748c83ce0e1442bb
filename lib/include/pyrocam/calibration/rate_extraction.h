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

  // temperatures x bands; NaN where a fit is missing.
  Eigen::MatrixXd rates() const;
  // The references as the QE fit takes them (CalibrationRates::references), in the same order.
  std::vector<ReferenceRates> reference_rates() const;
};

struct ExtractOptions {
  double saturated_pixel_fraction = 1e-3;  // more ROI pixels than this at full scale: saturated
  unsigned threads = 2;
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

}  // namespace pyrocam
