#include "pyrocam/calibration/rate_extraction.h"

#include <atomic>
#include <cmath>
#include <mutex>
#include <thread>

#include "pyrocam/core/error.h"

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
                       const CameraProfile& profile, int bands) {
  GroupMeans out{Eigen::VectorXd::Zero(bands), Eigen::VectorXd::Zero(bands)};
  for (const auto& f : g.files) {
    const cv::Mat img = d.load(f);
    const int depth = img.depth() == CV_8U ? 8 : 16;
    if ((depth == 8) != (profile.bit_depth == 8))
      throw InputError(f.string() + ": " + std::to_string(depth) + "-bit image, the profile " +
                       profile.name + " describes a " + std::to_string(profile.bit_depth) +
                       "-bit camera");
    const BandSums s = depth == 8 ? acc.sums<std::uint8_t>(img, profile.max_dn())
                                  : acc.sums<std::uint16_t>(img, profile.max_dn());
    for (int b = 0; b < bands; ++b) {
      if (s.count[b] == 0)
        throw InputError(d.folder().string() + ": the ROI holds no pixel of band " +
                         profile.band_names[b]);
      out.mean[b] += s.sum[b] / s.count[b];
      out.saturated_fraction[b] = std::max(out.saturated_fraction[b], s.saturated[b] / s.count[b]);
    }
  }
  out.mean /= static_cast<double>(g.files.size());
  return out;
}

}  // namespace

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

RateTable extract_rates(const Dataset& d, const CameraProfile& profile,
                        const ExtractOptions& options, const ProgressFn& progress) {
  const int bands = profile.band_count();
  const RoiAccumulator acc(d.roi(), profile.mosaic, bands);
  if (d.width() % profile.mosaic.period_width || d.height() % profile.mosaic.period_height)
    throw InputError(d.folder().string() + ": images of " + std::to_string(d.width()) + "x" +
                     std::to_string(d.height()) + " are not whole " + profile.mosaic.pattern +
                     " mosaic periods (profile " + profile.name + ")");

  // Darks and frames alike are reduced to per-band ROI means, in parallel over settings.
  std::vector<const FrameGroup*> work;
  for (const auto& g : d.darks()) work.push_back(&g);
  for (const auto& g : d.frames()) work.push_back(&g);
  std::vector<GroupMeans> means(work.size());
  std::size_t total_files = 0;
  for (const auto* g : work) total_files += g->files.size();

  std::atomic<std::size_t> next{0}, files_done{0};
  std::mutex error_mutex, progress_mutex;
  std::string error;
  auto worker = [&] {
    for (std::size_t i; (i = next++) < work.size();) {
      try {
        means[i] = group_means(d, *work[i], acc, profile, bands);
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (error.empty()) error = e.what();
        next = work.size();
      }
      files_done += work[i]->files.size();
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

  RateTable table;
  table.band_names = profile.band_names;
  table.temperatures_c = d.temperatures_c();
  const std::size_t n_dark = d.darks().size();
  for (std::size_t i = 0; i < d.frames().size(); ++i) {
    const FrameGroup& g = d.frames()[i];
    std::size_t dark_index = 0;
    for (std::size_t k = 0; k < n_dark; ++k)
      if (same_exposure(d.darks()[k].exposure_us, g.exposure_us)) dark_index = k;
    SettingMeans s;
    s.temperature_c = g.temperature_c;
    s.exposure_us = g.exposure_us;
    s.frames = static_cast<int>(g.files.size());
    s.raw_mean_dn = means[n_dark + i].mean;
    s.net_mean_dn = s.raw_mean_dn - means[dark_index].mean;
    s.saturated_fraction = means[n_dark + i].saturated_fraction;
    std::vector<PointStatus> st(static_cast<std::size_t>(bands));
    for (int b = 0; b < bands; ++b)
      st[b] = classify_point(profile, s.raw_mean_dn[b], s.net_mean_dn[b], s.saturated_fraction[b],
                             options.saturated_pixel_fraction);
    table.settings.push_back(std::move(s));
    table.status.push_back(std::move(st));
  }

  std::vector<int> usable_per_band(static_cast<std::size_t>(bands), 0);
  for (double t : table.temperatures_c) {
    std::vector<SlopeFit> row;
    for (int b = 0; b < bands; ++b) {
      std::vector<double> x, y;
      for (std::size_t i = 0; i < table.settings.size(); ++i)
        if (table.settings[i].temperature_c == t && table.status[i][b] == PointStatus::kUsed) {
          x.push_back(table.settings[i].exposure_us);
          y.push_back(table.settings[i].net_mean_dn[b]);
        }
      SlopeFit f = fit_line(x, y);
      if (f.points < 2) {
        table.warnings.push_back(std::to_string(static_cast<int>(std::lround(t))) + " degC band " +
                                 profile.band_names[b] + ": " + std::to_string(f.points) +
                                 " usable point(s), no slope");
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
  return table;
}

}  // namespace pyrocam
