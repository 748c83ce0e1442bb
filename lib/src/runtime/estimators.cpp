// Over 600 lines: the three estimators (network, lookup table, likelihood fit), the noise model
// and the GUM uncertainty share private helpers here; splitting them along those stages is
// planned with the architecture issue (one file per estimator).
#include "pyrocam/runtime/estimators.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "detail/portable_math.h"
#include "pyrocam/core/spectrum.h"
#include "detail/vector_clones.h"

namespace pyrocam {
namespace {

constexpr int kMaxBands = 64;

// Samples per step of approximate_chi2: long coarse scans in single precision, short windows
// in double precision.
constexpr std::ptrdiff_t kCoarseBlock = 32, kWindowBlock = 8;

// Approximate chi2 of the likelihood fit from low-rank factors stored rank after rank, `stride`
// samples each (see LikelihoodEstimator): at `count` samples from `from`, into out[0 .. count
// rounded up to kBlock) (values past count are meaningless). Blocks of samples keep their sums
// in registers.
// (Inlined into each compiled version, which would otherwise call one baseline copy.)
template <std::ptrdiff_t kBlock, class Real>
[[gnu::always_inline]] inline void approximate_chi2_impl(const Real* along, int rank,
                                                         const Real* along2, int rank2,
                                                         std::ptrdiff_t stride, std::ptrdiff_t from,
                                                         std::ptrdiff_t count, const Real* p,
                                                         const Real* q, Real sss, Real* out) {
  for (std::ptrdiff_t i0 = 0; i0 < count; i0 += kBlock) {
    Real ssm[kBlock] = {}, smm[kBlock] = {};
    for (int r = 0; r < rank; ++r) {
      const Real* a = along + r * stride + from + i0;
      for (std::ptrdiff_t j = 0; j < kBlock; ++j) ssm[j] += p[r] * a[j];
    }
    for (int r = 0; r < rank2; ++r) {
      const Real* a = along2 + r * stride + from + i0;
      for (std::ptrdiff_t j = 0; j < kBlock; ++j) smm[j] += q[r] * a[j];
    }
    for (std::ptrdiff_t j = 0; j < kBlock; ++j) out[i0 + j] = sss - ssm[j] * ssm[j] / smm[j];
  }
}

PYROCAM_VECTOR_CLONES
void approximate_chi2(const float* along, int rank, const float* along2, int rank2,
                      std::ptrdiff_t stride, std::ptrdiff_t from, std::ptrdiff_t count,
                      const float* p, const float* q, float sss, float* out) {
  approximate_chi2_impl<kCoarseBlock>(along, rank, along2, rank2, stride, from, count, p, q, sss,
                                      out);
}

PYROCAM_VECTOR_CLONES
void approximate_chi2(const double* along, int rank, const double* along2, int rank2,
                      std::ptrdiff_t stride, std::ptrdiff_t from, std::ptrdiff_t count,
                      const double* p, const double* q, double sss, double* out) {
  approximate_chi2_impl<kWindowBlock>(along, rank, along2, rank2, stride, from, count, p, q, sss,
                                      out);
}

// chi2 = sss - ssm^2 / smm of the likelihood fit at one locus sample: ssm = sum (w s) m and
// smm = sum w m^2 over the bands, each in four partial sums added in a fixed order (the same
// bits in every compiled version).
PYROCAM_VECTOR_CLONES
double profiled_chi2(const double* m, const double* m2, const double* ws, const double* w,
                     int bands, double sss) {
  double ssm[4] = {0, 0, 0, 0}, smm[4] = {0, 0, 0, 0};
  int b = 0;
  for (; b + 4 <= bands; b += 4)
    for (int k = 0; k < 4; ++k) {
      ssm[k] += ws[b + k] * m[b + k];
      smm[k] += w[b + k] * m2[b + k];
    }
  for (; b < bands; ++b) {
    ssm[0] += ws[b] * m[b];
    smm[0] += w[b] * m2[b];
  }
  const double sm = (ssm[0] + ssm[1]) + (ssm[2] + ssm[3]);
  const double mm = (smm[0] + smm[1]) + (smm[2] + smm[3]);
  return sss - sm * sm / mm;
}

// The likelihood fit's weights of one pixel: w = 1 / variance for a band with a reading (finite
// and at least `dim`), 0 for one without; ws = w s (0 without a reading); *sss = sum w s^2.
// Returns how many bands read. Selects, so that the divisions vectorise.
PYROCAM_VECTOR_CLONES
int weigh_bands(const double* __restrict s, int bands, double dim, const double* __restrict gain,
                const double* __restrict floor, double* __restrict w, double* __restrict ws,
                double* sss) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  for (int b = 0; b < bands; ++b) {
    const double v = s[b];
    const bool reads = v >= dim && v < kInf;  // NaN fails both
    const double weight = 1.0 / (gain[b] * std::max(v, 0.0) + floor[b]);
    w[b] = reads ? weight : 0.0;
    ws[b] = reads ? weight * v : 0.0;
  }
  int valid = 0;
  double sum = 0;
  for (int b = 0; b < bands; ++b) {
    valid += w[b] != 0.0;
    sum += w[b] != 0.0 ? ws[b] * s[b] : 0.0;
  }
  *sss = sum;
  return valid;
}

constexpr int kMaxRank = 16;  // low-rank factors of the likelihood fit's locus

// Projections p = V^T (w s), q = V2^T w on the factors (bands x kMaxRank each, zero padded), in
// double and single precision.
PYROCAM_VECTOR_CLONES
void project(const double* __restrict ws, const double* __restrict w, int bands,
             const double* __restrict v, const double* __restrict v2, double* __restrict p,
             double* __restrict q, float* __restrict pf, float* __restrict qf) {
  for (int b = 0; b < bands; ++b)
    for (int r = 0; r < kMaxRank; ++r) {
      p[r] += ws[b] * v[b * kMaxRank + r];
      q[r] += w[b] * v2[b * kMaxRank + r];
    }
  for (int r = 0; r < kMaxRank; ++r) {
    pf[r] = static_cast<float>(p[r]);
    qf[r] = static_cast<float>(q[r]);
  }
}

class MlpEstimator : public TemperatureEstimator {
 public:
  using TemperatureEstimator::TemperatureEstimator;
  double temperature_c(const double* s) const override {
    if (!all_bands_valid(s)) return NAN;
    const Normalisation& n = model_.profile().normalisation;
    double ref = 0;
    for (int b : n.reference) ref += s[b];
    ref /= static_cast<double>(n.reference.size());
    double x[kMaxBands];
    for (std::size_t i = 0; i < n.numerators.size(); ++i) x[i] = s[n.numerators[i]] / ref;
    return in_range(model_.mlp.predict(x));
  }
};

// Weighted least squares of the band signals against the modelled locus with a free scale
// (unknown emissivity, exposure and geometry): chi2(T) = sum w (S - a m(T))^2, a profiled out.
// The locus is sampled every 1 degC; chi2 is scanned every kCoarse samples keeping every local
// minimum (with few valid bands the locus can pass the same ratios twice, and a reading that
// fits two temperatures is no reading), each minimum is refined to the 1 degC sample within
// kCoarse of it, and a parabola through the best sample and its neighbours gives the answer.
// This base holds what both implementations share: the weights, the exact chi2 and the decision.
class LikelihoodFit : public TemperatureEstimator {
 public:
  // Two minima closer than this in chi2 (about 3 sigma) make the reading ambiguous.
  static constexpr double kAmbiguityChi2 = 9.0;
  static constexpr Eigen::Index kCoarse = 20;

