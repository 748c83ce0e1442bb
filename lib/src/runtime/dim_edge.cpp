#include "pyrocam/runtime/dim_edge.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/noise_model.h"

namespace pyrocam {

DimEdgeCheck::DimEdgeCheck(const CameraProfile& profile, double gain, const DemosaicNoise& noise) {
  const int bands = profile.band_count();
  if (bands > static_cast<int>(kMaxBands))
    throw InputError("dim-edge check: " + std::to_string(bands) + " bands, at most " +
                     std::to_string(kMaxBands));
  const double dim = profile.thresholds.inference_dim_dn;
  const int phases = noise.period_width * noise.period_height;
  for (int b = 0; b < bands; ++b) {
    double factor = noise.factor.empty() ? 1.0 : 0.0;
    for (int phase = 0; phase < phases && !noise.factor.empty(); ++phase)
      factor = std::max(factor, noise.factor[static_cast<std::size_t>(phase * noise.bands + b)]);
    const double sd = std::sqrt(signal_variance_dn2(profile, b, dim, 1, gain) * factor);
    accept_dn_.push_back(static_cast<float>(dim + kNoiseMargin * sd));
    checked_dn_.push_back(static_cast<float>(dim + kCheckedMargin * sd));
  }
}

namespace {

// Sums of the ring's four halves (above, below, left of, right of the pixel). A value without a
// reading (NaN: an invalid sample, or a mixed-pixel mark) counts as no light, so that such marks
// only ever refuse more; a saturated one (+INF) counts as `saturated`; a number above
// `foreign_above` makes the ring's mean NaN.
struct RingHalves {
  RingHalves(double saturated, double foreign_above)
      : saturated(saturated), foreign_above(foreign_above) {}
  double saturated, foreign_above;
  mutable bool foreign = false;
  // The first of from, from + 1, ... that lies on phase + k step.
  static int first(int from, int phase, int step) {
    return from + ((phase - from) % step + step) % step;
  }
  double sum[4] = {0, 0, 0, 0};
  int count[4] = {0, 0, 0, 0};

  // The values at columns phase_x + k step_x and rows phase_y + k step_y of the ring around
  // columns first .. last of row y.
  void add(const cv::Mat& image, int first_x, int last_x, int y, DimEdgeCheck::Ring ring,
           int step_x, int step_y, int phase_x, int phase_y) {
    last_x = std::min(last_x, image.cols - 1);
    const int y0 = first(std::max(0, y - ring.outer), phase_y, step_y);
    const int x0 = first(std::max(0, first_x - ring.outer), phase_x, step_x);
    const int y1 = std::min(image.rows - 1, y + ring.outer);
    const int x1 = std::min(image.cols - 1, last_x + ring.outer);
    // Per row: the values left of the span, on its columns and right of it, across the hole in
    // the ring's inner rows; the row's whole share goes to the half above or below.
    for (int v = y0; v <= y1; v += step_y) {
      const float* row = image.ptr<float>(v);
      const bool inner_row = std::abs(v - y) < ring.inner;
      const int left_end = inner_row ? first_x - ring.inner + 1 : first_x;  // exclusive
      const int right_begin = first(inner_row ? last_x + ring.inner : last_x + 1, phase_x, step_x);
      Span left{*this}, middle{*this}, right{*this};
      int u = x0;
      for (; u < left_end && u <= x1; u += step_x) left.add(row[u]);
      if (!inner_row)
        for (; u < right_begin && u <= x1; u += step_x) middle.add(row[u]);
      for (u = right_begin; u <= x1; u += step_x) right.add(row[u]);
      const int vertical = v < y ? 0 : v > y ? 1 : -1;
      if (vertical >= 0) {
        sum[vertical] += left.sum + middle.sum + right.sum;
        count[vertical] += left.n + middle.n + right.n;
      }
      sum[2] += left.sum, count[2] += left.n;
      sum[3] += right.sum, count[3] += right.n;
    }
  }
  struct Span {
    const RingHalves& halves;
    double sum = 0;
    int n = 0;
    void add(float v) { sum += halves.value(v), ++n; }
  };
  double value(float v) const {
    if (std::isnan(v)) return 0.0;
    if (std::isinf(v)) return saturated;
    foreign |= v > foreign_above;
    return v;
  }
  // The largest half's mean; NaN where no half has a value, or one is foreign.
  double largest() const {
    double best = NAN;
    if (foreign) return best;
    for (int k = 0; k < 4; ++k)
      if (count[k] > 0 && !(sum[k] / count[k] <= best)) best = sum[k] / count[k];
    return best;
  }
};

typedef std::int64_t LaneMask __attribute__((vector_size(32)));

// RingHalves of four spans side by side, lane j the span `span` columns right of lane j - 1's,
// where every lane's ring lies inside the image and `span` is a multiple of the sample step (so
// that each lane's loops are lane 0's, shifted): each lane takes RingHalves' operations in its
// order, so the means are the same bits. (Near the saturation level a plate's bands need a ring
// per span: one by one, they took most of a colour frame's time with the red band there.)
struct RingHalvesFour {
  RingHalvesFour(double saturated, double foreign_above)
      : saturated{saturated, saturated, saturated, saturated},
        foreign_above{foreign_above, foreign_above, foreign_above, foreign_above} {}
  Lanes saturated, foreign_above;
  LaneMask foreign = {0, 0, 0, 0};
  Lanes sum[4] = {};
  int count[4] = {0, 0, 0, 0};

