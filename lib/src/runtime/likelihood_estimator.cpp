// The likelihood fit of temperature and scale to the band signals (Method::kLikelihood): the fast
// fit that make_estimator gives (its shared part in likelihood_fit.h, the exhaustive scan it is
// tested against in likelihood_exhaustive.cpp, the per-pixel kernels in likelihood_kernels.h, the
// scan of pixels that few bands read in likelihood_direct.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "runtime/estimator_kinds.h"
#include "runtime/likelihood_bounds.h"
#include "runtime/likelihood_descent.h"
#include "runtime/likelihood_direct.h"
#include "runtime/likelihood_factors.h"
#include "runtime/likelihood_fit.h"
#include "runtime/likelihood_kernels.h"

namespace pyrocam {
namespace {

// The same fit, fast. chi2(T) = sss - ssm(T)^2 / smm(T) does not change when m(T) is scaled,
// so the locus rows are normalised, and the normalised rates (and their squares) over the
// samples form matrices of very low rank (smooth spectra: 9 to 11 of 25 columns leave rows off by
// 1e-8 to 1e-10). With such factors, ssm and smm at a sample cost one multiply-add per rank
// instead of one per band. The factors' row errors (measured when they are made) and the
// rounding of the sums bound ssm and smm, hence chi2, at every sample (FitBounds): the scan
// decides by these bounds where they tell, and by the exact chi2 (double precision, as the
// exhaustive scan computes it) where they overlap:
//  - coarse scan in single precision: a sample whose lower bound is above a neighbour's upper
//    bound is no local minimum; the few others are tested with double precision bounds from
//    all factors, then exactly;
//  - refinement window in double precision from the window's own basis of the factors' rows
//    (window_factors: 5 directions where all factors take 11 or 12): only samples whose lower
//    bound is not above the least upper bound can be the best, and only they are evaluated
//    exactly.
// So the answer and the no-reading decisions are those of the exhaustive scan by construction
// (the unit tests compare both on noisy pixels, with saturated, dim and NaN bands). Pixels whose
// bands all read take the descent instead where it is usable (likelihood_descent.h), and with
// partial readings those with a few bands dropped, as many as the descent read such pixels of
// the model's own as the scan: the same answers by comparison, when the fit is made and in the
// tests, not by construction. (A pixel with two saturated bands took the scan at about 3 times
// the walk's cost: at the exposure a camera's brightest band is set to, many do.)
class LikelihoodEstimator : public LikelihoodFit {
 public:
  // Row error left by the factors (rows have unit length): coarse (single precision sums are
  // off by about 1e-6 anyway: a closer fit only costs multiply-adds), window.
  static constexpr double kCoarseRankTolerance = 1e-6, kWindowRankTolerance = 1e-10;
  static constexpr Eigen::Index kMaxCoarse = 504;  // coarse samples: a 10 000 degC range
  // Room for a refinement window's samples and the reads of approximate_sums' last block.
  static constexpr Eigen::Index kWindowRoom =
      (2 * kCoarse + 1 + kWindowBlock - 1) / kWindowBlock * kWindowBlock;
  static_assert(kMaxCoarse <= kMaxMinimumCandidates);

