#include "runtime/bracket_motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace pyrocam::bracket_motion {

cv::Mat cell_logs(const cv::Mat& signal, int period, float low, float high) {
  const int rows = signal.rows / period, cols = signal.cols / period;
  cv::Mat out(rows, cols, CV_32F);
  const double per_cell = 1.0 / (period * period);
  for (int cy = 0; cy < rows; ++cy) {
    float* o = out.ptr<float>(cy);
    for (int cx = 0; cx < cols; ++cx) {
      double sum = 0;
      bool usable = true;
      for (int dy = 0; dy < period && usable; ++dy) {
        const float* v = signal.ptr<float>(cy * period + dy) + cx * period;
        for (int dx = 0; dx < period; ++dx) {
          usable = usable && v[dx] >= low && v[dx] <= high;  // NaN, +INF fail
          sum += v[dx];
        }
      }
      o[cx] = usable ? static_cast<float>(std::log(sum * per_cell))
                     : std::numeric_limits<float>::quiet_NaN();
    }
  }
  return out;
}

namespace {

struct Cell {
  int x, y;
  float v;
};

// Mean squared difference of the cells of `now` (listed) and `before` shifted by (sx, sy)
// cells; +INF where fewer than `least` are shared.
double mean_difference(const std::vector<Cell>& now, const cv::Mat& before, int sx, int sy,
                       std::size_t least) {
  double sum = 0, sum2 = 0;
  std::size_t shared = 0;
  for (const Cell& c : now) {
    const int x = c.x - sx, y = c.y - sy;
    if (x < 0 || y < 0 || x >= before.cols || y >= before.rows) continue;
    const float b = before.ptr<float>(y)[x];
    if (!std::isfinite(b)) continue;
    const double d = c.v - b;
    sum += d;
    sum2 += d * d;
    ++shared;
  }
  if (shared < least || shared == 0) return std::numeric_limits<double>::infinity();
  const double mean = sum / static_cast<double>(shared);
  return sum2 / static_cast<double>(shared) - mean * mean;
}

// The vertex of the parabola through (-1, a), (0, b), (1, c), within +-0.5; 0 where it does
// not open upwards or a value is not finite.
double vertex(double a, double b, double c) {
  const double curvature = a - 2 * b + c;
  if (!std::isfinite(curvature) || !(curvature > 0)) return 0;
  return std::clamp(0.5 * (a - c) / curvature, -0.5, 0.5);
}

}  // namespace

bool find_shift(const cv::Mat& now, const cv::Mat& before, int period, cv::Point2d& shift,
                bool* still) {
  if (still) *still = false;
  if (now.size() != before.size() || now.empty()) return false;
  std::vector<Cell> all;
  for (int y = 0; y < now.rows; ++y) {
    const float* v = now.ptr<float>(y);
    for (int x = 0; x < now.cols; ++x)
      if (std::isfinite(v[x])) all.push_back({x, y, v[x]});
  }
  // Evenly spread over the frame's usable cells, so a frame full of them costs no more.
  std::vector<Cell> cells;
  const std::size_t step = (all.size() + kMaxCompared - 1) / kMaxCompared;
  for (std::size_t i = 0; i < all.size(); i += std::max<std::size_t>(step, 1))
    cells.push_back(all[i]);
  if (static_cast<int>(cells.size()) < kMinSharedCells) return false;
  // The content moved, so at the right shift about as many cells are shared as `now` has.
  const std::size_t least = std::max<std::size_t>(kMinSharedCells, cells.size() / 2);
  constexpr int kR = kMaxShiftCells, kSide = 2 * kR + 1;
  std::vector<double> d(kSide * kSide);
  auto at = [&](int sx, int sy) -> double& { return d[(sy + kR) * kSide + (sx + kR)]; };
  for (int sy = -kR; sy <= kR; ++sy)
    for (int sx = -kR; sx <= kR; ++sx) at(sx, sy) = mean_difference(cells, before, sx, sy, least);
  int best_x = 0, best_y = 0;
  for (int sy = -kR; sy <= kR; ++sy)
    for (int sx = -kR; sx <= kR; ++sx)
      if (at(sx, sy) < at(best_x, best_y)) best_x = sx, best_y = sy;
  const double best = at(best_x, best_y);
  if (still) *still = std::isfinite(best) && best_x == 0 && best_y == 0;
  if (!std::isfinite(best) || (best_x == 0 && best_y == 0)) return false;
  if (std::abs(best_x) == kR || std::abs(best_y) == kR) return false;
  if (!(best <= kMinGain * at(0, 0))) return false;  // +INF at none: not shared enough there
  const double fx = vertex(at(best_x - 1, best_y), best, at(best_x + 1, best_y));
  const double fy = vertex(at(best_x, best_y - 1), best, at(best_x, best_y + 1));
  shift = cv::Point2d((best_x + fx) * period, (best_y + fy) * period);
  return true;
}