  explicit LikelihoodFit(const ThermalModel& m)
      : TemperatureEstimator(m),
        locus_(make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0)),
        rates_(static_cast<std::size_t>(locus_.size() * bands_)),
        squares_(rates_.size()) {
    for (Eigen::Index i = 0; i < locus_.size(); ++i)
      for (int b = 0; b < bands_; ++b) {
        const double m = locus_.rates(i, b);
        rates_[static_cast<std::size_t>(i * bands_ + b)] = m;
        squares_[static_cast<std::size_t>(i * bands_ + b)] = m * m;
      }
    for (int b = 0; b < bands_; ++b) {
      const SignalNoise n = signal_noise(m.profile(), b);
      shot_gain_[b] = n.shot_gain;
      noise_floor_[b] = n.floor_dn2;
    }
  }

 protected:
  struct Minimum {
    Eigen::Index index;
    double chi2;
    double below, above;  // chi2 at index -1 and +1 when already known, else NaN
  };

  // A pixel's signals as the fit uses them: inverse noise variances w (0 drops a band:
  // saturated, NaN or dim; the rest still fix the temperature), w*s (0 for a dropped band) and
  // sum w s^2.
  struct Weighted {
    double w[kMaxBands], ws[kMaxBands];
    double sss;
  };

  // Returns how many bands count.
  int weigh(const double* s, Weighted& px) const {
    return weigh_bands(s, bands_, dim_dn_, shot_gain_, noise_floor_, px.w, px.ws, &px.sss);
  }

  // chi2 at locus sample i.
  double chi2(Eigen::Index i, const Weighted& px) const {
    return profiled_chi2(&rates_[static_cast<std::size_t>(i * bands_)],
                         &squares_[static_cast<std::size_t>(i * bands_)], px.ws, px.w, bands_,
                         px.sss);
  }

  // The reading from the refined minima: the best one, unless another one far from it fits
  // almost as well (ambiguous) or it sits at an end of the locus (outside the range).
  double decide(const Minimum* minima, std::size_t count, const Weighted& px) const {
    std::size_t best_k = 0;
    double best_chi2 = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < count; ++k)
      if (minima[k].chi2 < best_chi2) best_chi2 = minima[k].chi2, best_k = k;
    const Eigen::Index best = count ? minima[best_k].index : 0;
    for (std::size_t k = 0; k < count; ++k)
      if (std::abs(minima[k].index - best) > 3 * kCoarse &&
          minima[k].chi2 - best_chi2 < kAmbiguityChi2)
        return NAN;
    const Eigen::Index n = locus_.size();
    if (best == 0 || best == n - 1) return NAN;  // at the edge: outside the model's range
    // Parabola through the minimum and its neighbours for sub-step resolution.
    const double cm = std::isnan(minima[best_k].below) ? chi2(best - 1, px) : minima[best_k].below;
    const double cp = std::isnan(minima[best_k].above) ? chi2(best + 1, px) : minima[best_k].above;
    const double denom = cm - 2 * best_chi2 + cp;
    const double offset = denom > 0 ? 0.5 * (cm - cp) / denom : 0.0;
    const double step = locus_.temperature_c[1] - locus_.temperature_c[0];
    return in_range(locus_.temperature_c[best] + std::clamp(offset, -1.0, 1.0) * step);
  }

  Locus locus_;
  std::vector<double> rates_, squares_;  // m and m^2: samples x bands, row after row
  double shot_gain_[kMaxBands] = {}, noise_floor_[kMaxBands] = {};
};

// The definition: every coarse sample and every 1 degC sample of each refinement window.
class ExhaustiveLikelihoodEstimator : public LikelihoodFit {
 public:
  using LikelihoodFit::LikelihoodFit;

