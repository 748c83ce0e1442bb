// The dim threshold as an edge that a reading's own noise does not decide.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/mosaic.h"
#include "pyrocam/core/profile.h"
#include "pyrocam/runtime/demosaic.h"

namespace pyrocam {

// A pixel that needs every band reads only where each reaches the dim threshold. On a surface
// whose band sits at the threshold, the pixels that reach it are those whose noise lifted that
// band, and their readings lean one way (a 1200 degC colour plate exposed so: 1 % of the pixels
// read, 98 degC low; 22 %, 48 degC low). The check decides from the band's values around the
// pixel, in a ring outside its demosaicking footprint, whose noise is not the pixel's: a reading
// with a band near the threshold stays only where the mean of one of the ring's halves (above,
// below, left, right: at a body's edge, the half inside it) lies kNoiseMargin of the band's own
// noise above the threshold. The pixel's own noise then no longer selects it; a uniform
// surface reads on all its pixels or on none, a body's edge keeps what its inside has.
class DimEdgeCheck {
 public:
  // Standard deviations of a band value's noise at the threshold: where the surface lies this
  // far above it, the threshold cuts off 2.3 % of a normal noise and leaves its mean 0.055 of
  // them high.
  static constexpr double kNoiseMargin = 2.0;
  // A band further above the threshold than this is not checked (its noise reaches below the
  // threshold once in 10^9).
  static constexpr double kCheckedMargin = 6.0;
  // The window: a ring of pixels at Chebyshev distances inner .. outer from the pixel, outside
  // its own demosaicking footprint so that its noise is not the pixel's. Band planes of a Bayer
  // mosaic: values whose kernels (5 x 5) do not reach the pixel's, 5 .. 6 (88 values over 21
  // samples of R or B); a Bayer mosaic's samples: 3 .. 6, outside the 5 x 5 footprint (36 of R
  // or B; 3 .. 4, 14 of them, left a 1200 degC plate's transition 2 % of the pixels wide
  // reading 12 degC low); snapshot cells: 3, outside the 3 x 3 cells matched registration
  // draws on (24 cells).
  struct Ring {
    int inner, outer;
  };
  static Ring plane_ring(const MosaicLayout& layout) {
    return layout.kind == MosaicLayout::Kind::kBayer ? Ring{5, 6} : Ring{3, 3};
  }
  static constexpr Ring kMosaicRing{3, 6};
  // Pixels of a row share their ring in spans of this many columns (from column 0 on): the
  // ring then goes around the whole span, outside every one of its pixels' footprints, and is
  // read once for both (about half the samples a pixel of its own would read; spans of 8 read
  // a sixth but left 13 % fewer readings on the rims of the mixed-pixel targets' small pools).
  static constexpr int kSpan = 2;
  static constexpr std::size_t kMaxBands = 64;  // the constructor refuses more

  // Thresholds per band from the profile's noise model at its dim threshold, with the analogue
  // gain (a factor) and what demosaicking did to the noise (its largest factor per band).
  DimEdgeCheck(const CameraProfile& profile, double gain, const DemosaicNoise& noise);
  int bands() const { return static_cast<int>(accept_dn_.size()); }
  float accept_dn(int band) const { return accept_dn_[static_cast<std::size_t>(band)]; }
  float checked_dn(int band) const { return checked_dn_[static_cast<std::size_t>(band)]; }

  // Refuses the readings out[0 .. n) (NaN) of output pixels x0 .. x0 + n - 1 of row y whose
  // band values rows[b][i] lie below checked_dn and whose span's ring's largest half mean
  // `window_mean(b, first, last, y)` (the span's columns) lies below accept_dn. The scan is
  // branch-free until a run of pixels holds one to check.
  template <class WindowMean>
  void apply(const float* const* rows, std::size_t n, float* out, int x0, int y,
             const WindowMean& window_mean) const {
    constexpr std::size_t kRun = 64;
    const std::size_t nb = accept_dn_.size();
    int span_of[kMaxBands];  // the span whose ring each band last read, and its verdict
    bool span_refuses[kMaxBands];
    std::fill(span_of, span_of + nb, -1);
    for (std::size_t start = 0; start < n; start += kRun) {
      const std::size_t m = std::min(kRun, n - start);
      if (!any_to_check(rows, start, m, out)) continue;
      for (std::size_t i = start; i < start + m; ++i) {
        if (!std::isfinite(out[i])) continue;
        const int span = (x0 + static_cast<int>(i)) / kSpan * kSpan;
        for (std::size_t b = 0; b < nb; ++b) {
          if (!(rows[b][i] < checked_dn_[b])) continue;
          if (span_of[b] != span) {  // the span's ring, read once
            span_of[b] = span;
            span_refuses[b] =
                refuses(b, window_mean(static_cast<int>(b), span, span + kSpan - 1, y));
          }
          if (span_refuses[b]) {
            out[i] = NAN;
            break;
          }
        }
      }
    }
  }