cv::Mat log_rates(const cv::Mat& now, const cv::Mat& before, const cv::Point2d& shift, int period,
                  int age) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  cv::Mat out(now.size(), CV_32FC2, cv::Scalar(kNaN, kNaN));
  if (now.size() != before.size() || now.empty() || age < 1) return out;
  const double samples = static_cast<double>(period) * period;
  // The variance of a cell's log at `log_mean` (the log of the mean of its samples, in DN).
  auto log_variance = [&](double log_mean) {
    const double mean = std::exp(log_mean);
    return (kRateShotDnPerDn * mean + kRateFloorDn2) / (samples * mean * mean);
  };
  // Cell (cx, cy) of now was at (cx, cy) - shift / period in `before`: between four cells.
  const double ux = -shift.x / period, uy = -shift.y / period;
  const int mx = static_cast<int>(std::floor(ux)), my = static_cast<int>(std::floor(uy));
  const double fx = ux - mx, fy = uy - my;
  const double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
  const double weights2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3];
  for (int cy = 0; cy < now.rows; ++cy) {
    const float* n = now.ptr<float>(cy);
    cv::Vec2f* o = out.ptr<cv::Vec2f>(cy);
    const int by = cy + my;
    if (by < 0 || by + 1 >= before.rows) continue;
    const float *b0 = before.ptr<float>(by), *b1 = before.ptr<float>(by + 1);
    for (int cx = 0; cx < now.cols; ++cx) {
      const int bx = cx + mx;
      if (!std::isfinite(n[cx]) || bx < 0 || bx + 1 >= before.cols) continue;
      const double v[4] = {b0[bx], b0[bx + 1], b1[bx], b1[bx + 1]};
      double then = 0;
      bool known = true;
      for (int k = 0; k < 4; ++k) {
        if (w[k] == 0) continue;
        known = known && std::isfinite(v[k]);
        if (!known) break;
        then += w[k] * v[k];
      }
      if (!known) continue;
      // The four cells' variances taken at their interpolated level (one exponential, not four).
      const double variance = weights2 * log_variance(then) + log_variance(n[cx]);
      o[cx] = cv::Vec2f(static_cast<float>((n[cx] - then) / age),
                        static_cast<float>(variance / (static_cast<double>(age) * age)));
    }
  }
  return out;
}

cv::Mat brightness_change(const std::vector<cv::Mat>& rates, const std::vector<cv::Point2d>& shifts,
                          int period) {
  // The latest frame's may be unknown (no frame of its light before it): the cells' size from
  // any that is known.
  const auto any =
      std::find_if(rates.begin(), rates.end(), [](const cv::Mat& r) { return !r.empty(); });
  if (any == rates.end()) return {};
  const cv::Size size = any->size();
  // Each cell's most recent rate, the older frames' read where their content was.
  cv::Mat known(size, CV_32FC2, cv::Scalar(0, 0));  // rate / variance, 1 / variance; 0: none
  std::vector<cv::Point> cells_moved;
  for (const cv::Point2d& s : shifts)
    cells_moved.emplace_back(static_cast<int>(std::lround(s.x / period)),
                             static_cast<int>(std::lround(s.y / period)));
  for (int cy = 0; cy < size.height; ++cy) {
    cv::Vec2f* k = known.ptr<cv::Vec2f>(cy);
    for (int cx = 0; cx < size.width; ++cx)
      for (std::size_t j = 0; j < rates.size(); ++j) {
        const int x = cx - cells_moved[j].x, y = cy - cells_moved[j].y;
        if (x < 0 || y < 0 || x >= size.width || y >= size.height || rates[j].size() != size)
          continue;
        const cv::Vec2f r = rates[j].ptr<cv::Vec2f>(y)[x];
        if (!std::isfinite(r[0]) || !(r[1] > 0)) continue;
        k[cx] = cv::Vec2f(r[0] / r[1], 1 / r[1]);
        break;
      }
  }
  cv::Mat out(size, CV_32F, cv::Scalar(0));
  for (int cy = 0; cy < size.height; ++cy) {
    float* o = out.ptr<float>(cy);
    for (int cx = 0; cx < size.width; ++cx) {
      double weighted = 0, weight = 0;
      for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, size.height - 1); ++y) {
        const cv::Vec2f* k = known.ptr<cv::Vec2f>(y);
        for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, size.width - 1); ++x)
          weighted += k[x][0], weight += k[x][1];
      }
      if (!(weight > 0)) continue;
      const double mean = weighted / weight;  // its variance: 1 / weight
      if (std::abs(mean) * std::sqrt(weight) > kRateDeviations) o[cx] = static_cast<float>(mean);
    }
  }
  return out;
}

