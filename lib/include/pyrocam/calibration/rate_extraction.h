// Calibration preprocessing (METHOD.md section 3): rate extraction, from a furnace dataset to
// per-band signal rates s_b(T), streaming images one at a time.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

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

struct RateTable {
  std::vector<double> temperatures_c;
  std::vector<std::string> band_names;
  std::vector<SettingMeans> settings;            // every frame setting, sorted by T then exposure
  std::vector<std::vector<SlopeFit>> fits;       // [temperature][band]
  std::vector<std::vector<PointStatus>> status;  // [setting][band]
  std::vector<std::string> warnings;             // e.g. "1100 degC band R: 1 usable point"

  // temperatures x bands; NaN where a fit is missing.
  Eigen::MatrixXd rates() const;
};

struct ExtractOptions {
  double saturated_pixel_fraction = 1e-3;  // more ROI pixels than this at full scale: saturated
  unsigned threads = 2;
};

using ProgressFn = std::function<void(std::size_t done, std::size_t total)>;

// Streams every image once. Throws InputError when the profile does not match the images
// (bit depth, mosaic period) or a band has no usable points at all.
RateTable extract_rates(const Dataset& dataset, const CameraProfile& profile,
                        const ExtractOptions& options = {}, const ProgressFn& progress = {});

// Classifies a setting's band against the profile's calibration thresholds.
PointStatus classify_point(const CameraProfile& profile, double raw_mean_dn, double net_mean_dn,
                           double saturated_fraction, double saturated_limit);

// Least-squares line through (exposure_us, net DN); slope returned per second.
SlopeFit fit_line(const std::vector<double>& exposure_us, const std::vector<double>& net_dn);

}  // namespace pyrocam