  double temperature_c(const double* s) const override {
    Weighted px;
    if (weigh(s, px) < min_bands_) return NAN;
    const Eigen::Index n = locus_.size();
    std::vector<double> c;
    for (Eigen::Index i = 0; i < n; i += kCoarse) c.push_back(chi2(i, px));
    std::vector<Minimum> refined;
    for (std::size_t k = 0; k < c.size(); ++k) {
      if (!((k == 0 || c[k] <= c[k - 1]) && (k + 1 == c.size() || c[k] <= c[k + 1]))) continue;
      const Eigen::Index around = static_cast<Eigen::Index>(k) * kCoarse;
      Minimum best{around, chi2(around, px), NAN, NAN};
      const Eigen::Index lo = std::max<Eigen::Index>(0, around - kCoarse);
      const Eigen::Index hi = std::min<Eigen::Index>(n - 1, around + kCoarse);
      for (Eigen::Index i = lo; i <= hi; ++i) {
        const double v = chi2(i, px);
        if (v < best.chi2) best = {i, v, NAN, NAN};
      }
      refined.push_back(best);
    }
    return decide(refined.data(), refined.size(), px);
  }
};

// The same fit, fast. chi2(T) = sss - ssm(T)^2 / smm(T) does not change when m(T) is scaled,
// so the locus rows are normalised, and the normalised rates (and their squares) over the
// samples form matrices of very low rank (smooth spectra: 9 to 11 of 25 columns leave rows off by
// 1e-8 to 1e-10). With such factors, ssm and smm at a sample cost one multiply-add per rank
// instead of one per band. An approximate chi2 from them steers the scan; the exact chi2 (double
// precision, as the exhaustive scan computes it) settles everything the approximation's error
// bound leaves open:
//  - coarse scan in single precision: two coarse samples closer than twice the bound are
//    compared exactly;
//  - refinement window in double precision from finer factors: every sample within the bound of
//    the exact chi2 of the approximate best is evaluated exactly, and the best of those wins.
// So the answer and the no-reading decisions are those of the exhaustive scan (the unit tests
// compare both on noisy pixels, with saturated, dim and NaN bands).
class LikelihoodEstimator : public LikelihoodFit {
 public:
  // Row error left by the factors (rows have unit length): coarse, window.
  static constexpr double kCoarseRankTolerance = 1e-8, kWindowRankTolerance = 1e-10;
  // Error bounds of the approximate chi2, relative to sum w s^2 (ten times the largest seen on
  // noisy pixels of both reference cameras).
  static constexpr double kCoarseError = 1e-5, kWindowError = 1e-8;
  static constexpr Eigen::Index kMaxCoarse = 504;  // coarse samples: a 10 000 degC range

