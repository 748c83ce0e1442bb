#include "pyrocam/calibration/rate_extraction.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <sstream>
#include <thread>

#include "detail/chi2.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/image_io.h"

namespace pyrocam {
namespace {

// Per-band ROI sums of one image and the count of ROI pixels at full scale.
struct BandSums {
  Eigen::VectorXd sum, saturated;
  Eigen::VectorXd count;
};

class RoiAccumulator {
 public:
  RoiAccumulator(const cv::Mat& roi, const MosaicLayout& mosaic, int bands) : bands_(bands) {
    // Spans of ROI pixels per row keep the inner loop free of mask tests.
    for (int y = 0; y < roi.rows; ++y) {
      const std::uint8_t* m = roi.ptr<std::uint8_t>(y);
      for (int x = 0; x < roi.cols;) {
        if (!m[x]) {
          ++x;
          continue;
        }
        const int start = x;
        while (x < roi.cols && m[x]) ++x;
        spans_.push_back({y, start, x});
      }
    }
    band_of_.resize(static_cast<std::size_t>(mosaic.period_width * mosaic.period_height));
    for (int py = 0; py < mosaic.period_height; ++py)
      for (int px = 0; px < mosaic.period_width; ++px)
        band_of_[py * mosaic.period_width + px] = mosaic.band_at(px, py);
    pw_ = mosaic.period_width;
    ph_ = mosaic.period_height;
  }

  template <typename T>
  BandSums sums(const cv::Mat& img, double full_scale) const {
    BandSums s{Eigen::VectorXd::Zero(bands_), Eigen::VectorXd::Zero(bands_),
               Eigen::VectorXd::Zero(bands_)};
    std::vector<double> sum(bands_), sat(bands_), cnt(bands_);
    for (const Span& sp : spans_) {
      const T* row = img.ptr<T>(sp.y);
      const int* bands_row = &band_of_[(sp.y % ph_) * pw_];
      for (int x = sp.x0; x < sp.x1; ++x) {
        const int b = bands_row[x % pw_];
        const double v = row[x];
        sum[b] += v;
        cnt[b] += 1;
        sat[b] += v >= full_scale;
      }
    }
    for (int b = 0; b < bands_; ++b)
      s.sum[b] = sum[b], s.saturated[b] = sat[b], s.count[b] = cnt[b];
    return s;
  }