  // RingHalves::value of the lanes' values at column u, added to `to` (vectors by reference:
  // by value the baseline version's ABI differs).
  void add_value(Lanes& to, const float* row, int u, int span) {
    const Lanes v = {row[u], row[u + span], row[u + 2 * span], row[u + 3 * span]};
    const Lanes zero = {0, 0, 0, 0}, inf = {INFINITY, INFINITY, INFINITY, INFINITY};
    const LaneMask infinite = (v == inf) | (v == -inf);
    foreign |= ~infinite & (v > foreign_above);  // false for NaN, as RingHalves::value
    const Lanes number = v == v ? v : zero;
    to += infinite ? saturated : number;
  }

  // RingHalves::add of lane 0's span first_x .. first_x + span - 1, without the clipping (the
  // caller checked that no lane's ring needs it).
  void add(const cv::Mat& image, int first_x, int span, int y, DimEdgeCheck::Ring ring, int step_x,
           int step_y, int phase_x, int phase_y) {
    const int last_x = first_x + span - 1;
    const int y0 = RingHalves::first(y - ring.outer, phase_y, step_y);
    const int x0 = RingHalves::first(first_x - ring.outer, phase_x, step_x);
    const int y1 = y + ring.outer, x1 = last_x + ring.outer;
    const Lanes zero = {0, 0, 0, 0};
    for (int v = y0; v <= y1; v += step_y) {
      const float* row = image.ptr<float>(v);
      const bool inner_row = std::abs(v - y) < ring.inner;
      const int left_end = inner_row ? first_x - ring.inner + 1 : first_x;
      const int right_begin =
          RingHalves::first(inner_row ? last_x + ring.inner : last_x + 1, phase_x, step_x);
      Lanes left = zero, middle = zero, right = zero;
      int n_left = 0, n_middle = 0, n_right = 0;
      int u = x0;
      for (; u < left_end && u <= x1; u += step_x) add_value(left, row, u, span), ++n_left;
      if (!inner_row)
        for (; u < right_begin && u <= x1; u += step_x) add_value(middle, row, u, span), ++n_middle;
      for (u = right_begin; u <= x1; u += step_x) add_value(right, row, u, span), ++n_right;
      const int vertical = v < y ? 0 : v > y ? 1 : -1;
      if (vertical >= 0) {
        sum[vertical] += left + middle + right;
        count[vertical] += n_left + n_middle + n_right;
      }
      sum[2] += left, count[2] += n_left;
      sum[3] += right, count[3] += n_right;
    }
  }