  explicit LikelihoodEstimator(std::shared_ptr<const ThermalModel> model)
      : LikelihoodFit(std::move(model)),
        descent_(locus_.rates, rates_.data(), squares_.data(), width_, monotonic_.data()),
        direct_(rates_.data(), squares_.data(), width_, bands_, locus_.size(), kCoarse,
                monotonic_.data()) {
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
    const FactorLayout layout{stride_,     coarse_count_,        coarse_stride_,      kCoarse,
                              kWindowRoom, kCoarseRankTolerance, kWindowRankTolerance};
    factor_locus(unit, layout, across_, rank_, coarse_rank_, along_, coarse_along_, residual_);
    factor_locus(squares, layout, across2_, rank2_, coarse_rank2_, along2_, coarse_along2_,
                 residual2_);
    factor_windows(along_, rank_, n, layout, window_rank_, window_basis_, window_along_,
                   window_residual_);
    factor_windows(along2_, rank2_, n, layout, window_rank2_, window_basis2_, window_along2_,
                   window_residual2_);
    // All factors of each coarse sample side by side (read sample by sample).
    pad_ = (rank_ + 3) / 4 * 4;
    point_width_ = pad_ + (rank2_ + 3) / 4 * 4;
    points_.assign(static_cast<std::size_t>(coarse_count_ * point_width_), 0.0);
    for (Eigen::Index k = 0; k < coarse_count_; ++k) {
      double* at = &points_[static_cast<std::size_t>(k * point_width_)];
      for (int r = 0; r < rank_; ++r)
        at[r] = along_[static_cast<std::size_t>(r * stride_ + k * kCoarse)];
      for (int r = 0; r < rank2_; ++r)
        at[pad_ + r] = along2_[static_cast<std::size_t>(r * stride_ + k * kCoarse)];
    }
    // The descent where it gives the scan's answers on this model's own noisy pixels; for
    // pixels with bands dropped too where it gives them with the dimmest or brightest bands of
    // every other one of those pixels dropped (below the dim threshold, saturated).
    descends_ = descent_.usable();
    const std::vector<double> check =
        LocusDescent::check_pixels(locus_.rates, shot_gain_, noise_floor_, weigh_dim_dn_,
                                   0.9 * m.profile().thresholds.inference_saturation_dn, 7);
    // Whether the walk reads s as the scan (true where it does not settle: the scan reads it);
    // with `complete`, only pixels whose bands all read are tested.
    const auto agrees = [&](const double* s, bool complete) {
      Weighted px;
      const int reading = weigh(s, px);
      double a;
      if (reading < 2 || (complete && reading < bands_) ||
          (reading < kMinSaturatedWalkBands && saturated_bands(s) > 0) || !descended(s, px, a))
        return true;
      const double b = scan(px);
      return a == b || (std::isnan(a) && std::isnan(b));
    };
    const auto pixel_bands = static_cast<std::size_t>(bands_);
    for (std::size_t i = 0; descends_ && i < check.size(); i += pixel_bands)
      descends_ = agrees(&check[i], true);
    // Pixels with bands dropped: the dimmest ones (below the dim threshold) of every other check
    // pixel, then the brightest ones (saturated), more at each level; each family walks up to
    // the last level at which every such pixel agreed, and both together only if a mixture of
    // the two agreed too.
    if (!descends_ || bands_ < 8) return;
    const std::size_t checked = check.size() / pixel_bands;
    std::vector<int> order;  // per checked pixel, its bands from dimmest to brightest
    for (std::size_t i = 0; i < checked; i += 2) {
      const double* px = &check[i * pixel_bands];
      const auto at = static_cast<std::ptrdiff_t>(order.size());
      order.resize(order.size() + pixel_bands);
      std::iota(order.begin() + at, order.end(), 0);
      std::sort(order.begin() + at, order.end(), [&](int x, int y) { return px[x] < px[y]; });
    }
    std::vector<double> dropped(pixel_bands);
    const auto all_agree = [&](int dim, int saturated) {
      for (std::size_t i = 0, k = 0; i < checked; i += 2, k += pixel_bands) {
        std::copy(&check[i * pixel_bands], &check[(i + 1) * pixel_bands], dropped.begin());
        for (int d = 0; d < dim; ++d) dropped[order[k + d]] = 0.0;
        for (int d = 0; d < saturated; ++d)
          dropped[order[k + pixel_bands - 1 - d]] = std::numeric_limits<double>::infinity();
        if (!agrees(dropped.data(), false)) return false;
      }
      return true;
    };
    for (const int dim : {2, 6, 12, 20})
      if (dim <= bands_ - 3 && all_agree(dim, 0))
        max_dim_dropped_ = dim;
      else
        break;
    for (const int saturated : {1, 3, 6, 9, 12, 15, 18, 22})
      if (saturated <= bands_ - 3 && all_agree(0, saturated))
        max_saturated_ = saturated;
      else
        break;
    mixed_dim_ = std::min(6, max_dim_dropped_);
    mixed_saturated_ = std::min(3, max_saturated_);
    if (mixed_dim_ == 0 || mixed_saturated_ == 0 || !all_agree(mixed_dim_, mixed_saturated_))
      mixed_dim_ = mixed_saturated_ = 0;
  }

