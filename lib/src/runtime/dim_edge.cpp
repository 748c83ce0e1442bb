#include "pyrocam/runtime/dim_edge.h"

#include <algorithm>
#include <cstdlib>

#include "pyrocam/core/noise_model.h"

namespace pyrocam {

DimEdgeCheck::DimEdgeCheck(const CameraProfile& profile, double gain, const DemosaicNoise& noise) {
  const int bands = profile.band_count();
  const double dim = profile.thresholds.inference_dim_dn;
  const int phases = noise.period_width * noise.period_height;
  for (int b = 0; b < bands; ++b) {
    double factor = noise.factor.empty() ? 1.0 : 0.0;
    for (int phase = 0; phase < phases && !noise.factor.empty(); ++phase)
      factor = std::max(factor, noise.factor[static_cast<std::size_t>(phase * noise.bands + b)]);
    const double sd = std::sqrt(signal_variance_dn2(profile, b, dim, 1, gain) * factor);
    accept_dn_.push_back(static_cast<float>(dim + kNoiseMargin * sd));
    checked_dn_.push_back(static_cast<float>(dim + kCheckedMargin * sd));
  }
}

namespace {

// The largest of the means of the ring's four halves (above, below, left of, right of the
// pixel) over their values for which `take(u, v)`; NaN where no half has any. A value without a
// reading (NaN: an invalid sample, or a mixed-pixel mark) counts as no light, so that such marks
// only ever refuse more; a saturated one (+INF) makes its half's mean +INF.
template <class Take>
double ring_mean(const cv::Mat& image, int x, int y, DimEdgeCheck::Ring ring, const Take& take) {
  double sum[4] = {0, 0, 0, 0};
  int count[4] = {0, 0, 0, 0};
  const int y0 = std::max(0, y - ring.outer), y1 = std::min(image.rows - 1, y + ring.outer);
  const int x0 = std::max(0, x - ring.outer), x1 = std::min(image.cols - 1, x + ring.outer);
  for (int v = y0; v <= y1; ++v) {
    const float* row = image.ptr<float>(v);
    const bool inner_row = std::abs(v - y) < ring.inner;
    for (int u = x0; u <= x1; ++u) {
      if (inner_row && std::abs(u - x) < ring.inner) {
        u = x + ring.inner - 1;  // across the hole
        continue;
      }
      if (!take(u, v)) continue;
      const int vertical = v < y ? 0 : v > y ? 1 : -1, horizontal = u < x ? 2 : u > x ? 3 : -1;
      for (const int half : {vertical, horizontal}) {
        if (half < 0) continue;
        sum[half] += std::isnan(row[u]) ? 0.f : row[u];
        ++count[half];
      }
    }
  }
  double largest = NAN;
  for (int k = 0; k < 4; ++k)
    if (count[k] > 0 && !(sum[k] / count[k] <= largest)) largest = sum[k] / count[k];
  return largest;
}

}  // namespace

double plane_ring_mean(const cv::Mat& plane, int x, int y, DimEdgeCheck::Ring ring) {
  return ring_mean(plane, x, y, ring, [](int, int) { return true; });
}

double mosaic_ring_mean(const cv::Mat& mosaic, const MosaicLayout& layout, int band, int x, int y,
                        DimEdgeCheck::Ring ring) {
  return ring_mean(mosaic, x, y, ring,
                   [&layout, band](int u, int v) { return layout.band_at(u, v) == band; });
}

}  // namespace pyrocam