  // RingHalves::largest of each lane.
  void largest(double* out) const {
    Lanes best = {NAN, NAN, NAN, NAN};
    for (int k = 0; k < 4; ++k) {
      if (count[k] == 0) continue;
      const Lanes mean = sum[k] / static_cast<double>(count[k]);
      best = mean <= best ? best : mean;
    }
    for (int j = 0; j < 4; ++j) out[j] = foreign[j] ? NAN : best[j];
  }
};

// Whether four spans from first_x on (`span` columns each) have rings of `ring` inside an
// image of cols x rows around row y, and lane 0's loops shifted give the others'.
bool four_inside(const cv::Mat& image, int first_x, int span, int y, DimEdgeCheck::Ring ring,
                 int step_x) {
  return span % step_x == 0 && first_x - ring.outer >= 0 &&
         first_x + 4 * span - 1 + ring.outer <= image.cols - 1 && y - ring.outer >= 0 &&
         y + ring.outer <= image.rows - 1;
}

PYROCAM_VECTOR_CLONES
void plane_four(const cv::Mat& plane, int first, int span, int y, DimEdgeCheck::Ring ring,
                double saturated, double foreign_above, double* means) {
  RingHalvesFour halves(saturated, foreign_above);
  halves.add(plane, first, span, y, ring, 1, 1, 0, 0);
  halves.largest(means);
}

PYROCAM_VECTOR_CLONES
void mosaic_four(const cv::Mat& mosaic, const MosaicLayout& layout, int band, int first, int span,
                 int y, DimEdgeCheck::Ring ring, double saturated, double foreign_above,
                 double* means) {
  RingHalvesFour halves(saturated, foreign_above);
  for (int py = 0; py < layout.period_height; ++py)
    for (int px = 0; px < layout.period_width; ++px)
      if (layout.band_at(px, py) == band)
        halves.add(mosaic, first, span, y, ring, layout.period_width, layout.period_height, px, py);
  halves.largest(means);
}

}  // namespace

void plane_ring_means_four(const cv::Mat& plane, int first, int span, int y,
                           DimEdgeCheck::Ring ring, double* means, double saturated,
                           double foreign_above) {
  if (four_inside(plane, first, span, y, ring, 1)) {
    plane_four(plane, first, span, y, ring, saturated, foreign_above, means);
    return;
  }
  for (int k = 0; k < 4; ++k) {
    const int at = first + k * span;
    means[k] = at < plane.cols
                   ? plane_ring_mean(plane, at, at + span - 1, y, ring, saturated, foreign_above)
                   : NAN;
  }
}

void mosaic_ring_means_four(const cv::Mat& mosaic, const MosaicLayout& layout, int band, int first,
                            int span, int y, DimEdgeCheck::Ring ring, double* means,
                            double saturated, double foreign_above) {
  if (four_inside(mosaic, first, span, y, ring, layout.period_width) && layout.period_height > 0) {
    mosaic_four(mosaic, layout, band, first, span, y, ring, saturated, foreign_above, means);
    return;
  }
  for (int k = 0; k < 4; ++k) {
    const int at = first + k * span;
    means[k] = at < mosaic.cols ? mosaic_ring_mean(mosaic, layout, band, at, at + span - 1, y, ring,
                                                   saturated, foreign_above)
                                : NAN;
  }
}

double plane_ring_mean(const cv::Mat& plane, int first, int last, int y, DimEdgeCheck::Ring ring,
                       double saturated, double foreign_above) {
  RingHalves halves(saturated, foreign_above);
  halves.add(plane, first, last, y, ring, 1, 1, 0, 0);
  return halves.largest();
}

double mosaic_ring_mean(const cv::Mat& mosaic, const MosaicLayout& layout, int band, int first,
                        int last, int y, DimEdgeCheck::Ring ring, double saturated,
                        double foreign_above) {
  // The band's samples only: a stride of the period from each of its places in the period.
  RingHalves halves(saturated, foreign_above);
  for (int py = 0; py < layout.period_height; ++py)
    for (int px = 0; px < layout.period_width; ++px)
      if (layout.band_at(px, py) == band)
        halves.add(mosaic, first, last, y, ring, layout.period_width, layout.period_height, px, py);
  return halves.largest();
}

}  // namespace pyrocam