  bool descends() const { return descends_; }
  bool partial_descends() const { return max_dim_dropped_ > 0 || max_saturated_ > 0; }

  double temperature_c(const double* s) const override {
    Weighted px;
    const int reading = weigh(s, px);
    if (!enough_bands(reading, px)) return NAN;
    double t;
    if (walks(px, reading, px.complete ? 0 : saturated_bands(s)) && descended(s, px, t)) return t;
    return scan(px);
  }

 private:
  // Pixels that walk do so side by side, kWalkBatch at a time: each walk is a chain of
  // dependent steps, and the processor overlaps the steps of different pixels (one by one, the
  // fit spent most of its time waiting on each step's sums). The same steps, the same answers.
  static constexpr std::size_t kWalkBatch = 16;
  // A pixel with saturated bands and fewer weighed ones than this is always scanned: with few
  // bands chi2 can have two equal minima (with two, it is 0 wherever the locus has their ratio),
  // and the walk finds one of them where the scan calls the pixel ambiguous. Such check pixels
  // (2, 5 and 7 bands weighed) kept the walk from pixels with 12 or more saturated bands, which
  // the scan then read at a sixth of the walk's rate (a 1500 degC 5x5 plate exposed twice as
  // long as for 170 DN: 15 of 25 bands saturated). At 8 one check pixel of the test model (12
  // saturated, 8 weighed: the walk 1268.7 degC, the scan no reading) did it again: that plate
  // read at 39 frames/s library level (51 CPU ms a frame, every pixel scanned), at 9 at 151
  // (13.2 ms; the walk then checked up to 22 saturated bands), the same readings.
  static constexpr int kMinSaturatedWalkBands = 9;
  // A pixel with at most this many bands weighed is scanned by direct_scan: alternated frame by
  // frame on the 5x5 benchmark's plate exposed three times as long (7 of 25 bands weighed, the
  // others saturated), 2.3 times faster than the scan through the factors; with all 25 bands
  // weighed (the same plate at 0.15 times the exposure, faint bands) 2.3 times slower. Only for
  // cameras with more bands: the colour camera's three are few factors too, and its 36 % plate
  // read 12 % slower by direct_scan.
  static constexpr int kDirectScanBands = 12;
  struct Walk {
    Weighted px;
    bool saturated;  // a band is
    Eigen::Index at;
    double chi2[3];
    std::size_t k;  // the pixel's place in the chunk
  };