 private:
  struct Span {
    int y, x0, x1;
  };
  int bands_, pw_ = 1, ph_ = 1;
  std::vector<Span> spans_;
  std::vector<int> band_of_;
};

struct GroupMeans {
  Eigen::VectorXd mean, saturated_fraction;
};

GroupMeans group_means(const Dataset& d, const FrameGroup& g, const RoiAccumulator& acc,
                       const std::string& roi_name, const CameraProfile& profile, int bands) {
  GroupMeans out{Eigen::VectorXd::Zero(bands), Eigen::VectorXd::Zero(bands)};
  for (const auto& f : g.files) {
    const cv::Mat img = d.load(f);
    const int depth = img.depth() == CV_8U ? 8 : 16;
    if ((depth == 8) != (profile.bit_depth == 8))
      throw InputError(f.string() + ": " + std::to_string(depth) + "-bit image, the profile " +
                       profile.name + " describes a " + std::to_string(profile.bit_depth) +
                       "-bit camera");
    check_within_bit_depth(img, profile.bit_depth, f.string() + " (profile " + profile.name + ")");
    const BandSums s = depth == 8 ? acc.sums<std::uint8_t>(img, profile.max_dn())
                                  : acc.sums<std::uint16_t>(img, profile.max_dn());
    for (int b = 0; b < bands; ++b) {
      if (s.count[b] == 0)
        throw InputError(roi_name + " holds no pixel of band " + profile.band_names[b]);
      out.mean[b] += s.sum[b] / s.count[b];
      out.saturated_fraction[b] = std::max(out.saturated_fraction[b], s.saturated[b] / s.count[b]);
    }
  }
  out.mean /= static_cast<double>(g.files.size());
  return out;
}

std::vector<PointStatus> classify_setting(const CameraProfile& profile, const SettingMeans& s,
                                          double saturated_limit) {
  std::vector<PointStatus> st(static_cast<std::size_t>(profile.band_count()));
  for (int b = 0; b < profile.band_count(); ++b)
    st[b] = classify_point(profile, s.raw_mean_dn[b], s.net_mean_dn[b], s.saturated_fraction[b],
                           saturated_limit);
  return st;
}

// Residual sum of squares of a sweep about a fitted line.
double residual_ss(const std::vector<double>& x_us, const std::vector<double>& y,
                   const SlopeFit& f) {
  if (f.points < 2 || !std::isfinite(f.rate_dn_per_s)) return 0;
  double ss = 0;
  for (std::size_t i = 0; i < x_us.size(); ++i) {
    const double r = y[i] - f.intercept_dn - f.rate_dn_per_s * 1e-6 * x_us[i];
    ss += r * r;
  }
  return ss;
}

// RateOffsetTest: whether the temperatures' own offsets differ beyond noise from one per band.
RateOffsetTest test_offsets(const std::vector<std::vector<std::vector<double>>>& x,
                            const std::vector<std::vector<std::vector<double>>>& y,
                            const std::vector<std::vector<SlopeFit>>& own,
                            const std::vector<std::vector<SlopeFit>>& common, double level) {
  RateOffsetTest test;
  test.chi2 = 0;
  test.common_offset_dn = Eigen::VectorXd::Constant(static_cast<Eigen::Index>(x.size()), NAN);
  for (std::size_t b = 0; b < x.size(); ++b) {
    double ss_own = 0, ss_common = 0;
    int lines = 0, residual_dof = 0;
    for (std::size_t t = 0; t < x[b].size(); ++t) {
      if (own[b][t].points < 2) continue;
      ++lines;
      residual_dof += own[b][t].points - 2;
      ss_own += residual_ss(x[b][t], y[b][t], own[b][t]);
      ss_common += residual_ss(x[b][t], y[b][t], common[b][t]);
      test.common_offset_dn[static_cast<Eigen::Index>(b)] = common[b][t].intercept_dn;
    }
    // A band whose lines have no residual freedom says nothing about its noise.
    if (lines < 2 || residual_dof < 1 || !(ss_own > 0)) continue;
    test.chi2 += (ss_common - ss_own) / (ss_own / residual_dof);
    test.degrees_of_freedom += lines - 1;
  }
  if (test.degrees_of_freedom > 0) {
    test.threshold = detail::chi2_quantile(test.degrees_of_freedom, level);
    test.common = test.chi2 <= test.threshold;
  } else {
    test.chi2 = NAN;  // nothing to test: each temperature keeps its own offset
  }
  return test;
}

std::string format_c(double t) {
  std::ostringstream o;
  o << t;
  return o.str();
}

// The slopes of one reference over its exposures; throws InputError unless 2 or more bands
// have one (the reference's scale is unknown, only its band ratios count).
void fit_reference(const Dataset& d, const CameraProfile& profile, ReferenceSweep& ref,
                   std::vector<std::string>& warnings) {
  const int bands = profile.band_count();
  std::vector<std::string> with_slope;
  bool any_used = false;
  for (int b = 0; b < bands; ++b) {
    std::vector<double> x, y;
    for (std::size_t i = 0; i < ref.settings.size(); ++i)
      if (ref.status[i][b] == PointStatus::kUsed) {
        x.push_back(ref.settings[i].exposure_us);
        y.push_back(ref.settings[i].net_mean_dn[b]);
      }
    any_used = any_used || !x.empty();
    SlopeFit f = fit_line(x, y);
    if (f.points < 2) {
      warnings.push_back(ref.name + " band " + profile.band_names[b] + ": " +
                         std::to_string(f.points) + " usable point(s), no slope");
      f.rate_dn_per_s = NAN;
    } else {
      with_slope.push_back(profile.band_names[b]);
    }
    ref.fits.push_back(f);
  }
  const std::string where = (d.folder() / "manifest.csv").string() + ": " + ref.name + ": ";
  const std::string levels = "between " + format_c(profile.thresholds.calibration_dim_dn) +
                             " DN net and " +
                             format_c(profile.thresholds.calibration_saturation_dn) + " DN raw";
  if (!any_used)
    throw InputError(where + "every band is dim or saturated at every one of its " +
                     std::to_string(ref.settings.size()) + " exposure(s) (" +
                     format_c(ref.settings.front().exposure_us) + "-" +
                     format_c(ref.settings.back().exposure_us) +
                     " us); choose exposures that put the bands " + levels);
  if (with_slope.size() < 2) {
    std::string names;
    for (const auto& n : with_slope) names += (names.empty() ? "" : ", ") + n;
    throw InputError(where + std::to_string(with_slope.size()) + " band(s) " +
                     (names.empty() ? "" : "(" + names + ") ") +
                     "with 2 or more usable exposures " + levels +
                     "; a reference needs 2 or more such bands, only its band ratios count");
  }
}

}  // namespace

std::vector<ReferenceRates> RateTable::reference_rates() const {
  std::vector<ReferenceRates> out;
  for (const auto& r : references) {
    ReferenceRates rr;
    rr.name = r.name;
    rr.temperature_c = r.temperature_c;
    rr.temperature_uncertainty_c = r.temperature_uncertainty_c;
    rr.rates.resize(static_cast<Eigen::Index>(r.fits.size()));
    for (std::size_t b = 0; b < r.fits.size(); ++b)
      rr.rates[static_cast<Eigen::Index>(b)] = r.fits[b].rate_dn_per_s;
    out.push_back(std::move(rr));
  }
  return out;
}

Eigen::MatrixXd RateTable::rates() const {
  Eigen::MatrixXd r(static_cast<Eigen::Index>(temperatures_c.size()),
                    static_cast<Eigen::Index>(band_names.size()));
  for (std::size_t t = 0; t < fits.size(); ++t)
    for (std::size_t b = 0; b < fits[t].size(); ++b)
      r(static_cast<Eigen::Index>(t), static_cast<Eigen::Index>(b)) = fits[t][b].rate_dn_per_s;
  return r;
}

PointStatus classify_point(const CameraProfile& profile, double raw_mean_dn, double net_mean_dn,
                           double saturated_fraction, double saturated_limit) {
  // Saturation is judged on raw values (the sensor clips before the dark is subtracted).
  if (raw_mean_dn > profile.thresholds.calibration_saturation_dn ||
      saturated_fraction > saturated_limit)
    return PointStatus::kSaturated;
  if (net_mean_dn < profile.thresholds.calibration_dim_dn) return PointStatus::kDim;
  return PointStatus::kUsed;
}

SlopeFit fit_line(const std::vector<double>& x_us, const std::vector<double>& y) {
  SlopeFit f;
  f.points = static_cast<int>(x_us.size());
  if (x_us.size() < 2) return f;
  const double n = static_cast<double>(x_us.size());
  double sx = 0, sy = 0;
  for (std::size_t i = 0; i < x_us.size(); ++i) sx += x_us[i], sy += y[i];
  const double mx = sx / n, my = sy / n;
  double sxx = 0, sxy = 0, syy = 0;
  for (std::size_t i = 0; i < x_us.size(); ++i) {
    sxx += (x_us[i] - mx) * (x_us[i] - mx);
    sxy += (x_us[i] - mx) * (y[i] - my);
    syy += (y[i] - my) * (y[i] - my);
  }
  if (!(sxx > 0)) return f;
  const double slope = sxy / sxx;
  f.rate_dn_per_s = slope * 1e6;
  f.intercept_dn = my - slope * mx;
  f.r_squared = syy > 0 ? (sxy * sxy) / (sxx * syy) : 1.0;
  return f;
}

std::vector<SlopeFit> fit_lines_common_offset(const std::vector<std::vector<double>>& x_us,
                                              const std::vector<std::vector<double>>& y) {
  // With the offset c fixed each slope is sum x (y - c) / sum x^2, so each residual is
  // u - c v, u = y - x Sxy / Sxx and v = 1 - x Sx / Sxx (uncentred sums): c = sum uv / sum v^2.
  double suv = 0, svv = 0;
  for (std::size_t t = 0; t < x_us.size(); ++t) {
    if (x_us[t].size() < 2) continue;
    double sx = 0, sxx = 0, sxy = 0;
    for (std::size_t i = 0; i < x_us[t].size(); ++i)
      sx += x_us[t][i], sxx += x_us[t][i] * x_us[t][i], sxy += x_us[t][i] * y[t][i];
    for (std::size_t i = 0; i < x_us[t].size(); ++i) {
      const double u = y[t][i] - x_us[t][i] * sxy / sxx, v = 1 - x_us[t][i] * sx / sxx;
      suv += u * v;
      svv += v * v;
    }
  }
  const double offset = svv > 0 ? suv / svv : 0;
  std::vector<SlopeFit> fits;
  for (std::size_t t = 0; t < x_us.size(); ++t) {
    SlopeFit f;
    f.points = static_cast<int>(x_us[t].size());
    if (f.points >= 2) {
      double sxx = 0, sxy = 0, my = 0;
      for (std::size_t i = 0; i < x_us[t].size(); ++i)
        sxx += x_us[t][i] * x_us[t][i], sxy += x_us[t][i] * (y[t][i] - offset), my += y[t][i];
      my /= f.points;
      const double slope = sxy / sxx;
      f.rate_dn_per_s = slope * 1e6;
      f.intercept_dn = offset;
      double ss = 0, st = 0;
      for (std::size_t i = 0; i < x_us[t].size(); ++i) {
        const double r = y[t][i] - offset - slope * x_us[t][i];
        ss += r * r;
        st += (y[t][i] - my) * (y[t][i] - my);
      }
      f.r_squared = st > 0 ? 1 - ss / st : 1.0;
    }
    fits.push_back(f);
  }
  return fits;
}

std::string rate_offsets_summary(const RateOffsetTest& test) {
  std::ostringstream o;
  o.precision(1);
  o << std::fixed;
  const std::string what = test.common ? "one per band" : "one per temperature";
  if (!test.tested) return what + " (as asked)";
  if (!std::isfinite(test.chi2)) return what + " (too few points to test)";
  o << what << " (chi2 " << test.chi2 << (test.common ? " <= " : " > ") << test.threshold << " on "
    << test.degrees_of_freedom << " degrees of freedom)";
  return o.str();
}

RateTable extract_rates(const Dataset& d, const CameraProfile& profile,
                        const ExtractOptions& options, const ProgressFn& progress) {
  const int bands = profile.band_count();
  const RoiAccumulator acc(d.roi(), profile.mosaic, bands);
  if (d.width() % profile.mosaic.period_width || d.height() % profile.mosaic.period_height)
    throw InputError(d.folder().string() + ": images of " + std::to_string(d.width()) + "x" +
                     std::to_string(d.height()) + " are not whole " + profile.mosaic.pattern +
                     " mosaic periods (profile " + profile.name + ")");

  // Darks, frames and references alike are reduced to per-band ROI means, in parallel over
  // settings; references (and the darks they subtract) in reference-roi.png when there is one.
  const bool own_reference_roi = d.has_reference_roi() && !d.references().empty();
  const RoiAccumulator ref_acc =
      own_reference_roi ? RoiAccumulator(d.reference_roi(), profile.mosaic, bands) : acc;
  const std::string roi_name = d.folder().string() + ": the ROI";
  const std::string ref_roi_name =
      own_reference_roi ? (d.folder() / kReferenceRoiFile).string() + ": the reference ROI"
                        : roi_name;
  struct Work {
    const FrameGroup* group;
    bool reference_roi;
  };
  std::vector<Work> work;
  for (const auto& g : d.darks()) work.push_back({&g, false});
  for (const auto& g : d.frames()) work.push_back({&g, false});
  for (const auto& g : d.references()) work.push_back({&g, true});
  const std::size_t first_ref_dark = work.size();
  if (own_reference_roi)
    for (const auto& g : d.darks())
      if (std::any_of(d.references().begin(), d.references().end(), [&](const FrameGroup& r) {
            return same_exposure(r.exposure_us, g.exposure_us);
          }))
        work.push_back({&g, true});
  std::vector<GroupMeans> means(work.size());
  std::size_t total_files = 0;
  for (const auto& w : work) total_files += w.group->files.size();

  std::atomic<std::size_t> next{0}, files_done{0};
  std::mutex error_mutex, progress_mutex;
  std::string error;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < work.size();) {
      try {
        means[i] = work[i].reference_roi
                       ? group_means(d, *work[i].group, ref_acc, ref_roi_name, profile, bands)
                       : group_means(d, *work[i].group, acc, roi_name, profile, bands);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (error.empty()) error = e.what();
        next = work.size();
      }
      files_done += work[i].group->files.size();
      if (progress) {
        std::lock_guard<std::mutex> lock(progress_mutex);
        progress(files_done, total_files);
      }
    }
  };
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < std::max(1u, options.threads); ++t) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
  if (!error.empty()) throw InputError(error);

  // The means of the dark of `exposure_us` in the furnace ROI or the reference's.
  const std::size_t n_dark = d.darks().size();
  auto dark_mean = [&](double exposure_us, bool reference_roi) -> const Eigen::VectorXd& {
    const std::size_t from = reference_roi && own_reference_roi ? first_ref_dark : 0;
    const std::size_t to = reference_roi && own_reference_roi ? work.size() : n_dark;
    std::size_t index = from;
    for (std::size_t k = from; k < to; ++k)
      if (same_exposure(work[k].group->exposure_us, exposure_us)) index = k;
    return means[index].mean;
  };
  auto setting_means = [&](std::size_t i) {
    const FrameGroup& g = *work[i].group;
    SettingMeans s;
    s.temperature_c = g.temperature_c;
    s.exposure_us = g.exposure_us;
    s.frames = static_cast<int>(g.files.size());
    s.raw_mean_dn = means[i].mean;
    s.net_mean_dn = s.raw_mean_dn - dark_mean(g.exposure_us, work[i].reference_roi);
    s.saturated_fraction = means[i].saturated_fraction;
    return s;
  };

  RateTable table;
  table.band_names = profile.band_names;
  table.temperatures_c = d.temperatures_c();
  for (std::size_t i = 0; i < d.frames().size(); ++i) {
    SettingMeans s = setting_means(n_dark + i);
    table.status.push_back(classify_setting(profile, s, options.saturated_pixel_fraction));
    table.settings.push_back(std::move(s));
  }

  // Each band's sweeps, one per temperature: the usable points' exposures and net means.
  const std::size_t steps = table.temperatures_c.size();
  std::vector<std::vector<std::vector<double>>> x(static_cast<std::size_t>(bands)), y(x);
  for (int b = 0; b < bands; ++b) {
    x[b].resize(steps);
    y[b].resize(steps);
    for (std::size_t t = 0; t < steps; ++t)
      for (std::size_t i = 0; i < table.settings.size(); ++i)
        if (table.settings[i].temperature_c == table.temperatures_c[t] &&
            table.status[i][b] == PointStatus::kUsed) {
          x[b][t].push_back(table.settings[i].exposure_us);
          y[b][t].push_back(table.settings[i].net_mean_dn[b]);
        }
  }
  std::vector<std::vector<SlopeFit>> own(static_cast<std::size_t>(bands)), common(own);
  for (int b = 0; b < bands; ++b) {
    for (std::size_t t = 0; t < steps; ++t) own[b].push_back(fit_line(x[b][t], y[b][t]));
    common[b] = fit_lines_common_offset(x[b], y[b]);
  }
  table.offsets = test_offsets(x, y, own, common, options.offsets_test_level);
  if (options.offsets != RateOffsets::kSelect) {
    table.offsets.common = options.offsets == RateOffsets::kCommon;
    table.offsets.tested = false;
  }
  const auto& chosen = table.offsets.common ? common : own;

  std::vector<int> usable_per_band(static_cast<std::size_t>(bands), 0);
  for (std::size_t t = 0; t < steps; ++t) {
    std::vector<SlopeFit> row;
    for (int b = 0; b < bands; ++b) {
      SlopeFit f = chosen[b][t];
      if (f.points < 2) {
        table.warnings.push_back(
            std::to_string(static_cast<int>(std::lround(table.temperatures_c[t]))) + " degC band " +
            profile.band_names[b] + ": " + std::to_string(f.points) + " usable point(s), no slope");
        f.rate_dn_per_s = NAN;
      } else {
        ++usable_per_band[b];
      }
      row.push_back(f);
    }
    table.fits.push_back(std::move(row));
  }
  for (int b = 0; b < bands; ++b)
    if (usable_per_band[b] == 0)
      throw InputError(d.folder().string() + ": band " + profile.band_names[b] +
                       " has no temperature with 2 usable points between " +
                       std::to_string(profile.thresholds.calibration_dim_dn) + " and " +
                       std::to_string(profile.thresholds.calibration_saturation_dn) + " DN");

  // Each reference temperature is one source; its settings come sorted by exposure.
  const std::size_t first_ref = n_dark + d.frames().size();
  for (std::size_t i = 0; i < d.references().size(); ++i) {
    const FrameGroup& g = d.references()[i];
    if (table.references.empty() ||
        std::abs(table.references.back().temperature_c - g.temperature_c) > 1e-6) {
      ReferenceSweep r;
      r.temperature_c = g.temperature_c;
      r.temperature_uncertainty_c = g.temperature_uncertainty_c;
      r.line = g.line;
      table.references.push_back(std::move(r));
    }
    ReferenceSweep& r = table.references.back();
    r.line = std::min(r.line, g.line);
    SettingMeans s = setting_means(first_ref + i);
    r.status.push_back(classify_setting(profile, s, options.saturated_pixel_fraction));
    r.settings.push_back(std::move(s));
  }
  for (auto& r : table.references) {
    r.name = "reference " + format_c(r.temperature_c) + " degC (manifest line " +
             std::to_string(r.line) + ")";
    fit_reference(d, profile, r, table.warnings);
  }
  return table;
}

}  // namespace pyrocam
