#include "pyrocam/runtime/region_stats.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

// Median of values (reordered); the mean of the middle two for an even count.
double median_of(std::vector<float>& values) {
  auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  double median = *mid;
  if (values.size() % 2 == 0) median = 0.5 * (median + *std::max_element(values.begin(), mid));
  return median;
}

// The peak search over one image: `valid` is 1 where a pixel has a reading inside the mask.
class PeakSearch {
 public:
  PeakSearch(const cv::Mat& t, const cv::Mat& valid, int window)
      : t_(t), valid_(valid), half_(window / 2), area_(window * window) {
    cv::boxFilter(valid_, valid_counts_, CV_16U, cv::Size(window, window), cv::Point(-1, -1), false,
                  cv::BORDER_CONSTANT);
  }

  // Window centred on pixel index i: the best so far unless its median is larger. Only windows
  // wholly inside the image: one cut by its edge holds fewer readings, whose median scatters
  // further, and the largest of the medians then sat on the edge, reading high.
  void evaluate(int i) {
    const int cx = i % t_.cols, cy = i / t_.cols;
    if (!inside(cx, cy)) return;
    values_.clear();
    for (int y = std::max(0, cy - half_); y <= std::min(t_.rows - 1, cy + half_); ++y) {
      const float* row = t_.ptr<float>(y);
      const std::uint8_t* ok = valid_.ptr<std::uint8_t>(y);
      for (int x = std::max(0, cx - half_); x <= std::min(t_.cols - 1, cx + half_); ++x)
        if (ok[x]) values_.push_back(row[x]);
    }
    if (2 * static_cast<int>(values_.size()) < area_) return;
    const double m = median_of(values_);
    if (!best_.found() || m > best_.c) best_ = {m, cx, cy};
  }

  // Centres of the windows that may have a median above the best so far: with k readings and
  // at least half the window valid, a median above L needs its upper middle value above L, so at
  // least k - k / 2 readings above L (exactly the windows with a larger median when k is odd).
  std::vector<int> candidates() {
    cv::Mat above;
    if (best_.found()) {
      cv::compare(t_, best_.c, above, cv::CMP_GT);  // NaN compares false
      cv::bitwise_and(above, valid_, above);        // 255 & 1 = 1: counts, not bytes
    } else {
      above = valid_;
    }
    cv::Mat counts;
    cv::boxFilter(above, counts, CV_16U, cv::Size(2 * half_ + 1, 2 * half_ + 1), cv::Point(-1, -1),
                  false, cv::BORDER_CONSTANT);
    std::vector<int> out;
    for (int y = half_; y < t_.rows - half_; ++y) {
      const std::uint16_t* k = valid_counts_.ptr<std::uint16_t>(y);
      const std::uint16_t* c = counts.ptr<std::uint16_t>(y);
      for (int x = half_; x < t_.cols - half_; ++x)
        if (2 * k[x] >= area_ && c[x] > 0 && c[x] >= k[x] - k[x] / 2)
          out.push_back(y * t_.cols + x);
    }
    return out;
  }

  const RegionPeak& best() const { return best_; }

 private:
  bool inside(int x, int y) const {
    return x >= half_ && x < t_.cols - half_ && y >= half_ && y < t_.rows - half_;
  }
  const cv::Mat& t_;
  const cv::Mat& valid_;
  const int half_, area_;
  cv::Mat valid_counts_;
  std::vector<float> values_;
  RegionPeak best_;
};

}  // namespace

RegionStats region_stats(const cv::Mat& t, const cv::Mat& mask) {
  RegionStats s;
  std::vector<float> values;
  for (int y = 0; y < t.rows; ++y)
    for (int x = 0; x < t.cols; ++x) {
      if (!mask.empty() && !mask.at<std::uint8_t>(y, x)) continue;
      ++s.pixels;
      const float v = t.at<float>(y, x);
      if (std::isfinite(v)) values.push_back(v);
    }
  s.valid = values.size();
  s.valid_fraction = s.pixels ? static_cast<double>(s.valid) / static_cast<double>(s.pixels) : 0;
  if (values.empty()) return s;
  double sum = 0;
  for (float v : values) sum += v;
  s.mean_c = sum / static_cast<double>(values.size());
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  s.min_c = *lo;
  s.max_c = *hi;
  s.median_c = median_of(values);
  return s;
}