  void read_chunk(const float* const* planes, std::size_t start, std::size_t m,
                  const std::int32_t* reading, int needed, float* out) const override {
    Walk batch[kWalkBatch];
    std::uint8_t walking[kWalkBatch];
    // A pixel's signals as doubles, where its walk needs them (not every band reads).
    alignas(32) double s[kWalkBatch][kMaxBands];
    for (std::size_t k = 0; k < m;) {
      std::size_t used = 0, count = 0;
      // The batch's slot `slot`, weighed, is pixel k: no reading, the scan's, or a walk.
      const auto take = [&](std::size_t slot, std::size_t k, int bands_read, int saturated_count,
                            double fraction) {
        Walk& w = batch[slot];
        if (!enough_bands(bands_read, w.px)) {
          out[k] = NAN;
          return;
        }
        const int saturated = w.px.complete ? 0 : saturated_count;
        if (!walks(w.px, bands_read, saturated)) {
          out[k] = static_cast<float>(scan(w.px));
          return;
        }
        // Where every band reads, first_guess is the fraction's guess (dim bands included).
        w.at = bands_read == bands_ ? descent_.guess(fraction) : -1;
        w.saturated = saturated > 0;
        w.k = k;
        walking[count++] = static_cast<std::uint8_t>(slot);
      };
      while (k < m && used < kWalkBatch) {
        if (reading[k] < needed) {
          out[k] = NAN;
          ++k;
          continue;
        }
        if (descends_ && k + 4 <= m && used + 4 <= kWalkBatch && reading[k + 1] >= needed &&
            reading[k + 2] >= needed && reading[k + 3] >= needed) {
          // Four pixels side by side; their signals as doubles (for the first guess) only where a
          // band does not read: where all do, the guess is the fraction's, dim bands included.
          double *w[4], *ws[4], *rows[4];
          bool all_read = true;
          for (std::size_t j = 0; j < 4; ++j) {
            w[j] = batch[used + j].px.w, ws[j] = batch[used + j].px.ws, rows[j] = s[used + j];
            all_read = all_read && reading[k + j] == bands_;
          }
          FourWeighed four;
          weigh_four(planes, bands_, start + k, weigh_dim_dn_, dim_dn_, shot_gain_, noise_floor_,
                     descent_.fast_bands(), w, ws, all_read ? nullptr : rows, four);
          for (std::size_t j = 0; j < 4; ++j) {
            Weighted& px = batch[used + j].px;
            px.sss = four.sss[j];
            px.complete = four.bright[j] == bands_;
            px.faint = four.reading[j] > four.bright[j];
            px.weighed = four.reading[j];
            px.bright = four.bright[j];
            take(used + j, k + j, four.reading[j], four.saturated[j], four.fraction[j]);
          }
          used += 4, k += 4;
          continue;
        }
        copy_signals(planes, start + k, s[used]);
        const int bands_read = weigh(s[used], batch[used].px);
        const bool complete = batch[used].px.complete;
        take(used, k, bands_read, complete ? 0 : saturated_bands(s[used]),
             bands_read == bands_ ? fast_fraction_of(s[used]) : 0.0);
        ++used, ++k;
      }
      // The other guesses side by side.
      const double* signals[kWalkBatch];
      Eigen::Index guesses[kWalkBatch];
      std::size_t guessed = 0;
      for (std::size_t i = 0; i < count; ++i)
        if (batch[walking[i]].at < 0) signals[guessed++] = s[walking[i]];
      descent_.first_guesses(signals, guessed, false, guesses);
      for (std::size_t i = 0, g = 0; i < count; ++i)
        if (batch[walking[i]].at < 0) batch[walking[i]].at = guesses[g++];
      walk(batch, walking, count, out);
    }
  }

  void copy_signals(const float* const* planes, std::size_t at, double* s) const {
    for (int b = 0; b < bands_; ++b) s[b] = planes[b][at];
  }

  double fast_fraction_of(const double* s) const {
    return descends_ ? fast_fraction(s, descent_.fast_bands(), bands_) : 0.0;
  }