  explicit LikelihoodEstimator(const ThermalModel& m) : LikelihoodFit(m) {
    const Eigen::Index n = locus_.size();
    Eigen::MatrixXd unit(n, bands_), squares(n, bands_);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::RowVectorXd row = locus_.rates.row(i);
      const double norm = row.norm();
      if (!(norm > 0) || !std::isfinite(norm))
        throw InputError("method likelihood: the model's locus has no signal at " +
                         std::to_string(locus_.temperature_c[i]) + " degC");
      unit.row(i) = row / norm;
      squares.row(i) = unit.row(i).array().square().matrix();
    }
    coarse_count_ = (n + kCoarse - 1) / kCoarse;
    // The coarse scan compares each sample with its neighbours: it needs two.
    if (coarse_count_ < 2)
      throw InputError("method likelihood: the model's temperature range (" +
                       std::to_string(m.min_temperature_c) + " to " +
                       std::to_string(m.max_temperature_c) + " degC) spans less than " +
                       std::to_string(kCoarse) + " degC");
    if (coarse_count_ > kMaxCoarse)
      throw InputError("method likelihood: the model's temperature range is too wide");
    stride_ = padded(n);
    coarse_stride_ = padded(coarse_count_);
    factor(unit, across_, rank_, coarse_rank_, along_, coarse_along_);
    factor(squares, across2_, rank2_, coarse_rank2_, along2_, coarse_along2_);
  }

  double temperature_c(const double* s) const override {
    Weighted px;
    if (weigh(s, px) < min_bands_) return NAN;
    // Projections of w*s and w on the factors.
    alignas(32) double p[kMaxRank] = {}, q[kMaxRank] = {};
    alignas(32) float pf[kMaxRank], qf[kMaxRank];
    project(px.ws, px.w, bands_, across_.data(), across2_.data(), p, q, pf, qf);

    // Coarse scan.
    alignas(32) float c[kMaxCoarse + kCoarseBlock];  // written in whole blocks
    const Eigen::Index nc = coarse_count_;
    approximate_chi2(coarse_along_.data(), coarse_rank_, coarse_along2_.data(), coarse_rank2_,
                     coarse_stride_, 0, nc, pf, qf, static_cast<float>(px.sss), c);
    const double tie = kCoarseError * px.sss + 1e-9;
    auto not_above = [&](Eigen::Index k, Eigen::Index other) {
      if (std::abs(c[k] - c[other]) > 2 * tie) return c[k] <= c[other];
      return chi2(k * kCoarse, px) <= chi2(other * kCoarse, px);  // too close to tell: exactly
    };
    // Local minima. A sample clearly above a neighbour is none (flags as bytes, scanned eight
    // at a time: most samples are not minima); the few others are checked.
    const auto margin = static_cast<float>(2 * tie);
    alignas(16) std::uint8_t candidate[kMaxCoarse + 8];
    std::memset(candidate + nc, 0, 8);
    candidate[0] = c[0] <= c[1] + margin;
    for (Eigen::Index k = 1; k + 1 < nc; ++k)
      candidate[k] = (c[k] <= c[k - 1] + margin) & (c[k] <= c[k + 1] + margin);
    candidate[nc - 1] = c[nc - 1] <= c[nc - 2] + margin;
    Minimum refined[kMaxCoarse];
    std::size_t count = 0;
    for (Eigen::Index k0 = 0; k0 < nc; k0 += 8) {
      std::uint64_t word;
      std::memcpy(&word, candidate + k0, sizeof word);
      if (!word) continue;
      for (Eigen::Index k = k0; k < std::min(k0 + 8, nc); ++k) {
        if (!candidate[k]) continue;
        if (!((k == 0 || not_above(k, k - 1)) && (k + 1 == nc || not_above(k, k + 1)))) continue;
        refined[count++] = refine(k * kCoarse, px, p, q);
      }
    }
    return decide(refined, count, px);
  }

 private:
  // Room for n samples and the reads of a last, partial block of approximate_chi2.
  static constexpr Eigen::Index padded(Eigen::Index n) {
    return (n + kCoarseBlock - 1) / kCoarseBlock * kCoarseBlock + kCoarseBlock;
  }

  // Low-rank factors of a samples x bands matrix A ~ (A V) V^T, V orthonormal: across (bands x
  // kMaxRank, V zero padded), along (rank x stride_, A V rank after rank, zero padded) for the
  // windows and coarse_along (coarse rank x coarse_stride_, every kCoarse-th sample, single
  // precision) for the coarse scan. V is grown greedily from the row A leaves least explained
  // (pivoted Gram-Schmidt), so its first columns are the coarse factors.
  void factor(const Eigen::MatrixXd& a, std::vector<double>& across, int& rank, int& coarse_rank,
              std::vector<double>& along, std::vector<float>& coarse_along) const {
    Eigen::MatrixXd left = a;
    Eigen::MatrixXd v(a.cols(), 0);
    coarse_rank = 0;
    for (int r = 0; r < std::min<int>(kMaxRank, static_cast<int>(a.cols())); ++r) {
      Eigen::Index worst;
      const double norm = left.rowwise().norm().maxCoeff(&worst);
      if (norm <= kCoarseRankTolerance && coarse_rank == 0) coarse_rank = r;
      if (norm <= kWindowRankTolerance) break;
      Eigen::VectorXd dir = left.row(worst).transpose() / norm;
      for (int pass = 0; pass < 2; ++pass) dir -= v * (v.transpose() * dir);  // stay orthogonal
      dir.normalize();
      left -= (left * dir) * dir.transpose();
      v.conservativeResize(Eigen::NoChange, r + 1);
      v.col(r) = dir;
    }
    rank = static_cast<int>(v.cols());
    if (coarse_rank == 0) coarse_rank = rank;
    const Eigen::MatrixXd av = a * v;
    across.assign(static_cast<std::size_t>(bands_ * kMaxRank), 0.0);
    along.assign(static_cast<std::size_t>(rank * stride_), 0.0);
    coarse_along.assign(static_cast<std::size_t>(coarse_rank * coarse_stride_), 0.f);
    for (int r = 0; r < rank; ++r) {
      for (int b = 0; b < bands_; ++b) across[static_cast<std::size_t>(b * kMaxRank + r)] = v(b, r);
      for (Eigen::Index i = 0; i < a.rows(); ++i)
        along[static_cast<std::size_t>(r * stride_ + i)] = av(i, r);
      if (r >= coarse_rank) continue;
      for (Eigen::Index j = 0; j < coarse_count_; ++j)
        coarse_along[static_cast<std::size_t>(r * coarse_stride_ + j)] =
            static_cast<float>(av(j * kCoarse, r));
    }
  }

  // The exact best 1 degC sample within kCoarse of `around`, as the exhaustive scan finds it:
  // the true best is no worse than the approximate best `at`, so its approximate chi2 is at most
  // the exact chi2 of `at` plus the error bound; only such samples are evaluated exactly.
  Minimum refine(Eigen::Index around, const Weighted& px, const double* p, const double* q) const {
    const Eigen::Index n = locus_.size();
    const Eigen::Index lo = std::max<Eigen::Index>(0, around - kCoarse);
    const Eigen::Index hi = std::min<Eigen::Index>(n - 1, around + kCoarse);
    alignas(32) double f[(2 * kCoarse + 1 + kWindowBlock - 1) / kWindowBlock * kWindowBlock];
    approximate_chi2(along_.data(), rank_, along2_.data(), rank2_, stride_, lo, hi - lo + 1, p, q,
                     px.sss, f);
    Eigen::Index at = lo;
    for (Eigen::Index i = lo; i <= hi; ++i)
      if (f[i - lo] < f[at - lo]) at = i;
    double exact[2 * kCoarse + 1];
    for (Eigen::Index i = lo; i <= hi; ++i) exact[i - lo] = NAN;
    exact[at - lo] = chi2(at, px);
    Minimum best{at, exact[at - lo], NAN, NAN};
    const double bound = best.chi2 + kWindowError * px.sss + 1e-12;
    for (Eigen::Index i = lo; i <= hi; ++i) {
      if (i == at || f[i - lo] > bound) continue;
      exact[i - lo] = chi2(i, px);
      if (exact[i - lo] < best.chi2 || (exact[i - lo] == best.chi2 && i < best.index))
        best = {i, exact[i - lo], NAN, NAN};
    }
    // Neighbours already evaluated are kept for the parabola.
    if (best.index - 1 >= lo) best.below = exact[best.index - 1 - lo];
    if (best.index + 1 <= hi) best.above = exact[best.index + 1 - lo];
    return best;
  }

  int rank_ = 0, rank2_ = 0, coarse_rank_ = 0, coarse_rank2_ = 0;
  Eigen::Index stride_ = 0, coarse_count_ = 0, coarse_stride_ = 0;
  std::vector<double> across_, across2_, along_, along2_;
  std::vector<float> coarse_along_, coarse_along2_;
};

