// The likelihood fit's short path for pixels whose bands all read, or all but a few
// (likelihood_estimator.cpp): a first guess from a ratio of two band sums, then a walk down chi2
// along the locus.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <vector>

namespace pyrocam {

// chi2(T) of a pixel whose bands all read (or all but a few of many) has one minimum near the
// locus when the camera's spectra change shape steadily with temperature (the 5x5 camera's 25
// bands). There the
// exhaustive scan's answer is the 1 degC sample whose chi2 is below both neighbours' that a walk
// from a good guess reaches: the fraction of the signal in the bands that brighten fastest (each
// weighed by its slope), which rises steadily with temperature, read on the locus. The walk jumps
// to the vertex of the parabola through three samples and stops at a sample below its neighbours:
// two steps on most pixels, whatever the scene. Where the faster half of the bands' fraction does
// not rise steadily (the colour camera's three bands turn over), the descent is not usable. It
// proves no global minimum: the estimator checks it against the scan on its own model when it is
// made (check_pixels) and keeps the scan where they differ.
class LocusDescent {
 public:
  // rates (samples x bands, DN/s) and the fit's tables of m and m^2, row after row, `width`
  // doubles a row (padded_bands); monotonic: bands x bands, whether the ratio of two bands is
  // monotonic over the locus (kept, not copied).
  LocusDescent(const Eigen::MatrixXd& rates, const double* m, const double* m2, int width,
               const std::uint8_t* monotonic);

  bool usable() const { return usable_; }

  // The sample `at` below both neighbours (chi2 at at - 1, at, at + 1 into chi2), reached from
  // the guess of signals s (ws = w s, sss = sum w s^2; first_guess; with a saturated band,
  // restart_saturated); false where the walk meets an end of the locus or does not settle (the
  // caller scans instead).
  bool descend(const double* s, bool every_band_reads, const double* w, const double* ws,
               double sss, Eigen::Index& at, double* chi2) const;