  // The walks of `count` pixels (batch[active[i]]), step by step (LocusDescent::descend's
  // loop); where a walk fails or does not settle, the scan reads the pixel.
  void walk(Walk* walks, std::uint8_t* active, std::size_t count, float* out) const {
    for (int step = 0; step < LocusDescent::kMaxSteps && count > 0; ++step) {
      // Four at a time; three left over as four, the last one repeated into a scratch (one
      // pixel's sums wasted against three scalar divisions saved), one or two one by one.
      std::size_t i = 0;
      for (; i + 4 <= count || i + 3 == count; i += 4) {
        alignas(32) double sss[4];
        double scratch[3];
        const double *m[4], *m2[4], *ws[4], *w[4];
        double* chi2[4];
        for (std::size_t j = 0; j < 4; ++j) {
          Walk& at = walks[active[std::min(i + j, count - 1)]];
          descent_.rows(at.at, m[j], m2[j]);
          ws[j] = at.px.ws, w[j] = at.px.w, sss[j] = at.px.sss;
          chi2[j] = i + j < count ? at.chi2 : scratch;
        }
        profiled_chi2_three_four(m, m2, ws, w, width_, sss, chi2);
      }
      for (; i < count; ++i) {
        Walk& w = walks[active[i]];
        descent_.evaluate(w.at, w.px.w, w.px.ws, w.px.sss, w.chi2);
      }
      for (std::size_t i = 0; step == 0 && i < count; ++i) {  // as descend
        Walk& w = walks[active[i]];
        if (w.saturated) w.at = descent_.restart_saturated(w.at, w.px.w, w.px.ws, w.px.sss, w.chi2);
      }
      std::size_t kept = 0;
      for (std::size_t i = 0; i < count; ++i) {
        Walk& w = walks[active[i]];
        const LocusDescent::Step done = descent_.next(w.at, w.chi2);
        if (done == LocusDescent::Step::kMoved && step + 1 < LocusDescent::kMaxSteps) {
          active[kept++] = active[i];
          continue;
        }
        out[w.k] =
            static_cast<float>(done == LocusDescent::Step::kSettled && settled_well(w.px, w.chi2)
                                   ? settled(w.at, w.chi2, w.px)
                                   : scan(w.px));
      }
      count = kept;
    }
  }

  // A pixel's reading once its walk settled at `at` (chi2 there and at its neighbours).
  double settled(Eigen::Index at, const double* chi2, const Weighted& px) const {
    const Minimum best{at, chi2[1], chi2[0], chi2[2]};
    return decide(&best, 1, px);
  }

  // Whether a pixel that has enough bands (px, `reading` of them; `saturated` of them saturated,
  // 0 where px.complete) walks: where the walk was checked for as many bands below the dim
  // threshold (weighed or not) and saturated as it has.
  bool walks(const Weighted& px, int reading, int saturated) const {
    if (!descends_ || px.complete) return descends_;
    if (saturated > 0 && reading < kMinSaturatedWalkBands) return false;
    const int other = bands_ - (px.faint ? px.bright : reading) - saturated;
    return saturated == 0 ? other <= max_dim_dropped_
           : other == 0   ? saturated <= max_saturated_
                          : other <= mixed_dim_ && saturated <= mixed_saturated_;
  }

  // A walk that settled with a band below the dim threshold weighed is kept where it fits as the
  // noise allows (chi2 at most twice the bands and 20 more; about 23 +- 7 on the locus): a band
  // far off the locus (an edge, a spike) can give chi2 a second minimum that the walk does not
  // see (5 of 30000 spliced and distorted spectra in the lib test read otherwise than the scan),
  // and then the scan reads the pixel.
  static bool settled_well(const Weighted& px, const double* chi2) {
    return !px.faint || chi2[1] <= 2.0 * px.weighed + 20;
  }

  int saturated_bands(const double* s) const {
    int n = 0;
    for (int b = 0; b < bands_; ++b) n += s[b] == std::numeric_limits<double>::infinity();
    return n;
  }

  // The descent's reading of a pixel (t; false where the walk does not settle).
  bool descended(const double* s, const Weighted& px, double& t) const {
    Eigen::Index at;
    double c[3];
    if (!descent_.descend(s, px.complete, px.w, px.ws, px.sss, at, c) || !settled_well(px, c))
      return false;
    t = settled(at, c, px);
    return true;
  }

