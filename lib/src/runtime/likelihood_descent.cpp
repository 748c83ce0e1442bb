// The likelihood fit's short path (see likelihood_descent.h).
#include "runtime/likelihood_descent.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "detail/portable_math.h"
#include "detail/vector_clones.h"
#include "runtime/estimator_kinds.h"
#include "runtime/likelihood_kernels.h"

namespace pyrocam {

namespace {
// Cells of the first guess's table: about a third of a sample each on the 5x5 camera.
constexpr std::size_t kGuesses = 8192;

// The largest finite signal of x (0 if none is above 0) and whether a band is saturated (+INF),
// four bands at a time: a maximum is the same in any order, and one band after band waited on
// each comparison (a saturated 5x5 pixel's guess spent most of its time there).
PYROCAM_VECTOR_CLONES
double brightest_finite(const double* __restrict x, int bands, bool* saturated) {
  typedef std::int64_t Mask __attribute__((vector_size(32)));
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Lanes inf = {kInf, kInf, kInf, kInf}, minus_inf = -inf;
  Lanes most = {0, 0, 0, 0};
  Mask any_saturated = {0, 0, 0, 0};
  int b = 0;
  for (; b + 4 <= bands; b += 4) {
    const Lanes v = *reinterpret_cast<const Lanes*>(x + b);
    const Mask finite = (v < inf) & (v > minus_inf);  // NaN fails both
    most = finite & (v > most) ? v : most;
    any_saturated |= v == inf;
  }
  double brightest = std::max(std::max(most[0], most[1]), std::max(most[2], most[3]));
  bool saturated_band =
      (any_saturated[0] | any_saturated[1] | any_saturated[2] | any_saturated[3]) != 0;
  for (; b < bands; ++b) {
    if (std::isfinite(x[b])) brightest = std::max(brightest, x[b]);
    saturated_band = saturated_band || x[b] == kInf;
  }
  *saturated = saturated_band;
  return brightest;
}
}  // namespace

LocusDescent::LocusDescent(const Eigen::MatrixXd& rates, const double* m, const double* m2,
                           int width, const std::uint8_t* monotonic)
    : m_(m),
      monotonic_(monotonic),
      m2_(m2),
      bands_(static_cast<int>(rates.cols())),
      width_(width),
      samples_(rates.rows()) {
  if (bands_ < 3 || samples_ < 3) return;
  // How fast each band brightens in the middle of the range.
  const Eigen::Index mid = samples_ / 2;
  std::vector<double> slope(static_cast<std::size_t>(bands_));
  for (int b = 0; b < bands_; ++b)
    slope[static_cast<std::size_t>(b)] = portable::log(rates(mid + 1, b) / rates(mid - 1, b));
  std::vector<double> sorted = slope;
  std::nth_element(sorted.begin(), sorted.begin() + bands_ / 2, sorted.end());
  const double median = sorted[static_cast<std::size_t>(bands_ / 2)];
  if (!std::isfinite(median)) return;
  for (Eigen::Index k = 0;; k += kPairStep) {
    const Eigen::Index at = std::min(k, samples_ - 1);
    for (int b = 0; b < bands_; ++b) pair_rows_.push_back(rates(at, b));
    if (at == samples_ - 1) break;
  }
  by_slope_.resize(slope.size());
  std::iota(by_slope_.begin(), by_slope_.end(), 0);
  std::stable_sort(by_slope_.begin(), by_slope_.end(), [&](int x, int y) {
    return slope[static_cast<std::size_t>(x)] > slope[static_cast<std::size_t>(y)];
  });
  // The walk is used where the fraction of the signal in the faster half of the bands rises
  // steadily over the locus (not the colour camera's three bands, whose ratios turn over). Its
  // guess then weighs each band by its slope scaled to 0 .. 1 instead, where that fraction rises
  // steadily too: sum(slope s) / sum(s) is the statistic that shot noise lets tell temperature
  // best (for shot noise the score of a band's share of the signal is its slope less the mean).
  // On the 5x5 camera's 1500 degC plate that guess is within a sample of the walk's end on 3
  // pixels in 4 (the halves': 1 in 5), and 3 walks in 10 settle at their first step (the
  // halves': 1 in 13): 4-16 % less time a frame on the benchmark's scenes.
  std::vector<double> fraction(static_cast<std::size_t>(samples_));
  const auto rises = [&] {
    Eigen::RowVectorXd row(bands_);
    for (Eigen::Index i = 0; i < samples_; ++i) {
      row = rates.row(i);
      const double f = fast_fraction(row.data(), fast_.data(), bands_);
      if (!std::isfinite(f) || (i > 0 && !(f > fraction[static_cast<std::size_t>(i - 1)])))
        return false;
      fraction[static_cast<std::size_t>(i)] = f;
    }
    return true;
  };
  fast_.resize(slope.size());
  for (std::size_t b = 0; b < slope.size(); ++b) fast_[b] = slope[b] > median ? 1 : 0;
  const auto fast_count = std::count(fast_.begin(), fast_.end(), 1.0);
  if (fast_count == 0 || fast_count == bands_ || !rises()) return;
  const std::vector<double> halves = fast_;
  const auto [lowest, highest] = std::minmax_element(slope.begin(), slope.end());
  for (std::size_t b = 0; b < slope.size(); ++b)
    fast_[b] = (slope[b] - *lowest) / (*highest - *lowest);
  if (!rises()) {
    fast_ = halves;
    rises();
  }
  first_ = fraction.front();
  per_ = (kGuesses - 1) / (fraction.back() - first_);
  guess_.resize(kGuesses);
  for (std::size_t j = 0; j < guess_.size(); ++j)
    guess_[j] = static_cast<std::int32_t>(
        std::lower_bound(fraction.begin(), fraction.end(), first_ + static_cast<double>(j) / per_) -
        fraction.begin());
  usable_ = true;
}

bool LocusDescent::descend(const double* s, bool every_band_reads, const double* w,
                           const double* ws, double sss, Eigen::Index& at, double* chi2) const {
  at = first_guess(s, every_band_reads);
  const bool saturated = !every_band_reads && std::any_of(s, s + bands_, [](double v) {
    return v == std::numeric_limits<double>::infinity();
  });
  for (int step = 0; step < kMaxSteps; ++step) {
    evaluate(at, w, ws, sss, chi2);
    if (step == 0 && saturated) at = restart_saturated(at, w, ws, sss, chi2);
    const Step done = next(at, chi2);
    if (done != Step::kMoved) return done == Step::kSettled;
  }
  return false;
}

Eigen::Index LocusDescent::first_guess(const double* s, bool every_band_reads) const {
  Eigen::Index at;
  first_guesses(&s, 1, every_band_reads, &at);
  return at;
}

void LocusDescent::first_guesses(const double* const* s, std::size_t n, bool every_band_reads,
                                 Eigen::Index* at) const {
  if (every_band_reads) {
    for (std::size_t k = 0; k < n; ++k) at[k] = guess(fast_fraction(s[k], fast_.data(), bands_));
    return;
  }
  if (n > kMaxGuesses) {
    for (std::size_t from = 0; from < n; from += kMaxGuesses)
      first_guesses(s + from, std::min(kMaxGuesses, n - from), false, at + from);
    return;
  }
  PairSearch pairs[kMaxGuesses];
  std::size_t searched[kMaxGuesses], count = 0;
  for (std::size_t k = 0; k < n; ++k) {
    const double* x = s[k];
    bool saturated;
    const double brightest = brightest_finite(x, bands_, &saturated);
    if (saturated && pick_pair(x, brightest, pairs[count])) {
      searched[count++] = k;
      continue;
    }
    // The guess from every band's signal as far as it is known: a dim band's is, a saturated
    // band's (+INF) is at least that of the brightest band that reads, an invalid one's (NaN)
    // is left out.
    alignas(32) double known[kMaxBands];
    for (int b = 0; b < bands_; ++b)
      known[b] = std::isfinite(x[b]) ? x[b] : x[b] > 0 ? brightest : 0.0;
    at[k] = guess(fast_fraction(known, fast_.data(), bands_));
  }
  // Where m_i / m_j reaches s_i / s_j (m_i / m_j rises: i brightens faster): the first of the
  // samples every kPairStep (a table in L1 cache) by halving without branches (the processor
  // cannot predict the halves), the pixels' halvings side by side (each is a chain of
  // dependent loads), then between that sample and the one before, the ratio taken as linear.
  const auto rows = static_cast<Eigen::Index>(pair_rows_.size()) / bands_;
  const auto row = [&](Eigen::Index r) {
    return &pair_rows_[static_cast<std::size_t>(r) * bands_];
  };
  const auto below = [&](const PairSearch& p, Eigen::Index r) {
    return row(r)[p.i] * p.sj < p.si * row(r)[p.j];
  };
  for (Eigen::Index left = rows; left > 1;) {
    const Eigen::Index half = left / 2;
    for (std::size_t c = 0; c < count; ++c)
      pairs[c].base = below(pairs[c], pairs[c].base + half) ? pairs[c].base + half : pairs[c].base;
    left -= half;
  }
  for (std::size_t c = 0; c < count; ++c) {
    const PairSearch& p = pairs[c];
    const Eigen::Index r = p.base + below(p, p.base);
    Eigen::Index& to = at[searched[c]];
    if (r == 0 || r == rows) {
      to = r == 0 ? 1 : samples_ - 2;
      continue;
    }
    const double r0 = row(r - 1)[p.i] / row(r - 1)[p.j], r1 = row(r)[p.i] / row(r)[p.j];
    const double part = std::clamp((p.si / p.sj - r0) / (r1 - r0), 0.0, 1.0);
    const Eigen::Index from = (r - 1) * kPairStep, end = std::min(r * kPairStep, samples_ - 1);
    to = std::clamp<Eigen::Index>(
        from + static_cast<Eigen::Index>(part * static_cast<double>(end - from) + 0.5), 1,
        samples_ - 2);
  }
}

bool LocusDescent::pick_pair(const double* s, double brightest, PairSearch& pair) const {
  const auto bright = [&](int b) { return std::isfinite(s[b]) && s[b] >= 0.1 * brightest; };
  int i = -1, j = -1;
  for (int b : by_slope_)
    if (bright(b)) {
      i = b;
      break;
    }
  for (auto b = by_slope_.rbegin(); b != by_slope_.rend(); ++b)
    if (bright(*b)) {
      j = *b;
      break;
    }
  if (i < 0 || j < 0 || i == j || !monotonic_[static_cast<std::size_t>(i * bands_ + j)])
    return false;
  pair = {i, j, s[i], s[j], 0};
  return true;
}

Eigen::Index LocusDescent::guess(double fraction) const {
  const double cell = (fraction - first_) * per_;
  const double last = static_cast<double>(guess_.size() - 1);
  const auto j = cell > 0 ? static_cast<std::size_t>(std::min(cell, last)) : 0;  // NaN: 0
  return std::clamp<Eigen::Index>(guess_[j], 1, samples_ - 2);
}

Eigen::Index LocusDescent::restart_saturated(Eigen::Index at, const double* w, const double* ws,
                                             double sss, double* chi2) const {
  // Where chi2 curves up, a parabola's vertex is a few steps away; where it does not, the guess
  // is far off.
  if (chi2[0] - 2 * chi2[1] + chi2[2] > 0) return at;
  const double at_chi2 = chi2[1];
  double c[kSpreadGuesses];
  Eigen::Index spread[kSpreadGuesses];
  int best = 0;
  for (int k = 0; k < kSpreadGuesses; ++k) {
    spread[k] = 1 + k * (samples_ - 3) / (kSpreadGuesses - 1);
    const auto row = static_cast<std::size_t>(spread[k] * width_);
    c[k] = profiled_chi2(m_ + row, m2_ + row, ws, w, width_, sss);
    if (c[k] < c[best]) best = k;
  }
  if (!(c[best] < at_chi2)) return at;
  Eigen::Index start = spread[best];
  if (best > 0 && best < kSpreadGuesses - 1) {
    const double curvature = c[best - 1] - 2 * c[best] + c[best + 1];
    const double offset = curvature > 0 ? 0.5 * (c[best - 1] - c[best + 1]) / curvature : 0.0;
    const auto spacing = static_cast<double>(spread[best + 1] - spread[best]);
    start = std::clamp<Eigen::Index>(
        start + static_cast<Eigen::Index>(std::round(std::clamp(offset, -1.0, 1.0) * spacing)), 1,
        samples_ - 2);
  }
  evaluate(start, w, ws, sss, chi2);
  return start;
}

void LocusDescent::evaluate(Eigen::Index at, const double* w, const double* ws, double sss,
                            double* chi2) const {
  const auto row = static_cast<std::size_t>((at - 1) * width_);
  profiled_chi2_three(m_ + row, m2_ + row, ws, w, width_, sss, chi2);
}

std::vector<double> LocusDescent::check_pixels(const Eigen::MatrixXd& rates,
                                               const double* shot_gain, const double* floor,
                                               double dim, double bright, Eigen::Index every) {
  const Eigen::Index bands = rates.cols();
  std::vector<double> pixels;
  std::uint64_t state = 20251127;
  const auto noise = [&] {  // uniform with variance 1, a fixed portable sequence
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return (static_cast<double>(state >> 11) / 9007199254740992.0 * 2 - 1) * std::sqrt(3.0);
  };
  const double middle = std::sqrt(3 * dim * bright);
  Eigen::VectorXd off(bands);
  for (Eigen::Index i = every / 2; i < rates.rows(); i += every) {
    const Eigen::VectorXd at = rates.row(i).transpose() / rates.row(i).maxCoeff();
    for (const double peak : {3 * dim, middle, bright})
      for (Eigen::Index b = 0; b < bands; ++b) {
        const double signal = peak * at[b];
        pixels.push_back(signal + noise() * std::sqrt(shot_gain[b] * signal + floor[b]));
      }
    // Off the locus, where chi2 may have two minima: half this temperature's light and half
    // another's (an edge pixel), and every band off by up to +-50 % (a camera unlike the model).
    const Eigen::Index j = (i * 7919 + 13) % rates.rows();
    off = at + rates.row(j).transpose() / rates.row(j).maxCoeff();
    for (int kind = 0; kind < 2; ++kind) {
      if (kind == 1)
        for (Eigen::Index b = 0; b < bands; ++b)
          off[b] = at[b] * (1 + 0.5 * noise() / std::sqrt(3.0));
      off *= middle / off.maxCoeff();
      pixels.insert(pixels.end(), off.data(), off.data() + bands);
    }
  }
  return pixels;
}

}  // namespace pyrocam
