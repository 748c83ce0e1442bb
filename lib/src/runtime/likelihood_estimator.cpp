// The likelihood fit of temperature and scale to the band signals (Method::kLikelihood): the fast
// fit that make_estimator gives and the exhaustive scan it is tested against, with their
// per-pixel kernels (compiled for AVX2 too).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "runtime/estimator_kinds.h"

namespace pyrocam {
namespace {

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

  explicit LikelihoodFit(std::shared_ptr<const ThermalModel> model)
      : TemperatureEstimator(std::move(model)),
        locus_(
            make_locus(model_->camera, model_->min_temperature_c, model_->max_temperature_c, 1.0)),
        rates_(static_cast<std::size_t>(locus_.size() * bands_)),
        squares_(rates_.size()) {
    for (Eigen::Index i = 0; i < locus_.size(); ++i)
      for (int b = 0; b < bands_; ++b) {
        const double m = locus_.rates(i, b);
        rates_[static_cast<std::size_t>(i * bands_ + b)] = m;
        squares_[static_cast<std::size_t>(i * bands_ + b)] = m * m;
      }
    for (int b = 0; b < bands_; ++b) {
      const SignalNoise n = signal_noise(model_->profile(), b);
      shot_gain_[b] = n.shot_gain;
      noise_floor_[b] = n.floor_dn2;
    }
    // A ratio that turns over (rises, then falls) fits two temperatures: only pairs whose ratio
    // keeps one direction over the whole range read a pixel alone.
    monotonic_.assign(static_cast<std::size_t>(bands_ * bands_), 0);
    for (int i = 0; i < bands_; ++i)
      for (int j = i + 1; j < bands_; ++j) {
        int rising = 0, falling = 0;
        bool positive = true;
        double previous = NAN;
        for (Eigen::Index k = 0; k < locus_.size() && positive; ++k) {
          const double a = locus_.rates(k, i), b = locus_.rates(k, j);
          positive = a > 0 && b > 0;
          const double r = a / b;
          if (k > 0) rising += r > previous, falling += r < previous;
          previous = r;
        }
        const bool one_way = positive && (rising == 0 || falling == 0);
        monotonic_[static_cast<std::size_t>(i * bands_ + j)] = one_way;
        monotonic_[static_cast<std::size_t>(j * bands_ + i)] = one_way;
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
  bool can_read_partial() const override {
    if (partial_ == PartialBands::kOff || bands_ < 3) return false;
    return partial_ == PartialBands::kAny ||
           std::any_of(monotonic_.begin(), monotonic_.end(), [](std::uint8_t m) { return m != 0; });
  }

  // Whether the bands that read are enough: all of them, or (set_partial_bands) at least two,
  // with kSafe among them a pair whose ratio is monotonic over the model's range.
  bool enough_bands(int reading, const Weighted& px) const {
    if (reading == bands_) return true;
    if (reading < min_bands_) return false;
    if (partial_ != PartialBands::kSafe) return true;
    for (int i = 0; i < bands_; ++i) {
      if (px.w[i] == 0.0) continue;
      for (int j = i + 1; j < bands_; ++j)
        if (px.w[j] != 0.0 && monotonic_[static_cast<std::size_t>(i * bands_ + j)]) return true;
    }
    return false;
  }

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
  std::vector<std::uint8_t> monotonic_;  // bands x bands: ratio monotonic over the locus
};

// The definition: every coarse sample and every 1 degC sample of each refinement window.
class ExhaustiveLikelihoodEstimator : public LikelihoodFit {
 public:
  using LikelihoodFit::LikelihoodFit;

  double temperature_c(const double* s) const override {
    Weighted px;
    if (!enough_bands(weigh(s, px), px)) return NAN;
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

  explicit LikelihoodEstimator(std::shared_ptr<const ThermalModel> model)
      : LikelihoodFit(std::move(model)) {
    const ThermalModel& m = *model_;
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
    if (!enough_bands(weigh(s, px), px)) return NAN;
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

}  // namespace

std::unique_ptr<TemperatureEstimator> make_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model) {
  return std::make_unique<LikelihoodEstimator>(std::move(model));
}

std::unique_ptr<TemperatureEstimator> make_exhaustive_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model) {
  return std::make_unique<ExhaustiveLikelihoodEstimator>(std::move(model));
}

}  // namespace pyrocam