RegionPeak region_peak(const cv::Mat& t, int window, const cv::Mat& mask) {
  if (t.type() != CV_32F) throw InputError("peak: temperature image must be CV_32F");
  if (!mask.empty() && (mask.type() != CV_8U || mask.size() != t.size()))
    throw InputError("peak: mask must be CV_8U and the image's size");
  if (window < 1 || window % 2 == 0 || window > kMaxPeakWindow || window > t.cols ||
      window > t.rows)
    throw InputError("peak: window " + std::to_string(window) + " must be odd, 1.." +
                     std::to_string(kMaxPeakWindow) + " and fit in the " + std::to_string(t.cols) +
                     "x" + std::to_string(t.rows) + " image");
  // One pass: the readings inside the mask, and the hottest few pixels as first guesses (a hot
  // spot's window is usually among them, and any qualifying window gives a bound to prune by).
  constexpr std::size_t kSeeds = 16;
  using Hot = std::pair<float, int>;
  std::priority_queue<Hot, std::vector<Hot>, std::greater<Hot>> hottest;
  cv::Mat valid(t.size(), CV_8U);
  for (int y = 0; y < t.rows; ++y) {
    const float* row = t.ptr<float>(y);
    const std::uint8_t* m = mask.empty() ? nullptr : mask.ptr<std::uint8_t>(y);
    std::uint8_t* ok = valid.ptr<std::uint8_t>(y);
    for (int x = 0; x < t.cols; ++x) {
      ok[x] = std::isfinite(row[x]) && (!m || m[x]);
      if (!ok[x]) continue;
      if (hottest.size() < kSeeds) {
        hottest.emplace(row[x], y * t.cols + x);
      } else if (row[x] > hottest.top().first) {
        hottest.pop();
        hottest.emplace(row[x], y * t.cols + x);
      }
    }
  }
  PeakSearch search(t, valid, window);
  for (; !hottest.empty(); hottest.pop()) search.evaluate(hottest.top().second);
  // Raise the bound on a sample of the windows that could beat it until few are left, then
  // evaluate those exactly. On a noisy plate this takes two or three rounds.
  constexpr std::size_t kEvaluateAll = 8192, kSample = 1024;
  constexpr int kMaxRounds = 8;
  for (int round = 0;; ++round) {
    const std::vector<int> c = search.candidates();
    const RegionPeak before = search.best();
    if (c.size() > kEvaluateAll && round < kMaxRounds) {
      const std::size_t step = c.size() / kSample;
      for (std::size_t i = 0; i < c.size(); i += step) search.evaluate(c[i]);
      const RegionPeak& now = search.best();
      if (now.found() && (!before.found() || now.c > before.c)) continue;
    }
    for (int i : c) search.evaluate(i);
    return search.best();
  }
}

namespace {
// 1 where a sample holds no value from the camera: +INF (saturated) or NaN; -INF (demosaicking's
// mark of a sample without light) is a value, 0.
void mark_unread(const cv::Mat& values, cv::Mat& mask) {
  for (int y = 0; y < values.rows; ++y) {
    const float* v = values.ptr<float>(y);
    std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < values.cols; ++x)
      m[x] |= std::isnan(v[x]) || v[x] == std::numeric_limits<float>::infinity() ? 1 : 0;
  }
}
}  // namespace

cv::Mat saturated_band_mask(const std::vector<cv::Mat>& planes) {
  if (planes.empty()) throw InputError("saturation mask: no band planes");
  cv::Mat saturated = cv::Mat::zeros(planes.front().size(), CV_8U), nan = saturated.clone();
  for (const cv::Mat& p : planes) {
    if (p.type() != CV_32F || p.size() != saturated.size())
      throw InputError("saturation mask: band planes must be CV_32F of one size");
    for (int y = 0; y < p.rows; ++y) {
      const float* v = p.ptr<float>(y);
      std::uint8_t* s = saturated.ptr<std::uint8_t>(y);
      std::uint8_t* n = nan.ptr<std::uint8_t>(y);
      for (int x = 0; x < p.cols; ++x) {
        s[x] |= v[x] == std::numeric_limits<float>::infinity() ? 1 : 0;
        n[x] |= std::isnan(v[x]) ? 1 : 0;
      }
    }
  }
  if (cv::countNonZero(nan) == 0) return saturated;
  // NaN from saturated samples of opposite signs in a kernel lies within the kernels' reach
  // (2 pixels) of a pixel that saturated outright; one elsewhere (the mixed-pixel check's mark,
  // a sample darksub left without a value) is no saturation.
  cv::Mat near;
  cv::dilate(saturated, near, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
  saturated |= nan & near;
  return saturated;
}

cv::Mat saturated_sample_mask(const cv::Mat& mosaic, int radius) {
  if (mosaic.type() != CV_32F) throw InputError("saturation mask: the mosaic must be CV_32F");
  if (radius < 0) throw InputError("saturation mask: negative radius");
  cv::Mat mask = cv::Mat::zeros(mosaic.size(), CV_8U);
  mark_unread(mosaic, mask);
  if (radius > 0)
    cv::dilate(mask, mask,
               cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * radius + 1, 2 * radius + 1)));
  return mask;
}