  // Whether a band value below checked_dn, with `ring_mean` (the largest half's) around it, is
  // refused.
  bool refuses(std::size_t band, double ring_mean) const {
    return !(ring_mean >= accept_dn_[band]);
  }

 private:
  // Whether pixels start .. start + m - 1 hold a reading with a band below checked_dn: one
  // vectorised pass (three bands unrolled, the colour camera's).
  bool any_to_check(const float* const* rows, std::size_t start, std::size_t m,
                    const float* out) const {
    int any = 0;
    if (accept_dn_.size() == 3) {
      const float* r0 = rows[0];
      const float* r1 = rows[1];
      const float* r2 = rows[2];
      const float c0 = checked_dn_[0], c1 = checked_dn_[1], c2 = checked_dn_[2];
      for (std::size_t i = start; i < start + m; ++i)
        any |= ((r0[i] < c0) | (r1[i] < c1) | (r2[i] < c2)) & (out[i] == out[i]);
      return any != 0;
    }
    for (std::size_t i = start; i < start + m; ++i) {
      int low = 0;
      for (std::size_t b = 0; b < accept_dn_.size(); ++b) low |= rows[b][i] < checked_dn_[b];
      any |= low & (out[i] == out[i]);
    }
    return any != 0;
  }

  std::vector<float> accept_dn_, checked_dn_;
};

// The largest of the means of the four halves (above, below, left, right) of the ring around
// columns first .. last of row y of `plane` (CV_32F): within `ring.outer` of them, not within
// `ring.inner - 1`, clipped to the image; a NaN value (no reading) counts as 0, a +INF
// (saturated) one as `saturated` (by default making its half's mean +INF); NaN where a number
// lies above `foreign_above`. Columns first .. last are in neither the left nor the right half.
double plane_ring_mean(const cv::Mat& plane, int first, int last, int y, DimEdgeCheck::Ring ring,
                       double saturated = INFINITY, double foreign_above = INFINITY);
// The same over the samples of band `band` of a mosaic (CV_32F, the layout's pattern at its
// top-left pixel).
double mosaic_ring_mean(const cv::Mat& mosaic, const MosaicLayout& layout, int band, int first,
                        int last, int y, DimEdgeCheck::Ring ring, double saturated = INFINITY,
                        double foreign_above = INFINITY);
// The ring means a check reads (plane_ring_mean or mosaic_ring_mean with their settings): of one
// span, columns first .. last, and of four neighbouring ones at once (the ..._four functions).
struct RingMeans {
  std::function<double(int band, int first, int last, int y)> one;
  std::function<void(int band, int first, int span, int y, double* means)> four;
  double operator()(int band, int first, int last, int y) const {
    return one(band, first, last, y);
  }
};

// plane_ring_mean and mosaic_ring_mean of four neighbouring spans, columns first + k span ..
// first + k span + span - 1 (k < 4), into means[k] (NaN for a span that starts past the image):
// the same bits, side by side where the rings lie inside the image.
void plane_ring_means_four(const cv::Mat& plane, int first, int span, int y,
                           DimEdgeCheck::Ring ring, double* means, double saturated = INFINITY,
                           double foreign_above = INFINITY);
void mosaic_ring_means_four(const cv::Mat& mosaic, const MosaicLayout& layout, int band, int first,
                            int span, int y, DimEdgeCheck::Ring ring, double* means,
                            double saturated = INFINITY, double foreign_above = INFINITY);

}  // namespace pyrocam
