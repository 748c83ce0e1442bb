// The likelihood fit's exact chi2 from the weighed bands alone (likelihood_direct.h).
#include "runtime/likelihood_direct.h"

#include <cmath>
#include <cstddef>
#include <limits>

#include "detail/portable_math.h"
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

int sign(double v) { return (v > 0) - (v < 0); }

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
                       Eigen::Index samples, Eigen::Index coarse, const std::uint8_t* monotonic)
    : bands_(bands),
      // Whole groups of eight from any sample (up to seven past the last one).
      stride_((samples + 7) / 8 * 8 + 8),
      coarse_count_((samples + coarse - 1) / coarse),
      coarse_stride_((coarse_count_ + 7) / 8 * 8 + 8),
      m_(static_cast<std::size_t>(bands * stride_), 0.0),
      m2_(m_.size(), 0.0),
      coarse_m_(static_cast<std::size_t>(bands * coarse_stride_), 0.0),
      coarse_m2_(coarse_m_.size(), 0.0),
      reach_(static_cast<std::size_t>(bands * bands), 0.0) {
  if (samples > 0)
    for (int i = 0; i < bands; ++i)
      for (int j = 0; j < bands; ++j) {
        if (i == j || !monotonic[i * bands + j]) continue;
        const auto at = [&](Eigen::Index k, int b) { return m[k * width + b]; };
        reach_[static_cast<std::size_t>(i * bands + j)] =
            portable::log(at(samples - 1, i) / at(samples - 1, j)) -
            portable::log(at(0, i) / at(0, j));
      }
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
                           Eigen::Index from, Eigen::Index count, double* chi2) const {
  chi2_run(coarse_m_.data(), coarse_m2_.data(), coarse_stride_, lanes, ws, w, sss, from, count,
           chi2);
}

bool DirectChi2::coarse_span(const LaneBands& lanes, const double* ws, const double* w, double sss,
                             double margin, Eigen::Index& first, Eigen::Index& last,
                             double& upper) const {
  const Eigen::Index nc = coarse_count_;
  if (nc < 1) return false;
  // The weighed pair that tells temperatures apart best: the largest squared reach of its log
  // ratio along the locus over the variance of its measured log ratio (1 / (w s^2) a band),
  // compared as fractions.
  const int weighed = lanes.start[4];
  double variance[kMaxBands];
  for (int a = 0; a < weighed; ++a) {
    const int b = lanes.band[a];
    variance[a] = w[b] / (ws[b] * ws[b]);  // infinite for a band without signal
  }
  int bi = -1, bj = -1;
  double best_reach2 = 0, best_variance = 1;
  for (int a = 0; a < weighed; ++a)
    for (int b = a + 1; b < weighed; ++b) {
      const double reach = reach_[static_cast<std::size_t>(lanes.band[a] * bands_ + lanes.band[b])];
      const double v = variance[a] + variance[b];
      if (reach != 0 && v < std::numeric_limits<double>::infinity() &&
          reach * reach * best_variance > best_reach2 * v)
        best_reach2 = reach * reach, best_variance = v, bi = lanes.band[a], bj = lanes.band[b];
    }
  if (bi < 0) return false;
  // The pair's chi2 with its own scale at coarse sample k: w_i w_j d^2 / (w_i m_i^2 + w_j m_j^2)
  // with d = s_i m_j - s_j m_i, as numerator and denominator.
  const double si = ws[bi] / w[bi], sj = ws[bj] / w[bj], wi = w[bi], wj = w[bj], wij = wi * wj;
  const auto row = [&](const std::vector<double>& table, int band) {
    return table.data() + static_cast<std::ptrdiff_t>(band) * coarse_stride_;
  };
  const double *mi = row(coarse_m_, bi), *mj = row(coarse_m_, bj), *qi = row(coarse_m2_, bi),
               *qj = row(coarse_m2_, bj);
  struct Terms {
    double d, numerator, denominator;
  };
  const auto terms = [&](Eigen::Index k) {
    const double d = si * mj[k] - sj * mi[k];
    return Terms{d, wij * d * d, wi * qi[k] + wj * qj[k]};
  };
  // It is least where the locus ratio m_i / m_j is the pixel's (d = 0) and rises away from there
  // on both sides (its derivative in the ratio has the sign of ratio - s_i / s_j): along the
  // locus it falls while d has the sign `before` (the ratio below the pixel's where it rises
  // along the locus) and rises after. `cross`: a coarse sample after which d takes the other
  // sign (a bisection; the tests below hold wherever it lands).
  const int before = reach_[static_cast<std::size_t>(bi * bands_ + bj)] > 0 ? 1 : -1;
  Eigen::Index below = -1, cross = nc;
  while (cross - below > 1) {
    const Eigen::Index mid = below + (cross - below) / 2;
    (sign(terms(mid).d) == -before ? cross : below) = mid;
  }
  Eigen::Index at = cross == 0 ? 0 : cross - 1;
  if (cross > 0 && cross < nc) {
    const Terms a = terms(at), b = terms(cross);
    if (b.numerator * a.denominator < a.numerator * b.denominator) at = cross;
  }
  alignas(32) double around[8];
  at_coarse(lanes, ws, w, sss, at, 1, around);
  upper = around[0];
  if (!std::isfinite(upper)) return false;
  // The rim, far beyond the rounding of chi2 (about 1e-12 of sss) and of the pair's terms. A
  // coarse sample past it on the falling side bounds every sample before it, on the rising side
  // every sample after it.
  const double rim = (upper + margin + 1e-6 * (sss + 1)) * (1 + 1e-9);
  first = 0, last = nc - 1;
  for (Eigen::Index k = cross - 1; k >= 0; --k) {
    const Terms t = terms(k);
    if (t.numerator > rim * t.denominator) {
      if (sign(t.d) != before) return false;
      first = k;
      break;
    }
  }
  for (Eigen::Index k = cross; k < nc; ++k) {
    const Terms t = terms(k);
    if (t.numerator > rim * t.denominator) {
      if (sign(t.d) != -before) return false;
      last = k;
      break;
    }
  }
  return true;
}

void DirectChi2::at_samples(const LaneBands& lanes, const double* ws, const double* w, double sss,
                            Eigen::Index from, Eigen::Index count, double* chi2) const {
  chi2_run(m_.data(), m2_.data(), stride_, lanes, ws, w, sss, from, count, chi2);
}

}  // namespace pyrocam