namespace {

// Lagrange's polynomials' weights at t in [0, 1) of nodes -1 .. 2 (0 for a node not used): the
// cubic on all four, the quadratics on 0..2 and on -1..1. At t = 0 node 0 alone.
void curved_weights(double t, double (&w)[kCurvedKinds][4]) {
  if (t == 0) {
    for (auto& k : w) k[0] = 0, k[1] = 1, k[2] = 0, k[3] = 0;
    return;
  }
  w[0][0] = -t * (t - 1) * (t - 2) / 6;
  w[0][1] = (t + 1) * (t - 1) * (t - 2) / 2;
  w[0][2] = -(t + 1) * t * (t - 2) / 2;
  w[0][3] = (t + 1) * t * (t - 1) / 6;
  w[1][0] = 0;
  w[1][1] = (t - 1) * (t - 2) / 2;
  w[1][2] = -t * (t - 2);
  w[1][3] = t * (t - 1) / 2;
  w[2][0] = t * (t - 1) / 2;
  w[2][1] = (1 - t) * (1 + t);
  w[2][2] = t * (t + 1) / 2;
  w[2][3] = 0;
}

}  // namespace

Displacement::Displacement(const cv::Point2d& shift, int period) : period(period) {
  // Along each axis the band's samples at offsets period * m and period * (m + 1) from the
  // pixel, m = floor(-shift / period).
  const double ux = -shift.x / period, uy = -shift.y / period;
  const double mx = std::floor(ux), my = std::floor(uy);
  dx = period * static_cast<int>(mx), dy = period * static_cast<int>(my);
  wx[0] = 1 - (ux - mx), wx[1] = ux - mx;
  wy[0] = 1 - (uy - my), wy[1] = uy - my;
  curved_weights(ux - mx, curved_x);
  curved_weights(uy - my, curved_y);
}

cv::Mat sample_logs(const cv::Mat& signal) {
  cv::Mat out(signal.size(), CV_32F);
  for (int y = 0; y < signal.rows; ++y) {
    const float* v = signal.ptr<float>(y);
    float* o = out.ptr<float>(y);
    for (int x = 0; x < signal.cols; ++x)
      o[x] = v[x] >= kLogFromDn && v[x] < std::numeric_limits<float>::infinity()
                 ? std::log(v[x])
                 : std::numeric_limits<float>::quiet_NaN();
  }
  return out;
}

DisplacedRow::DisplacedRow(const cv::Mat& signal, const cv::Mat& near_level, const cv::Mat& logs,
                           const Displacement& d, int y)
    : d_(d), width_(signal.cols) {
  for (int j = 0; j < 2; ++j) {
    if (d.wy[j] == 0) continue;
    const int sy = y + d.dy + j * d.period;
    inside_ = inside_ && sy >= 0 && sy < signal.rows;
    if (!inside_) return;
    rows_[j] = signal.ptr<float>(sy);
    flags_[j] = near_level.ptr<std::uint8_t>(sy);
  }
  if (logs.size() != signal.size()) return;  // no curved kinds
  for (int j = 0; j < 4; ++j) {
    const int sy = y + d.dy + (j - 1) * d.period;
    if (sy >= 0 && sy < logs.rows) logs_[j] = logs.ptr<float>(sy);
  }
}

}  // namespace pyrocam::bracket_motion