  // The scan of the whole locus, exhaustive by its bounds.
  double scan(const Weighted& px) const {
    if (bands_ > kDirectScanBands && px.weighed <= kDirectScanBands) return direct_scan(px);
    // Projections of w*s and w on the factors.
    alignas(32) double p[kMaxRank], q[kMaxRank];
    alignas(32) float pf[kMaxRank], qf[kMaxRank];
    double squares[2];
    project(px.ws, px.w, bands_, across_.data(), across2_.data(), p, q, pf, qf, squares);
    const double ws_norm = std::sqrt(squares[0]), w_norm = std::sqrt(squares[1]);

    // Coarse scan: bounds of chi2 at every coarse sample, in single precision. Single precision
    // sums of up to kMaxRank terms are off by at most 1.1e-6 of sum |p_r a_r| <= |w s| (the
    // factors' rows are at most unit length), and the bounds' own rounding by about 1e-6 of sss.
    alignas(32) float lower[kMaxCoarse + kCoarseBlock], upper[kMaxCoarse + kCoarseBlock];
    const Eigen::Index nc = coarse_count_;
    bounded_chi2(coarse_along_.data(), coarse_rank_, coarse_along2_.data(), coarse_rank2_,
                 coarse_stride_, nc, pf, qf, static_cast<float>(px.sss),
                 static_cast<float>(ws_norm * (residual_[0] + 2e-6)),
                 static_cast<float>(w_norm * (residual2_[0] + 2e-6)),
                 static_cast<float>(1e-5 * px.sss + 1e-9), lower, upper);
    const FitBounds fine = fit_bounds(px.sss, ws_norm, w_norm, residual_[1], residual2_[1]);
    const FitBounds window = fit_bounds(px.sss, ws_norm, w_norm, residual_[1] + window_residual_,
                                        residual2_[1] + window_residual2_);
    // The exhaustive scan's test c[k] <= c[other]: by bounds from all factors in double
    // precision (each sample's once: a candidate's neighbours are often candidates too),
    // exactly only where they overlap.
    double low[kMaxCoarse], high[kMaxCoarse];
    std::uint8_t known[kMaxCoarse];
    std::memset(known, 0, static_cast<std::size_t>(nc));
    auto bounds = [&](Eigen::Index k) {
      if (!known[k]) coarse_bounds(k, p, q, fine, low[k], high[k]), known[k] = 1;
    };
    auto not_above = [&](Eigen::Index k, Eigen::Index other) {
      bounds(k), bounds(other);
      if (high[k] < low[other]) return true;
      if (low[k] > high[other]) return false;
      return chi2(k * kCoarse, px) <= chi2(other * kCoarse, px);
    };
    // Local minima: a sample surely above a neighbour is none, the few others are tested.
    std::int32_t candidates[kMaxCoarse];
    const int found = minimum_candidates(lower, upper, nc, candidates);
    Minimum refined[kMaxCoarse];
    std::size_t count = 0;
    for (int c = 0; c < found; ++c) {
      const Eigen::Index k = candidates[c];
      if (!((k == 0 || not_above(k, k - 1)) && (k + 1 == nc || not_above(k, k + 1)))) continue;
      refined[count++] = refine(k * kCoarse, px, p, q, window);
    }
    return decide(refined, count, px);
  }

  // The scan of the exhaustive fit itself, each chi2 computed exactly from the weighed bands
  // alone (DirectChi2): every coarse sample, then the window of each coarse local minimum. Only
  // the coarse samples whose windows can come within kAmbiguityChi2 of the least chi2
  // (DirectChi2::coarse_span): the minima outside neither read nor make a reading ambiguous.
  double direct_scan(const Weighted& px, bool whole = false) const {
    const LaneBands lanes = lane_bands(px.w, bands_);
    const Eigen::Index n = locus_.size(), nc = direct_.coarse_count();
    Eigen::Index first = 0, last = nc - 1;
    double upper = 0;
    const bool spanned = !whole && direct_.coarse_span(lanes, px.ws, px.w, px.sss, kAmbiguityChi2,
                                                       first, last, upper);
    if (!spanned) first = 0, last = nc - 1;
    // Their neighbours too, for the local minima's test.
    const Eigen::Index from = std::max<Eigen::Index>(first - 1, 0),
                       to = std::min<Eigen::Index>(last + 1, nc - 1);
    alignas(32) double c[kMaxCoarse + 8];
    direct_.at_coarse(lanes, px.ws, px.w, px.sss, from, to - from + 1, c + from);
    Minimum refined[kMaxCoarse];
    std::size_t count = 0;
    double least = std::numeric_limits<double>::infinity();
    for (Eigen::Index k = first; k <= last; ++k) {
      if (!((k == 0 || c[k] <= c[k - 1]) && (k + 1 == nc || c[k] <= c[k + 1]))) continue;
      const Eigen::Index around = k * kCoarse;
      const Eigen::Index lo = std::max<Eigen::Index>(0, around - kCoarse);
      const Eigen::Index hi = std::min<Eigen::Index>(n - 1, around + kCoarse);
      alignas(32) double v[2 * kCoarse + 8];
      direct_.at_samples(lanes, px.ws, px.w, px.sss, lo, hi - lo + 1, v);
      // As the exhaustive scan: `around` first, then the first sample below it.
      Minimum best{around, v[around - lo], NAN, NAN};
      for (Eigen::Index i = lo; i <= hi; ++i)
        if (v[i - lo] < best.chi2) best = {i, v[i - lo], NAN, NAN};
      if (best.index > lo) best.below = v[best.index - 1 - lo];
      if (best.index < hi) best.above = v[best.index + 1 - lo];
      refined[count++] = best;
      least = std::min(least, best.chi2);
    }
    // The span holds a sample at `upper`, so a minimum at most that: else (not seen) scan all.
    if (spanned && !(least <= upper)) return direct_scan(px, true);
    return decide(refined, count, px);
  }

