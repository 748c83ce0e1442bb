// The likelihood fit's per-pixel kernels (see likelihood_kernels.h).
#include "runtime/likelihood_kernels.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "detail/vector_clones.h"
#include "runtime/estimator_kinds.h"

namespace pyrocam {

namespace {

// Lanes (detail/vector_clones.h): lane k sums bands b + k, as the four partial sums below are
// specified.

inline const Lanes& lanes_at(const double* at) { return *reinterpret_cast<const Lanes*>(at); }

inline double lane_sum(const Lanes& v) { return (v[0] + v[1]) + (v[2] + v[3]); }

// The lanes of ws . m and w . m2 at three rows (m, m + bands, m + 2 bands) over the whole lanes
// of bands, into a and c; returns the first band left (the caller adds the rest into lane 0).
// Three rows interleaved: their additions are independent.
[[gnu::always_inline]] inline int three_rows_lanes(const double* m, const double* m2,
                                                   const double* ws, const double* w, int bands,
                                                   Lanes (&a)[3], Lanes (&c)[3]) {
  const double *m1 = m + bands, *m3 = m + 2 * bands;
  const double *q1 = m2 + bands, *q3 = m2 + 2 * bands;
  Lanes a0 = {0, 0, 0, 0}, a1 = a0, a2 = a0, b0 = a0, b1 = a0, b2 = a0;
  int b = 0;
  for (; b + 4 <= bands; b += 4) {
    const Lanes x = lanes_at(ws + b), y = lanes_at(w + b);
    a0 += x * lanes_at(m + b);
    a1 += x * lanes_at(m1 + b);
    a2 += x * lanes_at(m3 + b);
    b0 += y * lanes_at(m2 + b);
    b1 += y * lanes_at(q1 + b);
    b2 += y * lanes_at(q3 + b);
  }
  a[0] = a0, a[1] = a1, a[2] = a2, c[0] = b0, c[1] = b1, c[2] = b2;
  return b;
}

}  // namespace

// chi2 = sss - ssm^2 / smm of the likelihood fit at one locus sample: ssm = sum (w s) m and
// smm = sum w m^2 over the bands, each in four partial sums added in a fixed order (the same
// bits in every compiled version).
PYROCAM_VECTOR_CLONES
double profiled_chi2(const double* m, const double* m2, const double* ws, const double* w,
                     int bands, double sss) {
  Lanes ssm = {0, 0, 0, 0}, smm = {0, 0, 0, 0};
  int b = 0;
  for (; b + 4 <= bands; b += 4) {
    ssm += lanes_at(ws + b) * lanes_at(m + b);
    smm += lanes_at(w + b) * lanes_at(m2 + b);
  }
  for (; b < bands; ++b) {
    ssm[0] += ws[b] * m[b];
    smm[0] += w[b] * m2[b];
  }
  const double sm = lane_sum(ssm), mm = lane_sum(smm);
  return sss - sm * sm / mm;
}

// Each sample's sums in the order profiled_chi2 adds them; three of them interleaved (their
// additions are independent), in explicit lanes (left to itself the compiler shuffles the rows
// into place and spills the sums).
PYROCAM_VECTOR_CLONES
void profiled_chi2_three(const double* m, const double* m2, const double* ws, const double* w,
                         int bands, double sss, double* chi2) {
  Lanes a[3], c[3];
  const int b = three_rows_lanes(m, m2, ws, w, bands, a, c);
  const double *m1 = m + bands, *m3 = m + 2 * bands;
  const double *q1 = m2 + bands, *q3 = m2 + 2 * bands;
  for (int k = b; k < bands; ++k) {
    a[0][0] += ws[k] * m[k], a[1][0] += ws[k] * m1[k], a[2][0] += ws[k] * m3[k];
    c[0][0] += w[k] * m2[k], c[1][0] += w[k] * q1[k], c[2][0] += w[k] * q3[k];
  }
  for (int s = 0; s < 3; ++s) {
    const double sm = lane_sum(a[s]), mm = lane_sum(c[s]);
    chi2[s] = sss - sm * sm / mm;
  }
}

namespace {

// lane_sum of each of a, b, c and d, in one vector: pairs added side by side, then the halves.
inline void lane_sums(const Lanes& a, const Lanes& b, const Lanes& c, const Lanes& d, Lanes& out) {
  const Lanes ab =
      __builtin_shufflevector(a, b, 0, 4, 2, 6) + __builtin_shufflevector(a, b, 1, 5, 3, 7);
  const Lanes cd =
      __builtin_shufflevector(c, d, 0, 4, 2, 6) + __builtin_shufflevector(c, d, 1, 5, 3, 7);
  out = __builtin_shufflevector(ab, cd, 0, 1, 4, 5) + __builtin_shufflevector(ab, cd, 2, 3, 6, 7);
}

}  // namespace

// profiled_chi2_three's sums pixel by pixel, then their lane sums and chi2 four at a time (one
// division of four instead of four): the same operations on each value, the same bits.
PYROCAM_VECTOR_CLONES
void profiled_chi2_three_four(const double* const* m, const double* const* m2,
                              const double* const* ws, const double* const* w, int width,
                              const double* sss, double* const* chi2) {
  Lanes a[3][4], c[3][4];  // [row][pixel]
  for (int k = 0; k < 4; ++k) {
    Lanes pa[3], pc[3];
    three_rows_lanes(m[k], m2[k], ws[k], w[k], width, pa, pc);
    for (int r = 0; r < 3; ++r) a[r][k] = pa[r], c[r][k] = pc[r];
  }
  const Lanes s = lanes_at(sss);
  for (int r = 0; r < 3; ++r) {
    Lanes sm, mm;
    lane_sums(a[r][0], a[r][1], a[r][2], a[r][3], sm);
    lane_sums(c[r][0], c[r][1], c[r][2], c[r][3], mm);
    const Lanes chi = s - sm * sm / mm;
    for (int k = 0; k < 4; ++k) chi2[k][r] = chi[k];
  }
}

// Band after band in one sum each (weigh_four adds four pixels' the same way, one per lane).
double fast_fraction(const double* s, const double* fast, int bands) {
  double f = 0, a = 0;
  for (int b = 0; b < bands; ++b) f += s[b] * fast[b], a += s[b];
  return f / a;
}

// The likelihood fit's weights of one pixel: w = 1 / variance for a band with a reading (finite
// and at least `weigh_dim`), 0 for one without; ws = w s (0 without a reading); *sss = sum w s^2.
// Returns how many bands read, and in *bright how many are at least `dim` too. In explicit lanes of
// four bands (left to the compiler, the divisions went through masked loads and sss through a
// chain of scalar additions).
PYROCAM_VECTOR_CLONES
int weigh_bands(const double* __restrict s, int bands, double weigh_dim, double dim,
                const double* __restrict gain, const double* __restrict floor, double* __restrict w,
                double* __restrict ws, double* sss, int* bright) {
  typedef std::int64_t Mask __attribute__((vector_size(32)));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Lanes zero = {0, 0, 0, 0}, one = {1, 1, 1, 1};
  const Lanes lows = {weigh_dim, weigh_dim, weigh_dim, weigh_dim}, dims = {dim, dim, dim, dim};
  const Lanes inf = {kInf, kInf, kInf, kInf};
  Lanes sum = zero;
  Mask counted = {0, 0, 0, 0}, bright_counted = counted;  // -1 per band with a weight, bright
  for (int b = 0; b < bands; b += 4) {
    // The last group's bands past `bands` read as 0 (no reading), from a copy: the caller's
    // arrays hold `bands` values.
    alignas(32) double tail[3][4];
    const double *at = s + b, *g = gain + b, *f = floor + b;
    if (b + 4 > bands) {
      for (int k = 0; k < 4; ++k) {
        const bool in = k < bands - b;
        tail[0][k] = in ? at[k] : 0.0, tail[1][k] = in ? g[k] : 0.0, tail[2][k] = in ? f[k] : 0.0;
      }
      at = tail[0], g = tail[1], f = tail[2];
    }
    const Lanes v = lanes_at(at);
    const Mask below_inf = v < inf;
    const Mask reads = (v >= lows) & below_inf;  // NaN fails both
    bright_counted += (v >= dims) & below_inf;
    const Lanes positive = v > zero ? v : zero;  // std::max(v, 0.0) wherever it matters
    const Lanes weight = one / (lanes_at(g) * positive + lanes_at(f));
    const Lanes wl = reads ? weight : zero, wsl = reads ? weight * v : zero;
    *reinterpret_cast<Lanes*>(w + b) = wl;
    *reinterpret_cast<Lanes*>(ws + b) = wsl;
    const Mask weighted = wl != zero;
    counted += weighted;
    sum += weighted ? wsl * v : zero;
  }
  *sss = lane_sum(sum);
  *bright = static_cast<int>(
      -(bright_counted[0] + bright_counted[1] + bright_counted[2] + bright_counted[3]));
  return static_cast<int>(-(counted[0] + counted[1] + counted[2] + counted[3]));
}

namespace {

// Four pixels' lanes of one group of four bands (v[j]: band g + j) as the rows of bands that
// rows[k] (pixel k) holds, at g.
inline void store_transposed(const Lanes (&v)[4], double* const* rows, int g) {
  const Lanes t0 = __builtin_shufflevector(v[0], v[1], 0, 4, 2, 6);
  const Lanes t1 = __builtin_shufflevector(v[0], v[1], 1, 5, 3, 7);
  const Lanes t2 = __builtin_shufflevector(v[2], v[3], 0, 4, 2, 6);
  const Lanes t3 = __builtin_shufflevector(v[2], v[3], 1, 5, 3, 7);
  *reinterpret_cast<Lanes*>(rows[0] + g) = __builtin_shufflevector(t0, t2, 0, 1, 4, 5);
  *reinterpret_cast<Lanes*>(rows[1] + g) = __builtin_shufflevector(t1, t3, 0, 1, 4, 5);
  *reinterpret_cast<Lanes*>(rows[2] + g) = __builtin_shufflevector(t0, t2, 2, 3, 6, 7);
  *reinterpret_cast<Lanes*>(rows[3] + g) = __builtin_shufflevector(t1, t3, 2, 3, 6, 7);
}

}  // namespace

// weigh_bands and fast_fraction of four neighbouring pixels with a lane for each pixel: the
// signals come as they lie in the band planes (no copy into rows of bands, whose single stores
// the rows' loads of four then waited on), each lane takes weigh_bands' operations, the partial
// sums over bands b, b + 4, ... are added in weigh_bands' order and the fraction's band after
// band: the same bits.
PYROCAM_VECTOR_CLONES
void weigh_four(const float* const* planes, int bands, std::size_t from, double weigh_dim,
                double dim, const double* __restrict gain, const double* __restrict floor,
                const double* __restrict fast, double* const* w, double* const* ws,
                double* const* s, FourWeighed& out) {
  typedef std::int64_t Mask __attribute__((vector_size(32)));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Lanes zero = {0, 0, 0, 0}, one = {1, 1, 1, 1};
  const Lanes lows = {weigh_dim, weigh_dim, weigh_dim, weigh_dim}, dims = {dim, dim, dim, dim};
  const Lanes inf = {kInf, kInf, kInf, kInf};
  Lanes sum[4] = {zero, zero, zero, zero}, fast_sum = zero, all_sum = zero;
  Mask counted = {0, 0, 0, 0}, bright_counted = counted, saturated = counted;
  for (int g = 0; g < bands; g += 4) {
    Lanes wl[4], wsl[4], v[4];
    for (int j = 0; j < 4; ++j) {
      const int b = g + j;
      if (b >= bands) {
        wl[j] = wsl[j] = v[j] = zero;
        continue;
      }
      // Element by element: GCC 12 converts a vector of four floats in two halves through the
      // stack, these into one vcvtps2pd (the same values).
      const float* at = planes[b] + from;
      v[j] = Lanes{at[0], at[1], at[2], at[3]};
      const Mask below_inf = v[j] < inf;
      const Mask reads = (v[j] >= lows) & below_inf;
      bright_counted += (v[j] >= dims) & below_inf;
      saturated += v[j] == inf;
      const Lanes positive = v[j] > zero ? v[j] : zero;
      const double gb = gain[b], fb = floor[b], fast_b = fast[b];
      const Lanes weight = one / (Lanes{gb, gb, gb, gb} * positive + Lanes{fb, fb, fb, fb});
      wl[j] = reads ? weight : zero, wsl[j] = reads ? weight * v[j] : zero;
      const Mask weighted = wl[j] != zero;
      counted += weighted;
      sum[j] += weighted ? wsl[j] * v[j] : zero;
      fast_sum += v[j] * Lanes{fast_b, fast_b, fast_b, fast_b};
      all_sum += v[j];
    }
    store_transposed(wl, w, g);
    store_transposed(wsl, ws, g);
    if (s) store_transposed(v, s, g);
  }
  const Lanes sss = (sum[0] + sum[1]) + (sum[2] + sum[3]);
  const Lanes fraction = fast_sum / all_sum;
  for (int k = 0; k < 4; ++k) {
    out.sss[k] = sss[k];
    out.fraction[k] = fraction[k];
    out.reading[k] = static_cast<int>(-counted[k]);
    out.bright[k] = static_cast<int>(-bright_counted[k]);
    out.saturated[k] = static_cast<int>(-saturated[k]);
  }
}

// Per pixel, how many of its bands read as weigh_bands decides, in single precision (dim_f is
// the least float whose double is at least the threshold, so the comparison is weigh_bands'
// own). Eight pixels at a time over all bands, in vectors of four that SSE2 has too (a plain loop
// over the bands' rows compiled to scalar code in both versions).
PYROCAM_VECTOR_CLONES
void count_reading_bands(const float* const* planes, int bands, std::size_t from, std::size_t n,
                         float dim_f, std::int32_t* __restrict reading) {
  typedef float Floats __attribute__((vector_size(16), aligned(4), may_alias));
  typedef std::int32_t Ints __attribute__((vector_size(16), aligned(4), may_alias));
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const Floats dim = {dim_f, dim_f, dim_f, dim_f}, inf = {kInf, kInf, kInf, kInf};
  std::size_t k = 0;
  for (; k + 8 <= n; k += 8) {
    Ints low = {0, 0, 0, 0}, high = low;  // -1 per band that reads (vector comparisons)
    for (int b = 0; b < bands; ++b) {
      const float* v = planes[b] + from + k;
      const Floats x = *reinterpret_cast<const Floats*>(v);
      const Floats y = *reinterpret_cast<const Floats*>(v + 4);
      low += (x >= dim) & (x < inf);
      high += (y >= dim) & (y < inf);
    }
    *reinterpret_cast<Ints*>(reading + k) = -low;
    *reinterpret_cast<Ints*>(reading + k + 4) = -high;
  }
  for (; k < n; ++k) {
    std::int32_t count = 0;
    for (int b = 0; b < bands; ++b) {
      const float x = planes[b][from + k];
      count += x >= dim_f && x < kInf ? 1 : 0;
    }
    reading[k] = count;
  }
}

// Projections p = V^T (w s), q = V2^T w on the factors (bands x kMaxRank each, zero padded), in
// double and single precision, and |w s|^2, |w|^2. The sums start from the first band's products
// (zeroed arrays compile to a slow rep stos).
PYROCAM_VECTOR_CLONES
void project(const double* __restrict ws, const double* __restrict w, int bands,
             const double* __restrict v, const double* __restrict v2, double* __restrict p,
             double* __restrict q, float* __restrict pf, float* __restrict qf,
             double* __restrict squares) {
  double a[kMaxRank], c[kMaxRank];
  for (int r = 0; r < kMaxRank; ++r) {
    a[r] = ws[0] * v[r];
    c[r] = w[0] * v2[r];
  }
  double ws2 = ws[0] * ws[0], w2 = w[0] * w[0];
  for (int b = 1; b < bands; ++b) {
    for (int r = 0; r < kMaxRank; ++r) {
      a[r] += ws[b] * v[b * kMaxRank + r];
      c[r] += w[b] * v2[b * kMaxRank + r];
    }
    ws2 += ws[b] * ws[b];
    w2 += w[b] * w[b];
  }
  for (int r = 0; r < kMaxRank; ++r) {
    p[r] = a[r];
    q[r] = c[r];
    pf[r] = static_cast<float>(a[r]);
    qf[r] = static_cast<float>(c[r]);
  }
  squares[0] = ws2;
  squares[1] = w2;
}

// Blocks of samples keep their sums in registers, ssm's and smm's summed in the same loop (twice
// as many independent additions: the sums are bound by the adds' latency, not their number);
// selects, so that the bounds vectorise.
PYROCAM_VECTOR_CLONES
void bounded_chi2(const float* along, int rank, const float* along2, int rank2,
                  std::ptrdiff_t stride, std::ptrdiff_t count, const float* p, const float* q,
                  float sss, float ssm_error, float smm_error, float slack, float* lower,
                  float* upper) {
  for (std::ptrdiff_t i0 = 0; i0 < count; i0 += kCoarseBlock) {
    // The sums start from the first products (zeroed arrays compile to a slow rep stos).
    float ssm[kCoarseBlock], smm[kCoarseBlock];
    for (std::ptrdiff_t j = 0; j < kCoarseBlock; ++j) {
      ssm[j] = p[0] * along[i0 + j];
      smm[j] = q[0] * along2[i0 + j];
    }
    int r = 1;
    for (; r < rank && r < rank2; ++r) {
      const float* a = along + r * stride + i0;
      const float* a2 = along2 + r * stride + i0;
      for (std::ptrdiff_t j = 0; j < kCoarseBlock; ++j) {
        ssm[j] += p[r] * a[j];
        smm[j] += q[r] * a2[j];
      }
    }
    for (; r < rank; ++r) {
      const float* a = along + r * stride + i0;
      for (std::ptrdiff_t j = 0; j < kCoarseBlock; ++j) ssm[j] += p[r] * a[j];
    }
    for (; r < rank2; ++r) {
      const float* a = along2 + r * stride + i0;
      for (std::ptrdiff_t j = 0; j < kCoarseBlock; ++j) smm[j] += q[r] * a[j];
    }
    // One division for both bounds: top^2 / bottom = top^2 over inv and least^2 / over = least^2
    // bottom inv with inv = 1 / (bottom over), a few roundings more, far inside slack. Where
    // bottom over is tiny or not positive: no lower bound, and chi2 <= sss.
    for (std::ptrdiff_t j = 0; j < kCoarseBlock; ++j) {
      const float x = std::abs(ssm[j]), top = x + ssm_error, least = std::max(x - ssm_error, 0.0f);
      const float bottom = smm[j] - smm_error, over = smm[j] + smm_error, both = bottom * over;
      const bool usable = bottom > 0 && both > 1e-30f;
      const float inv = 1.0f / (usable ? both : 1.0f);
      lower[i0 + j] =
          usable ? sss - top * top * over * inv - slack : -std::numeric_limits<float>::max();
      upper[i0 + j] = sss - (usable ? least * least * bottom * inv : 0.0f) + slack;
    }
  }
}

// Flags as bytes (the ends apart, so that the rest vectorises), scanned eight at a time: most
// samples are not minima.
PYROCAM_VECTOR_CLONES
int minimum_candidates(const float* lower, const float* upper, std::ptrdiff_t count,
                       std::int32_t* at) {
  alignas(32) std::uint8_t flag[kMaxMinimumCandidates + 8];
  flag[0] = lower[0] <= upper[1];
  for (std::ptrdiff_t k = 1; k + 1 < count; ++k)
    flag[k] = (lower[k] <= upper[k - 1]) & (lower[k] <= upper[k + 1]);
  flag[count - 1] = lower[count - 1] <= upper[count - 2];
  std::memset(flag + count, 0, 8);
  int n = 0;
  for (std::ptrdiff_t k0 = 0; k0 < count; k0 += 8) {
    std::uint64_t word;
    std::memcpy(&word, flag + k0, sizeof word);
    if (!word) continue;
    for (std::ptrdiff_t k = k0; k < k0 + 8; ++k)
      if (flag[k]) at[n++] = static_cast<std::int32_t>(k);
  }
  return n;
}

// The least upper bound is sss - g + slack for the largest g = (|ssm| - ssm_error)^2 / (smm +
// smm_error), the bound chi2_upper gives at that sample (likelihood_bounds.h). A sample is open
// where (|ssm| + ssm_error)^2 >= bar (smm - smm_error), bar = sss - 2 slack - least upper bound,
// i.e. its lower bound (chi2_lower) is not above it.
PYROCAM_VECTOR_CLONES
int window_candidates(const double* ssm, const double* smm, std::ptrdiff_t count, double sss,
                      double ssm_error, double smm_error, double slack, std::uint8_t* open) {
  // Each sample's quotient (vectorised divisions), then the largest in four lanes; a sum that
  // may be 0 (no bound) gives 0.
  constexpr std::ptrdiff_t kMost = 64;
  alignas(32) double quotient[kMost];
  double g = 0;
  for (std::ptrdiff_t from = 0; from < count; from += kMost) {
    const std::ptrdiff_t part = std::min(kMost, count - from);
    for (std::ptrdiff_t i = 0; i < part; ++i) {
      const double least = std::max(std::abs(ssm[from + i]) - ssm_error, 0.0);
      const double b = smm[from + i] + smm_error;
      const double v = least * least / (b > 0 ? b : 1.0);
      quotient[i] = b > 0 && v < std::numeric_limits<double>::infinity() ? v : 0.0;
    }
    double most[4] = {0, 0, 0, 0};
    std::ptrdiff_t i = 0;
    for (; i + 4 <= part; i += 4)
      for (int j = 0; j < 4; ++j) most[j] = quotient[i + j] > most[j] ? quotient[i + j] : most[j];
    for (; i < part; ++i) most[0] = quotient[i] > most[0] ? quotient[i] : most[0];
    for (int j = 0; j < 4; ++j) g = most[j] > g ? most[j] : g;
  }
  const double least_upper = sss - g + slack;
  const double bar = sss - 2 * slack - least_upper;
  for (std::ptrdiff_t i = 0; i < count; ++i) {
    const double top = std::abs(ssm[i]) + ssm_error, bottom = smm[i] - smm_error;
    open[i] = !(bottom > 0) || top * top >= bar * bottom;
  }
  int n = 0;
  for (std::ptrdiff_t i = 0; i < count; ++i) n += open[i];
  return n;
}

// Summed r after r into explicit lanes (left to itself the compiler transposes the basis).
PYROCAM_VECTOR_CLONES
void to_window_basis(const double* basis, int rank, const double* x, double* out) {
  static_assert(kMaxWindowRank == 8);
  Lanes low = {0, 0, 0, 0}, high = low;
  for (int r = 0; r < rank; ++r) {
    const Lanes xr = {x[r], x[r], x[r], x[r]};
    low += xr * lanes_at(basis + r * kMaxWindowRank);
    high += xr * lanes_at(basis + r * kMaxWindowRank + 4);
  }
  std::memcpy(out, &low, sizeof low);
  std::memcpy(out + 4, &high, sizeof high);
}

// Blocks of samples keep their sums in registers, ssm's and smm's summed in the same loop (as in
// bounded_chi2).
PYROCAM_VECTOR_CLONES
void approximate_sums(const double* along, int rank, const double* along2, int rank2,
                      std::ptrdiff_t stride, std::ptrdiff_t from, std::ptrdiff_t count,
                      const double* p, const double* q, double* ssm, double* smm) {
  for (std::ptrdiff_t i0 = 0; i0 < count; i0 += kWindowBlock) {
    double a[kWindowBlock], b[kWindowBlock];  // from the first products, as in bounded_chi2
    for (std::ptrdiff_t j = 0; j < kWindowBlock; ++j) {
      a[j] = p[0] * along[from + i0 + j];
      b[j] = q[0] * along2[from + i0 + j];
    }
    int r = 1;
    for (; r < rank && r < rank2; ++r) {
      const double* f = along + r * stride + from + i0;
      const double* f2 = along2 + r * stride + from + i0;
      for (std::ptrdiff_t j = 0; j < kWindowBlock; ++j) {
        a[j] += p[r] * f[j];
        b[j] += q[r] * f2[j];
      }
    }
    for (; r < rank; ++r) {
      const double* f = along + r * stride + from + i0;
      for (std::ptrdiff_t j = 0; j < kWindowBlock; ++j) a[j] += p[r] * f[j];
    }
    for (; r < rank2; ++r) {
      const double* f = along2 + r * stride + from + i0;
      for (std::ptrdiff_t j = 0; j < kWindowBlock; ++j) b[j] += q[r] * f[j];
    }
    for (std::ptrdiff_t j = 0; j < kWindowBlock; ++j) ssm[i0 + j] = a[j], smm[i0 + j] = b[j];
  }
}

}  // namespace pyrocam