// The lookup table's per-pixel passes (see LutEstimator::estimate), compiled for AVX2 too.
namespace lut {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kInTable = 0.0f, kOffTable = -1.0f;  // pixel status codes; NaN: no reading

struct Grid {
  float dim, inv_h, offset_x, offset_y, cells_x, cells_y;
};

// Status and table coordinates (cells) of m pixels from their two numerators a, b and their
// reference r; `others_read` (may be null) flags pixels whose other bands are all readable.
// Coordinates are 0 where the status is not kInTable. Selects the compiler turns into vector
// masks: NaN fails every comparison, +INF the upper ones. Returns whether any pixel reads.
PYROCAM_VECTOR_CLONES
bool coordinates(const float* __restrict a, const float* __restrict b, const float* __restrict r,
                 const float* __restrict others_read, std::size_t m, Grid g,
                 float* __restrict status, float* __restrict fx, float* __restrict fy) {
  for (std::size_t k = 0; k < m; ++k) {
    const float av = a[k], bv = b[k], rv = r[k];
    const float scale = g.inv_h / rv;
    const float x = av * scale - g.offset_x, y = bv * scale - g.offset_y;
    const bool inside = x >= 0.f && x < g.cells_x && y >= 0.f && y < g.cells_y;
    const float place = inside ? kInTable : kOffTable;
    const float unsaturated = av < kInf && bv < kInf && rv < kInf ? place : NAN;
    status[k] = av >= g.dim && bv >= g.dim && rv >= g.dim ? unsaturated : NAN;
    fx[k] = inside ? x : 0.f;
    fy[k] = inside ? y : 0.f;
  }
  if (others_read)
    for (std::size_t k = 0; k < m; ++k) status[k] = others_read[k] != 0.f ? status[k] : NAN;
  std::int32_t reads = 0;
  for (std::size_t k = 0; k < m; ++k) reads |= status[k] == status[k] ? 1 : 0;
  return reads != 0;
}

// Block and cell of each pixel and its position in the cell.
PYROCAM_VECTOR_CLONES
void cells(const float* __restrict fx, const float* __restrict fy, std::size_t m, int shift,
           std::int32_t blocks_x, std::int32_t* __restrict block, std::int32_t* __restrict cell,
           float* __restrict wx, float* __restrict wy) {
  const std::int32_t mask = (1 << shift) - 1;
  for (std::size_t k = 0; k < m; ++k) {
    const auto ix = static_cast<std::int32_t>(fx[k]), iy = static_cast<std::int32_t>(fy[k]);
    block[k] = (iy >> shift) * blocks_x + (ix >> shift);
    cell[k] = ((iy & mask) << shift) + (ix & mask);
    wx[k] = fx[k] - static_cast<float>(ix);
    wy[k] = fy[k] - static_cast<float>(iy);
  }
}

// Bilinear interpolation from each pixel's four cell corners (NaN where the status is not
// kInTable), then `special` = 1 for the pixels the network answers: off the table, or near or
// beyond a range end. Returns whether there are any.
PYROCAM_VECTOR_CLONES
bool interpolate(const float* __restrict corners, const float* __restrict wx,
                 const float* __restrict wy, const float* __restrict status, std::size_t m,
                 MlpOutputTransform space, float lowest, float highest, float* __restrict out,
                 float* __restrict special) {
  for (std::size_t k = 0; k < m; ++k) {
    const float* c = corners + 4 * k;
    const float below = c[0] + wx[k] * (c[1] - c[0]);
    const float above = c[2] + wx[k] * (c[3] - c[2]);
    const float v = below + wy[k] * (above - below);
    out[k] = status[k] == kInTable ? v : NAN;
  }
  // Back from the network's output space to degC (a value <= 0 of 1/T leaves the range).
  constexpr float kZeroCelsiusF = static_cast<float>(kZeroCelsius);
  if (space == MlpOutputTransform::kInverseKelvin) {
    for (std::size_t k = 0; k < m; ++k) out[k] = 1.f / out[k] - kZeroCelsiusF;
  } else if (space == MlpOutputTransform::kLogKelvin) {
    for (std::size_t k = 0; k < m; ++k) out[k] = portable::exp(out[k]) - kZeroCelsiusF;
  }
  // Selects in a separate loop, which the compiler vectorises.
  for (std::size_t k = 0; k < m; ++k) {
    const float t = out[k], st = status[k];
    const float outside_range = t >= lowest && t <= highest ? 0.f : 1.f;
    const float off_table = st == kOffTable ? 1.f : outside_range;
    special[k] = st == kInTable || st == kOffTable ? off_table : 0.f;
  }
  std::int32_t any = 0;
  for (std::size_t k = 0; k < m; ++k) any |= static_cast<std::int32_t>(special[k]);
  return any != 0;
}

}  // namespace lut