  // A pixel's error bounds with factors whose rows are off by at most `residual` (unit rows)
  // and `residual2` (their squares), |w s| and |w| being ws_norm and w_norm. The rounding
  // allowances are far above what double precision loses on these sums (about 1e-14 relative).
  static FitBounds fit_bounds(double sss, double ws_norm, double w_norm, double residual,
                              double residual2) {
    FitBounds f;
    f.sss = sss;
    f.ssm_error = ws_norm * (residual + 1e-12);
    f.smm_error = w_norm * (residual2 + 1e-12);
    f.slack = 1e-11 * sss + 1e-12;
    return f;
  }

  // Bounds of chi2 at coarse sample k from all its factors (points_), summed in four lanes.
  void coarse_bounds(Eigen::Index k, const double* p, const double* q, const FitBounds& f,
                     double& lower, double& upper) const {
    const double* at = &points_[static_cast<std::size_t>(k * point_width_)];
    double a[4] = {}, b[4] = {};
    for (Eigen::Index r = 0; r < pad_; r += 4)
      for (int j = 0; j < 4; ++j) a[j] += p[r + j] * at[r + j];
    for (Eigen::Index r = pad_; r < point_width_; r += 4)
      for (int j = 0; j < 4; ++j) b[j] += q[r - pad_ + j] * at[r + j];
    const double ssm = (a[0] + a[1]) + (a[2] + a[3]), smm = (b[0] + b[1]) + (b[2] + b[3]);
    lower = chi2_lower(ssm, 0, smm, 0, f);
    upper = chi2_upper(ssm, smm, f);
  }

  // Room for n samples and the reads of a last, partial block of bounded_chi2.
  static constexpr Eigen::Index padded(Eigen::Index n) {
    return (n + kCoarseBlock - 1) / kCoarseBlock * kCoarseBlock + kCoarseBlock;
  }

