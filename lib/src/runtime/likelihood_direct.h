// The likelihood fit's scan for pixels that few bands read (likelihood_estimator.cpp): chi2 at
// every coarse sample and in each refinement window computed exactly from those bands alone.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "runtime/estimator_kinds.h"

namespace pyrocam {

// The bands a pixel weighs, by the lane of four that profiled_chi2 adds each of them in (band
// b in lane b % 4), in increasing order within a lane: lane j's bands are band[start[j] ..
// start[j + 1]).
struct LaneBands {
  int band[kMaxBands];
  int start[5];
};

// Which of `bands` bands have a weight (w[b] != 0), by lane.
LaneBands lane_bands(const double* w, int bands);

// The locus rates m and their squares m^2 band after band (every sample of a band side by side),
// in full and at the coarse samples (every `coarse`th). chi2 = sss - ssm^2 / smm at a sample then
// costs two multiply-adds per weighed band, eight samples at a time, instead of two per band of
// the row: a pixel with 7 of 25 bands weighed (the others saturated) was scanned at about 2 us a
// pixel through the low-rank factors, whose cost does not fall with the bands. Each lane sums its
// bands in profiled_chi2's order, and a band without a weight adds +0 there (w and ws are 0):
// the same bits as profiled_chi2 over the row.
class DirectChi2 {
 public:
  // m and m2: samples x width (padded_bands), row after row; `bands` of each row are read.
  // monotonic: bands x bands, whether a pair's ratio keeps one direction over the samples.
  DirectChi2(const double* m, const double* m2, int width, int bands, Eigen::Index samples,
             Eigen::Index coarse, const std::uint8_t* monotonic);

  Eigen::Index coarse_count() const { return coarse_count_; }

  // chi2 at the coarse samples from, from + 1, ... from + count - 1 (samples from * coarse, ...)
  // into chi2[0 .. count) (room for count rounded up to eight); each sample's bits are the same
  // whatever the run it is in.
  void at_coarse(const LaneBands& lanes, const double* ws, const double* w, double sss,
                 Eigen::Index from, Eigen::Index count, double* chi2) const;

  // The coarse samples [first, last] whose refinement windows (a coarse step each side) can hold
  // a sample where chi2 is less than `margin` above its least value; false where it cannot tell
  // (no weighed pair of bands has a monotonic ratio): then every coarse sample can. chi2 with
  // all weighed bands is at least that of any two of them alone, each fit with its own scale,
  // and for a pair whose ratio is monotonic along the locus that is a bowl around the sample
  // where the ratio is the pixel's, rising on both sides. *upper (an upper bound of the least
  // chi2: chi2 at the coarse sample where the ratios cross) plus `margin` sets its rim; samples
  // past the first coarse sample outside it on each side cannot come within `margin`.
  bool coarse_span(const LaneBands& lanes, const double* ws, const double* w, double sss,
                   double margin, Eigen::Index& first, Eigen::Index& last, double& upper) const;
  // chi2 at the samples from .. from + count - 1 into chi2[0 .. count) (room for count rounded
  // up to eight).
  void at_samples(const LaneBands& lanes, const double* ws, const double* w, double sss,
                  Eigen::Index from, Eigen::Index count, double* chi2) const;

 private:
  int bands_ = 0;
  Eigen::Index stride_ = 0, coarse_count_ = 0, coarse_stride_ = 0;
  std::vector<double> m_, m2_, coarse_m_, coarse_m2_;  // band after band, `stride` a band
  // bands x bands: how far a monotonic pair's log ratio moves along the locus, first to last
  // sample (positive: it rises; 0: not monotonic).
  std::vector<double> reach_;
};

}  // namespace pyrocam