// The network tabulated over the colour camera's two ratios x = (s_n0 / ref, s_n1 / ref)
// themselves, on a uniform grid. A ReLU network is piecewise affine in its inputs (log ratios,
// when it takes their logarithms, which are close to affine over a cell) and a grid cell is a
// rectangle in x, so bilinear interpolation of the cell's corners, in the space of the network's
// output unit, is exact or nearly so wherever one linear piece covers the cell and off only by
// the cell's share of a kink elsewhere. The spacing follows the network's steepest slope along
// the locus (kCellChangeC per cell there); off the locus the network can be steeper, which is
// why the change per cell is well under the 0.5 degC tolerance's ten-fold; the unit tests
// measure the agreement on noisy pixels.
//
// Ratios do not follow the temperature monotonically (R/G of a camera behind a visible band-pass
// rises, then falls), so no coordinate along the locus is used: the grid covers the box of the
// locus widened by a factor e^kMarginLn in each ratio, which holds noisy pixels down to the dim
// threshold and most mixed-temperature pixels at edges. It is filled in blocks of kBlockCells^2
// cells the first time a pixel needs one, so a scene pays only for the ratios it shows; at most
// kMaxBlocks are filled (the band around the locus that noisy pixels of every temperature reach
// takes about a quarter of them). Pixels outside the box or in a block beyond that budget, and
// estimates within kGuardC of the model's range ends, go to the network itself: the no-reading
// decisions are the network's.
class LutEstimator : public TemperatureEstimator {
 public:
  static constexpr int kBlockShift = 4, kBlockCells = 1 << kBlockShift;
  static constexpr int kBlockNodes = kBlockCells + 1;  // per side; edges stored in both blocks
  static constexpr double kMarginLn = 1.0;
  static constexpr double kCellChangeC = 4.0;
  static constexpr double kGuardC = 2.0;
  static constexpr std::size_t kMaxCells = std::size_t{1} << 26;  // in the box
  static constexpr std::size_t kMaxBlocks = 8192;                 // filled: 32 MB

  explicit LutEstimator(const ThermalModel& m) : TemperatureEstimator(m), mlp_(m) {
    const Normalisation& n = m.profile().normalisation;
    if (n.numerators.size() != 2)
      throw InputError(
          "method lut needs a model with exactly two ratios (colour camera); this "
          "model has " +
          std::to_string(n.numerators.size()));
    num0_ = n.numerators[0];
    num1_ = n.numerators[1];
    ref_ = n.reference;
    const Locus locus = make_locus(m.camera, m.min_temperature_c, m.max_temperature_c, 1.0);
    // Steepest slope of the network along the locus, degC per unit ratio (L1 over both).
    double slope = 0;
    for (Eigen::Index i = 0; i < locus.size(); i += 5) {
      const double x[2] = {locus.ratios(i, 0), locus.ratios(i, 1)};
      double g[2];
      m.mlp.predict_with_gradient(x, g);
      slope = std::max(slope, std::abs(g[0]) + std::abs(g[1]));
    }
    const double widen = portable::exp(kMarginLn);
    const double x_lo = locus.ratios.col(0).minCoeff() / widen;
    const double x_hi = locus.ratios.col(0).maxCoeff() * widen;
    const double y_lo = locus.ratios.col(1).minCoeff() / widen;
    const double y_hi = locus.ratios.col(1).maxCoeff() * widen;
    if (!(x_lo > 0) || !(y_lo > 0) || !std::isfinite(x_hi) || !std::isfinite(y_hi) ||
        !(slope > 0) || !std::isfinite(slope))
      throw InputError("method lut: the model's locus or network is degenerate");
    h_ = kCellChangeC / slope;
    // A coarser grid rather than an unbounded one for extreme models.
    const double area_cells = (x_hi - x_lo) * (y_hi - y_lo) / (h_ * h_);
    if (area_cells > static_cast<double>(kMaxCells))
      h_ *= std::sqrt(area_cells / static_cast<double>(kMaxCells));
    x0_ = x_lo;
    y0_ = y_lo;
    blocks_x_ = static_cast<int>(std::ceil((x_hi - x_lo) / h_ / kBlockCells));
    blocks_y_ = static_cast<int>(std::ceil((y_hi - y_lo) / h_ / kBlockCells));
    cells_x_ = static_cast<float>(blocks_x_ * kBlockCells);
    cells_y_ = static_cast<float>(blocks_y_ * kBlockCells);
    inv_h_ = static_cast<float>(1 / h_);
    offset_x_ = static_cast<float>(x0_ / h_);
    offset_y_ = static_cast<float>(y0_ / h_);
    inv_ref_count_ = 1.0f / static_cast<float>(ref_.size());
    lowest_ = static_cast<float>(m.min_temperature_c + kGuardC);
    highest_ = static_cast<float>(m.max_temperature_c - kGuardC);
    const auto slots = static_cast<std::size_t>(blocks_x_) * static_cast<std::size_t>(blocks_y_);
    blocks_.reset(new std::atomic<float*>[slots]);
    for (std::size_t i = 0; i < slots; ++i) blocks_[i].store(nullptr, std::memory_order_relaxed);
  }

  ~LutEstimator() override {
    const auto slots = static_cast<std::size_t>(blocks_x_) * static_cast<std::size_t>(blocks_y_);
    for (std::size_t i = 0; i < slots; ++i) delete[] blocks_[i].load(std::memory_order_relaxed);
  }
  LutEstimator(const LutEstimator&) = delete;
  LutEstimator& operator=(const LutEstimator&) = delete;

  double temperature_c(const double* s) const override {
    if (!all_bands_valid(s)) return NAN;
    float f[kMaxBands];
    const float* planes[kMaxBands];
    for (int b = 0; b < bands_; ++b) {
      f[b] = static_cast<float>(s[b]);
      planes[b] = &f[b];
    }
    float out;
    estimate(planes, 1, &out);
    return out;
  }

