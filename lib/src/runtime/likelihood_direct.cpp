// The likelihood fit's exact chi2 from the weighed bands alone (likelihood_direct.h).
#include "runtime/likelihood_direct.h"

#include <cstddef>

#include "detail/vector_clones.h"

namespace pyrocam {

namespace {

// chi2 at `count` samples from `at` on (rounded up to eight: the tables hold the padding),
// eight at a time: lane j of profiled_chi2 is band list j here, summed from 0 in the same order,
// and the lanes are added as its lane_sum adds them.
PYROCAM_VECTOR_CLONES
void chi2_run(const double* __restrict m, const double* __restrict m2, std::ptrdiff_t stride,
              const LaneBands& lanes, const double* __restrict ws, const double* __restrict w,
              double sss, std::ptrdiff_t at, std::ptrdiff_t count, double* __restrict chi2) {
  const Lanes zero = {0, 0, 0, 0}, s = {sss, sss, sss, sss};
  for (std::ptrdiff_t i = 0; i < count; i += 8) {
    Lanes a[4][2], c[4][2];
    for (int j = 0; j < 4; ++j) {
      Lanes x0 = zero, x1 = zero, y0 = zero, y1 = zero;
      for (int k = lanes.start[j]; k < lanes.start[j + 1]; ++k) {
        const int b = lanes.band[k];
        const double* mb = m + b * stride + at + i;
        const double* qb = m2 + b * stride + at + i;
        const Lanes u = {ws[b], ws[b], ws[b], ws[b]}, v = {w[b], w[b], w[b], w[b]};
        x0 += u * *reinterpret_cast<const Lanes*>(mb);
        x1 += u * *reinterpret_cast<const Lanes*>(mb + 4);
        y0 += v * *reinterpret_cast<const Lanes*>(qb);
        y1 += v * *reinterpret_cast<const Lanes*>(qb + 4);
      }
      a[j][0] = x0, a[j][1] = x1, c[j][0] = y0, c[j][1] = y1;
    }
    for (int h = 0; h < 2; ++h) {
      const Lanes sm = (a[0][h] + a[1][h]) + (a[2][h] + a[3][h]);
      const Lanes mm = (c[0][h] + c[1][h]) + (c[2][h] + c[3][h]);
      *reinterpret_cast<Lanes*>(chi2 + i + 4 * h) = s - sm * sm / mm;
    }
  }
}

}  // namespace

LaneBands lane_bands(const double* w, int bands) {
  LaneBands lanes;
  int n = 0;
  for (int j = 0; j < 4; ++j) {
    lanes.start[j] = n;
    for (int b = j; b < bands; b += 4)
      if (w[b] != 0.0) lanes.band[n++] = b;
  }
  lanes.start[4] = n;
  return lanes;
}

DirectChi2::DirectChi2(const double* m, const double* m2, int width, int bands,
                       Eigen::Index samples, Eigen::Index coarse)
    :  // Whole groups of eight from any sample of a window (up to seven past the last sample).
      stride_((samples + 7) / 8 * 8 + 8),
      coarse_count_((samples + coarse - 1) / coarse),
      coarse_stride_((coarse_count_ + 7) / 8 * 8),
      m_(static_cast<std::size_t>(bands * stride_), 0.0),
      m2_(m_.size(), 0.0),
      coarse_m_(static_cast<std::size_t>(bands * coarse_stride_), 0.0),
      coarse_m2_(coarse_m_.size(), 0.0) {
  for (int b = 0; b < bands; ++b)
    for (Eigen::Index i = 0; i < samples; ++i) {
      const auto from = static_cast<std::size_t>(i * width + b);
      const auto to = static_cast<std::size_t>(b * stride_ + i);
      m_[to] = m[from], m2_[to] = m2[from];
      if (i % coarse == 0) {
        const auto k = static_cast<std::size_t>(b * coarse_stride_ + i / coarse);
        coarse_m_[k] = m[from], coarse_m2_[k] = m2[from];
      }
    }
}

void DirectChi2::at_coarse(const LaneBands& lanes, const double* ws, const double* w, double sss,
                           double* chi2) const {
  chi2_run(coarse_m_.data(), coarse_m2_.data(), coarse_stride_, lanes, ws, w, sss, 0, coarse_count_,
           chi2);
}

void DirectChi2::at_samples(const LaneBands& lanes, const double* ws, const double* w, double sss,
                            Eigen::Index from, Eigen::Index count, double* chi2) const {
  chi2_run(m_.data(), m2_.data(), stride_, lanes, ws, w, sss, from, count, chi2);
}

}  // namespace pyrocam