  // The walk in its parts, so that a caller can walk many pixels side by side (their steps are
  // independent, and the processor overlaps them): descend is first_guess, then evaluate and
  // next until next settles or fails, at most kMaxSteps times.
  static constexpr int kMaxSteps = 12;  // a walk not settled by then is left to the scan
  // Where a band is saturated, the walk's first step from first_guess `at` (chi2 there and at
  // its neighbours in chi2): with many saturated bands the guess can land far off (from the
  // fraction, a 1500 degC 5x5 plate with 15 of 25 bands saturated: 3100 degC; from a pair of
  // bands still off-locus pixels), where chi2 does not curve up, and the walk did not arrive in
  // kMaxSteps. There the walk starts again from the sample of least chi2
  // among kSpreadGuesses spread over the locus, moved to the vertex of the parabola through its
  // neighbours among them, with chi2 there into chi2 (where that is lower than at `at`).
  Eigen::Index restart_saturated(Eigen::Index at, const double* w, const double* ws, double sss,
                                 double* chi2) const;
  static constexpr int kSpreadGuesses = 8;
  // The farthest jump to a parabola's vertex, and the step where chi2 curves the other way.
  static constexpr double kMaxJump = 200;
  static constexpr Eigen::Index kConcaveStep = 20;
  enum class Step { kSettled, kMoved, kFailed };
  // The walk's start: where the fraction of the signal in the fast bands is that of s. Where a
  // band is saturated, where the ratio of the fastest and the slowest of the bands that read at
  // a tenth of the brightest or more is s's, if that ratio is monotonic over the locus (with 15
  // of the 5x5 camera's 25 bands saturated, the fraction landed every pixel of a 1500 degC plate
  // where chi2 does not curve up, so that every walk started again from samples spread over the
  // locus; this pair lands them where it curves up). Else, or where not every band reads, from
  // the fraction taking a saturated band's +INF as the brightest finite signal and an invalid
  // band's NaN as 0.
  Eigen::Index first_guess(const double* s, bool every_band_reads) const;
  // first_guess of n pixels (signals s[k]) into at[k], kMaxGuesses at a time side by side.
  void first_guesses(const double* const* s, std::size_t n, bool every_band_reads,
                     Eigen::Index* at) const;
  static constexpr std::size_t kMaxGuesses = 16;
  // The first guess of a pixel whose bands all read from its fast_fraction with fast_bands().
  Eigen::Index guess(double fraction) const;
  const double* fast_bands() const { return fast_.data(); }
  // The rows of m and m^2 that evaluate reads (from at - 1).
  void rows(Eigen::Index at, const double*& m, const double*& m2) const {
    const auto row = static_cast<std::size_t>((at - 1) * width_);
    m = m_ + row, m2 = m2_ + row;
  }
  // chi2 at at - 1, at, at + 1 into chi2.
  void evaluate(Eigen::Index at, const double* w, const double* ws, double sss, double* chi2) const;
  // From chi2 at at - 1, at, at + 1: settled (at is below both neighbours), moved (at is the next
  // sample to evaluate) or failed (the minimum is at an end of the locus).
  // Inline: the walks call it once per step and pixel.
  Step next(Eigen::Index& at, const double* chi2) const {
    if (chi2[1] < chi2[0] && chi2[1] <= chi2[2]) return Step::kSettled;
    const double curvature = chi2[0] - 2 * chi2[1] + chi2[2];
    const Eigen::Index down = chi2[0] < chi2[2] ? -1 : 1;
    Eigen::Index jump = down * kConcaveStep;
    if (curvature > 0) {
      const double vertex = std::clamp(0.5 * (chi2[0] - chi2[2]) / curvature, -kMaxJump, kMaxJump);
      jump = static_cast<Eigen::Index>(vertex + (vertex < 0 ? -0.5 : 0.5));  // nearest
      if (jump == 0) jump = down;
    }
    const Eigen::Index to = std::clamp<Eigen::Index>(at + jump, 1, samples_ - 2);
    if (to == at) return Step::kFailed;  // the minimum is at an end of the locus
    at = to;
    return Step::kMoved;
  }

  // Pixels that the estimator reads both ways when it is made: along the whole locus every
  // `every` samples, the brightest band at three levels from just above `dim` to `bright` DN,
  // with noise of the fit's model (shot gain and floor per band) drawn from a fixed sequence,
  // and two pixels off the locus (a mixture with another temperature, every band off by up to
  // +-50 %). Pixel after pixel.
  static std::vector<double> check_pixels(const Eigen::MatrixXd& rates, const double* shot_gain,
                                          const double* floor, double dim, double bright,
                                          Eigen::Index every);

 private:
  // A pair of bands for first_guess, and where its search is.
  struct PairSearch {
    int i, j;  // the fastest and the slowest band
    double si, sj;
    Eigen::Index base;  // the halving's row of pair_rows_
  };
  // The pair of s's bands for first_guess (false where it is not monotonic).
  bool pick_pair(const double* s, double brightest, PairSearch& pair) const;
  const double* m_;
  const std::uint8_t* monotonic_;
  std::vector<int> by_slope_;
  static constexpr Eigen::Index kPairStep = 64;
  std::vector<double> pair_rows_;  // the rates every kPairStep samples and at the last
  const double* m2_;
  int bands_, width_;
  Eigen::Index samples_;
  std::vector<double> fast_;  // per band: 1 where it brightens faster than the median band
  // The first guess: the sample where the fraction of the signal in the fast bands reaches
  // first_ + j / per_ (lower bound on the locus), j < kGuesses. The fraction, not a log ratio:
  // one division instead of a logarithm, and a third of a sample per cell all the same.
  std::vector<std::int32_t> guess_;  // int32: half the cache of an index
  double first_ = 0, per_ = 0;
  bool usable_ = false;
};

}  // namespace pyrocam