  // In chunks of pixels, in passes: the arithmetic of every pixel (branch-free, vectorised),
  // the table reads, the interpolation (vectorised), then the few pixels the network answers.
  // A chunk without a reading (background) stops after the first pass.
  void estimate(const float* const* planes, std::size_t n, float* out) const override {
    constexpr std::size_t kChunk = 256;
    alignas(64) float status[kChunk], fx[kChunk], fy[kChunk], wx[kChunk], wy[kChunk];
    alignas(64) float special[kChunk], others_read[kChunk];
    alignas(64) float corners[4 * kChunk];  // per pixel: its cell's four corners
    alignas(64) std::int32_t block[kChunk], cell[kChunk];
    const lut::Grid grid{dim_f(), inv_h_, offset_x_, offset_y_, cells_x_, cells_y_};
    const bool three_bands = bands_ == 3 && ref_.size() == 1;
    for (std::size_t start = 0; start < n; start += kChunk) {
      const std::size_t m = std::min(kChunk, n - start);
      float* __restrict o = out + start;
      const float* reference = planes[ref_[0]] + start;
      if (!three_bands) {
        // Every band must read; the reference is the mean of its bands.
        float* mean = wx;  // scratch until the cells pass
        for (std::size_t k = 0; k < m; ++k) {
          float s[kMaxBands];
          bool read = true;
          for (int band = 0; band < bands_; ++band) {
            s[band] = planes[band][start + k];
            read &= s[band] >= grid.dim && s[band] < lut::kInf;
          }
          mean[k] = this->reference(s);
          others_read[k] = read ? 1.f : 0.f;
        }
        reference = mean;
      }
      if (!lut::coordinates(planes[num0_] + start, planes[num1_] + start, reference,
                            three_bands ? nullptr : others_read, m, grid, status, fx, fy)) {
        std::fill(o, o + m, NAN);
        continue;
      }
      lut::cells(fx, fy, m, kBlockShift, blocks_x_, block, cell, wx, wy);
      for (std::size_t k = 0; k < m; ++k) {
        float* c = corners + 4 * k;
        if (status[k] != lut::kInTable) {
          c[0] = c[1] = c[2] = c[3] = 0;
          continue;
        }
        const float* blk =
            blocks_[static_cast<std::size_t>(block[k])].load(std::memory_order_acquire);
        if (!blk) blk = build_block(block[k] % blocks_x_, block[k] / blocks_x_);
        if (!blk) {  // over the memory budget
          status[k] = lut::kOffTable;
          c[0] = c[1] = c[2] = c[3] = 0;
          continue;
        }
        std::memcpy(c, blk + 4 * cell[k], 4 * sizeof(float));
      }
      if (!lut::interpolate(corners, wx, wy, status, m, space_, lowest_, highest_, o, special))
        continue;
      for (std::size_t k = 0; k < m; ++k) {
        if (special[k] == 0.f) continue;
        const float t = o[k];
        // Well beyond a range end there is no reading; near one, or off the table, the
        // network decides.
        const bool far_out =
            status[k] == lut::kInTable && (t < lowest_ - 2 * static_cast<float>(kGuardC) ||
                                           t > highest_ + 2 * static_cast<float>(kGuardC));
        o[k] = far_out ? NAN : static_cast<float>(network(planes, start + k));
      }
    }
  }

  std::size_t memory_bytes() const override {
    return built_.load(std::memory_order_relaxed) * kBlockCells * kBlockCells * 4 * sizeof(float) +
           static_cast<std::size_t>(blocks_x_) * static_cast<std::size_t>(blocks_y_) *
               sizeof(std::atomic<float*>);
  }

 private:
  float dim_f() const { return static_cast<float>(dim_dn_); }

  float reference(const float* s) const {
    if (ref_.size() == 1) return s[ref_[0]];
    float sum = 0;
    for (int b : ref_) sum += s[b];
    return sum * inv_ref_count_;
  }

  double network(const float* const* planes, std::size_t i) const {
    double s[kMaxBands];
    for (int b = 0; b < bands_; ++b) s[b] = planes[b][i];
    return mlp_.temperature_c(s);
  }

  // Fills a block with the network at its nodes and publishes it; two threads that need the same
  // block at once both compute it (the same values) and one copy is kept. Null once kMaxBlocks
  // are filled.
  const float* build_block(int bx, int by) const {
    if (built_.load(std::memory_order_relaxed) >= kMaxBlocks) return nullptr;
    Eigen::MatrixXd x(kBlockNodes * kBlockNodes, 2);
    for (int j = 0; j < kBlockNodes; ++j)
      for (int i = 0; i < kBlockNodes; ++i) {
        x(j * kBlockNodes + i, 0) = x0_ + (bx * kBlockCells + i) * h_;
        x(j * kBlockNodes + i, 1) = y0_ + (by * kBlockCells + j) * h_;
      }
    const Eigen::VectorXd t = to_output_space(model_.mlp.predict(x));
    // Cell after cell, each with its four corners (one 16-byte read per pixel).
    std::unique_ptr<float[]> values(new float[4 * kBlockCells * kBlockCells]);
    for (int j = 0; j < kBlockCells; ++j)
      for (int i = 0; i < kBlockCells; ++i) {
        float* c = &values[static_cast<std::size_t>(4 * (j * kBlockCells + i))];
        c[0] = static_cast<float>(t[j * kBlockNodes + i]);
        c[1] = static_cast<float>(t[j * kBlockNodes + i + 1]);
        c[2] = static_cast<float>(t[(j + 1) * kBlockNodes + i]);
        c[3] = static_cast<float>(t[(j + 1) * kBlockNodes + i + 1]);
      }
    std::atomic<float*>& slot = blocks_[static_cast<std::size_t>(by * blocks_x_ + bx)];
    float* expected = nullptr;
    if (slot.compare_exchange_strong(expected, values.get(), std::memory_order_acq_rel)) {
      built_.fetch_add(1, std::memory_order_relaxed);
      return values.release();
    }
    return expected;  // another thread was first
  }