  // The exhaustive scan's refinement around `around` with the window factors' provable bounds:
  // only samples whose lower bound is not above an upper bound of the window's least chi2 can be
  // the best one, and only they are evaluated exactly; ties go as in the exhaustive scan (`around`
  // first, then the first sample).
  Minimum refine(Eigen::Index around, const Weighted& px, const double* p, const double* q,
                 const FitBounds& f) const {
    const Eigen::Index n = locus_.size();
    const Eigen::Index lo = std::max<Eigen::Index>(0, around - kCoarse);
    const Eigen::Index hi = std::min<Eigen::Index>(n - 1, around + kCoarse);
    constexpr Eigen::Index kRoom = kWindowRoom;
    // The window's own bases: p and q in them, then the sums at its samples.
    const std::size_t k = static_cast<std::size_t>(around / kCoarse);
    alignas(32) double pw[kMaxWindowRank], qw[kMaxWindowRank];
    to_window_basis(&window_basis_[k * kMaxRank * kMaxWindowRank], rank_, p, pw);
    to_window_basis(&window_basis2_[k * kMaxRank * kMaxWindowRank], rank2_, q, qw);
    alignas(32) double ssm[kRoom], smm[kRoom];
    const Eigen::Index count = hi - lo + 1;
    approximate_sums(&window_along_[k * kRoom * window_rank_], window_rank_,
                     &window_along2_[k * kRoom * window_rank2_], window_rank2_, kRoom, 0, count, pw,
                     qw, ssm, smm);
    alignas(16) std::uint8_t open[kRoom];
    const int opened =
        window_candidates(ssm, smm, count, f.sss, f.ssm_error, f.smm_error, f.slack, open);
    if (opened == 1) {  // the usual case: the best sample, with its neighbours for decide
      const Eigen::Index at = lo + (std::find(open, open + count, 1) - open);
      if (at == 0 || at == n - 1) return {at, chi2(at, px), NAN, NAN};
      double c[3];
      const std::size_t row = static_cast<std::size_t>((at - 1) * width_);
      profiled_chi2_three(&rates_[row], &squares_[row], px.ws, px.w, width_, px.sss, c);
      return {at, c[1], c[0], c[2]};
    }
    double exact[2 * kCoarse + 1];
    for (Eigen::Index i = 0; i < count; ++i) exact[i] = NAN;
    Minimum best{around, std::numeric_limits<double>::infinity(), NAN, NAN};
    if (open[around - lo]) best.chi2 = exact[around - lo] = chi2(around, px);
    for (Eigen::Index i = lo; i <= hi; ++i) {
      if (i == around || !open[i - lo]) continue;
      exact[i - lo] = chi2(i, px);
      if (exact[i - lo] < best.chi2) best = {i, exact[i - lo], NAN, NAN};
    }
    if (best.index - 1 >= lo) best.below = exact[best.index - 1 - lo];
    if (best.index + 1 <= hi) best.above = exact[best.index + 1 - lo];
    return best;
  }

  int rank_ = 0, rank2_ = 0, coarse_rank_ = 0, coarse_rank2_ = 0;
  int window_rank_ = 0, window_rank2_ = 0;
  std::vector<double> window_basis_, window_basis2_, window_along_, window_along2_;
  double window_residual_ = 0, window_residual2_ = 0;
  Eigen::Index stride_ = 0, coarse_count_ = 0, coarse_stride_ = 0;
  std::vector<double> across_, across2_, along_, along2_;
  std::vector<float> coarse_along_, coarse_along2_;
  double residual_[2] = {}, residual2_[2] = {};  // row errors: coarse factors, all factors
  std::vector<double> points_;  // per coarse sample: its factors, then its squares' (padded)
  Eigen::Index pad_ = 0, point_width_ = 0;
  LocusDescent descent_;
  DirectChi2 direct_;
  bool descends_ = false;
  // With partial readings, a pixel walks with up to max_dim_dropped_ bands dropped that are not
  // saturated (dim or invalid), or up to max_saturated_ saturated ones, or with both kinds up to
  // mixed_dim_ and mixed_saturated_: what the check allowed (on the test model up to 22
  // saturated bands of 25, and 20 dropped dim ones).
  int max_dim_dropped_ = 0, max_saturated_ = 0, mixed_dim_ = 0, mixed_saturated_ = 0;
};

}  // namespace

std::unique_ptr<TemperatureEstimator> make_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model) {
  return std::make_unique<LikelihoodEstimator>(std::move(model));
}

bool likelihood_fit_descends(const TemperatureEstimator& estimator, bool with_dropped_bands) {
  const auto* fit = dynamic_cast<const LikelihoodEstimator*>(&estimator);
  return fit && (with_dropped_bands ? fit->partial_descends() : fit->descends());
}

}  // namespace pyrocam