namespace {

// The normalised samples of a Gaussian whose squares sum to `squared_sum` (in 0..1]: a
// footprint of that noise share along one axis.
std::vector<double> gaussian_footprint(double squared_sum) {
  if (squared_sum >= 1) return {1.0};
  std::vector<double> w;
  double low = 0.05, high = 64;  // standard deviations, pixels
  for (int i = 0; i < 60; ++i) {
    const double sigma = 0.5 * (low + high);
    const int radius = static_cast<int>(std::ceil(4 * sigma));
    w.assign(static_cast<std::size_t>(2 * radius + 1), 0.0);
    double sum = 0, squares = 0;
    for (int x = -radius; x <= radius; ++x)
      sum += w[static_cast<std::size_t>(x + radius)] = std::exp(-0.5 * x * x / (sigma * sigma));
    for (double& v : w) v /= sum, squares += v * v;
    (squares > squared_sum ? low : high) = sigma;
  }
  return w;
}

}  // namespace

double median_noise_share(const cv::Mat& used, double noise_area) {
  if (used.type() != CV_8U) throw InputError("median noise: the mask must be CV_8U");
  if (!(noise_area >= 1)) throw InputError("median noise: a noise area below one pixel");
  const int n = cv::countNonZero(used);
  if (n == 0) return NAN;
  const bool median = n > 2;  // of one or two readings the median is their mean
  // Two readings d apart along an axis share the part rho1(d) of their noise.
  const std::vector<double> w = gaussian_footprint(1 / std::sqrt(noise_area));
  const int width = static_cast<int>(w.size());
  std::vector<double> rho1;
  double single = 0;
  for (double v : w) single += v * v;
  for (int d = 0; d < width; ++d) {
    double shared = 0;
    for (int k = 0; k + d < width; ++k)
      shared += w[static_cast<std::size_t>(k)] * w[static_cast<std::size_t>(k + d)];
    if (d > 0 && shared / single < 1e-7) break;
    rho1.push_back(shared / single);
  }
  // Sum over the pairs of readings of the part of their noise the mean shares (rho) or, for a
  // median, the part their signs share: arcsin(rho) for jointly normal noise (Sheppard), so
  // that var(median) = sigma^2 / n^2 * sum arcsin(rho): pi/2 sigma^2 / n for independent
  // readings, sigma^2 for readings that share all of it.
  const int radius = static_cast<int>(rho1.size()) - 1;
  cv::Mat kernel(2 * radius + 1, 2 * radius + 1, CV_64F);
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const double rho = rho1[static_cast<std::size_t>(std::abs(dx))] *
                         rho1[static_cast<std::size_t>(std::abs(dy))];
      kernel.at<double>(dy + radius, dx + radius) = median ? std::asin(std::min(rho, 1.0)) : rho;
    }
  const cv::Rect bounds = cv::boundingRect(used);
  cv::Mat in = cv::Mat::zeros(bounds.height + 2 * radius, bounds.width + 2 * radius, CV_64F);
  used(bounds).convertTo(in(cv::Rect(radius, radius, bounds.width, bounds.height)), CV_64F);
  cv::threshold(in, in, 0, 1, cv::THRESH_BINARY);
  cv::Mat pairs;
  cv::filter2D(in, pairs, CV_64F, kernel, cv::Point(-1, -1), 0, cv::BORDER_CONSTANT);
  const double share = in.dot(pairs) / (static_cast<double>(n) * n);
  // Between independent readings and one reading.
  const double one = median ? M_PI / 2 : 1.0;
  return std::clamp(share, one / n, one);
}

std::size_t count_without_reading(const cv::Mat& temperature_c, const cv::Mat& mask) {
  if (temperature_c.type() != CV_32F || mask.type() != CV_8U || mask.size() != temperature_c.size())
    throw InputError("saturation count: a CV_32F image and a CV_8U mask of its size are needed");
  std::size_t n = 0;
  for (int y = 0; y < mask.rows; ++y) {
    const float* t = temperature_c.ptr<float>(y);
    const std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < mask.cols; ++x) n += m[x] != 0 && std::isnan(t[x]);
  }
  return n;
}

}  // namespace pyrocam