  // The table holds the network's answer in the space of its output unit (1/T for an
  // inverse-kelvin output): there the network is piecewise affine in its (log) inputs and close
  // to affine in the ratios themselves; degC would curve steeply at the hot end.
  Eigen::VectorXd to_output_space(const Eigen::VectorXd& t_c) const {
    switch (space_) {
      case MlpOutputTransform::kInverseKelvin:
        return (t_c.array() + kZeroCelsius).inverse().matrix();
      case MlpOutputTransform::kLogKelvin:
        return (t_c.array() + kZeroCelsius)
            .unaryExpr([](double v) { return portable::log(v); })
            .matrix();
      case MlpOutputTransform::kNone:
        break;
    }
    return t_c;
  }

  MlpEstimator mlp_;
  MlpOutputTransform space_ = model_.mlp.output_transform();
  int num0_ = 0, num1_ = 1;
  std::vector<int> ref_;
  double x0_ = 0, y0_ = 0, h_ = 1;
  int blocks_x_ = 0, blocks_y_ = 0;
  float cells_x_ = 0, cells_y_ = 0, inv_h_ = 1, offset_x_ = 0, offset_y_ = 0;
  float inv_ref_count_ = 1, lowest_ = 0, highest_ = 0;
  std::unique_ptr<std::atomic<float*>[]> blocks_;
  mutable std::atomic<std::size_t> built_{0};
};

}  // namespace

Method parse_method(const std::string& name) {
  if (name == "mlp") return Method::kMlp;
  if (name == "lut") return Method::kLut;
  if (name == "likelihood") return Method::kLikelihood;
  throw InputError("unknown method '" + name + "' (use mlp, lut or likelihood)");
}

std::string method_name(Method m) {
  switch (m) {
    case Method::kMlp:
      return "mlp";
    case Method::kLut:
      return "lut";
    case Method::kLikelihood:
      return "likelihood";
  }
  return "?";
}

TemperatureEstimator::TemperatureEstimator(const ThermalModel& model)
    : model_(model),
      bands_(model.profile().band_count()),
      dim_dn_(model.profile().thresholds.inference_dim_dn),
      min_bands_(bands_) {
  if (bands_ > kMaxBands) throw InputError("at most 64 bands are supported");
}

bool TemperatureEstimator::all_bands_valid(const double* s) const {
  for (int b = 0; b < bands_; ++b)
    if (!std::isfinite(s[b]) || s[b] < dim_dn_) return false;
  return true;
}

double TemperatureEstimator::in_range(double t_c) const {
  return t_c >= model_.min_temperature_c && t_c <= model_.max_temperature_c ? t_c : NAN;
}

void TemperatureEstimator::estimate(const float* const* planes, std::size_t n, float* out) const {
  double s[kMaxBands];
  for (std::size_t i = 0; i < n; ++i) {
    for (int b = 0; b < bands_; ++b) s[b] = planes[b][i];
    out[i] = static_cast<float>(temperature_c(s));
  }
}

std::unique_ptr<TemperatureEstimator> make_estimator(const ThermalModel& model, Method method) {
  switch (method) {
    case Method::kMlp:
      return std::make_unique<MlpEstimator>(model);
    case Method::kLikelihood:
      return std::make_unique<LikelihoodEstimator>(model);
    case Method::kLut:
      return std::make_unique<LutEstimator>(model);
  }
  throw InputError("unknown estimator method");
}

std::unique_ptr<TemperatureEstimator> make_exhaustive_likelihood_estimator(
    const ThermalModel& model) {
  return std::make_unique<ExhaustiveLikelihoodEstimator>(model);
}

SignalNoise signal_noise(const CameraProfile& p, int band) {
  const double k = p.band_gain[band] * p.noise.system_gain_dn_per_e;
  const double read = k * p.noise.read_noise_e;
  return {k, 2 * (read * read + 1.0 / 12)};
}

double signal_variance_dn2(const CameraProfile& p, int band, double signal_dn, int frames) {
  const SignalNoise n = signal_noise(p, band);
  return (n.shot_gain * std::max(signal_dn, 0.0) + n.floor_dn2) / std::max(frames, 1);
}

double expanded_uncertainty_c(const TemperatureEstimator& est, const double* signals, double t_c,
                              int frames) {
  if (!std::isfinite(t_c)) return NAN;
  const ThermalModel& m = est.model();
  const int bands = m.profile().band_count();
  double s[kMaxBands];
  for (int b = 0; b < bands; ++b) s[b] = signals[b];
  double var = 0;
  for (int b = 0; b < bands; ++b) {
    if (!std::isfinite(s[b])) continue;
    const double keep = s[b];
    s[b] = keep + 1;
    const double tp = est.temperature_c(s);
    s[b] = keep - 1;
    const double tm = est.temperature_c(s);
    s[b] = keep;
    double dt_ds;
    if (std::isfinite(tp) && std::isfinite(tm))
      dt_ds = (tp - tm) / 2;
    else if (std::isfinite(tp))
      dt_ds = tp - t_c;
    else if (std::isfinite(tm))
      dt_ds = t_c - tm;
    else
      continue;
    var += dt_ds * dt_ds * signal_variance_dn2(m.profile(), b, keep, frames);
  }
  const double sys = m.uncertainty.systematic_u_c(t_c);
  return m.uncertainty.coverage_factor * std::sqrt(var + sys * sys);
}

}  // namespace pyrocam
