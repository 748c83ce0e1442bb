// The likelihood fit's per-pixel kernels (likelihood_estimator.cpp), compiled for AVX2 too
// (PYROCAM_VECTOR_CLONES): the same bits in every version.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <new>

namespace pyrocam {

// Bands rounded up to whole lanes of four: the row width of the fit's tables of m and m^2 and
// what weigh_bands fills of w and ws, zero past the bands. profiled_chi2 over the padded width
// adds the same terms in the same lanes as over the bands alone when bands % 4 is 0, 1 or 3
// with bands < 4 (the 5x5 and colour cameras): padding adds +0 to whole lanes only.
constexpr int padded_bands(int bands) { return (bands + 3) / 4 * 4; }

// n zeroed doubles from a 64-byte boundary: rows of padded_bands doubles then never straddle a
// cache line within one 32-byte load (rows of 25 did, at one load in three).
class AlignedDoubles {
 public:
  explicit AlignedDoubles(std::size_t n) : size_(n) {
    const std::size_t bytes = (n * sizeof(double) + 63) / 64 * 64;
    data_.reset(static_cast<double*>(std::aligned_alloc(64, bytes == 0 ? 64 : bytes)));
    if (!data_) throw std::bad_alloc();
    for (std::size_t i = 0; i < n; ++i) data_[i] = 0.0;
  }
  double& operator[](std::size_t i) { return data_[i]; }
  const double& operator[](std::size_t i) const { return data_[i]; }
  const double* data() const { return data_.get(); }
  std::size_t size() const { return size_; }

 private:
  struct Free {
    void operator()(double* p) const { std::free(p); }
  };
  std::unique_ptr<double[], Free> data_;
  std::size_t size_;
};

// Samples per step of bounded_chi2 (long coarse scans, single precision) and approximate_sums
// (short windows, double precision).
inline constexpr std::ptrdiff_t kCoarseBlock = 32, kWindowBlock = 16;
inline constexpr int kMaxRank = 16;       // low-rank factors of the likelihood fit's locus
inline constexpr int kMaxWindowRank = 8;  // a refinement window's own basis of them
inline constexpr std::ptrdiff_t kMaxMinimumCandidates = 1024;  // samples minimum_candidates takes

// Bounds of chi2 from factors in single precision at the first `count` samples, into lower
// and upper [0 .. count rounded up to kCoarseBlock) (rank, rank2 >= 1): ssm and smm summed
// from the factors are taken to be off by at most ssm_error and smm_error, and the bounds
// widened by slack (their own rounding). A lower bound is -FLT_MAX where smm may be 0.
void bounded_chi2(const float* along, int rank, const float* along2, int rank2,
                  std::ptrdiff_t stride, std::ptrdiff_t count, const float* p, const float* q,
                  float sss, float ssm_error, float smm_error, float slack, float* lower,
                  float* upper);

// The samples of bounded_chi2's bounds that may be local minima (2 <= count <=
// kMaxMinimumCandidates): those whose lower bound is not above the upper bound of either
// neighbour, their indices into `at` in increasing order. Returns how many.
int minimum_candidates(const float* lower, const float* upper, std::ptrdiff_t count,
                       std::int32_t* at);

// The approximate sums ssm = p . along, smm = q . along2 at `count` samples from `from`, into
// ssm and smm [0 .. count rounded up to kWindowBlock) (rank, rank2 >= 1).
void approximate_sums(const double* along, int rank, const double* along2, int rank2,
                      std::ptrdiff_t stride, std::ptrdiff_t from, std::ptrdiff_t count,
                      const double* p, const double* q, double* ssm, double* smm);

// x (projections on `rank` factors) in a refinement window's basis (kMaxRank x kMaxWindowRank,
// zero padded): out[j] = sum_r x[r] basis[r][j] for j < kMaxWindowRank.
void to_window_basis(const double* basis, int rank, const double* x, double* out);

// Flags, into open[0 .. count), the samples whose chi2 (sss - ssm^2 / smm, ssm and smm within
// ssm_error and smm_error of the values given, the exact chi2 within slack of it) may be the
// least of them: those whose lower bound is not above the least of their upper bounds (or where
// smm may be 0). Returns how many. Vectorises.
int window_candidates(const double* ssm, const double* smm, std::ptrdiff_t count, double sss,
                      double ssm_error, double smm_error, double slack, std::uint8_t* open);

// chi2 = sss - ssm^2 / smm of the likelihood fit at one locus sample: ssm = sum (w s) m and
// smm = sum w m^2 over the bands.
double profiled_chi2(const double* m, const double* m2, const double* ws, const double* w,
                     int bands, double sss);

// profiled_chi2 at three samples side by side (rows m, m + bands, m + 2 bands), into chi2[0 .. 3):
// the same bits, in one pass.
void profiled_chi2_three(const double* m, const double* m2, const double* ws, const double* w,
                         int bands, double sss, double* chi2);

// profiled_chi2_three of four pixels, the same bits: pixel k's rows from m[k] and m2[k] (width a
// multiple of four, padded_bands), its ws[k], w[k] and sss[k], into chi2[k][0 .. 3).
void profiled_chi2_three_four(const double* const* m, const double* const* m2,
                              const double* const* ws, const double* const* w, int width,
                              const double* sss, double* const* chi2);

// sum(fast s) / sum(s) over the bands (fast: a weight per band, 0 .. 1), each summed band after
// band: the descent's first guess (NaN or infinite where sum(s) is 0).
double fast_fraction(const double* s, const double* fast, int bands);

// The likelihood fit's weights of one pixel: w = 1 / variance for a band with a reading (finite
// and at least `weigh_dim`), 0 for one without; ws = w s (0 without a reading); *sss = sum w s^2.
// w and ws are filled to padded_bands(bands), with 0 past the bands. Returns how many bands
// read; *bright: how many of them are at least `dim` too (dim >= weigh_dim).
int weigh_bands(const double* __restrict s, int bands, double weigh_dim, double dim,
                const double* __restrict gain, const double* __restrict floor, double* __restrict w,
                double* __restrict ws, double* sss, int* bright);

// What weigh_four gives per pixel besides w and ws.
struct FourWeighed {
  double sss[4], fraction[4];
  int reading[4], bright[4], saturated[4];  // bands: weighed, at the dim threshold, +INF
};

// weigh_bands and fast_fraction (fast: a weight per band) of the four pixels from .. from + 3 of
// the band rows planes[b], the same bits: pixel k's w and ws into w[k] and ws[k] (to
// padded_bands(bands), rows on 32 bytes), its signals as doubles into s[k] unless s is null
// (whole lanes of four: zero past the bands), sum w s^2, the fraction and the counts into out.
void weigh_four(const float* const* planes, int bands, std::size_t from, double weigh_dim,
                double dim, const double* __restrict gain, const double* __restrict floor,
                const double* __restrict fast, double* const* w, double* const* ws,
                double* const* s, FourWeighed& out);

// reading[k] = how many of pixel from + k's bands read as weigh_bands decides (finite and at
// least the threshold), for k < n: planes[b] is band b's row; dim_f is the least float whose
// double value is at least weigh_bands' threshold (so the two agree). Vectorises.
void count_reading_bands(const float* const* planes, int bands, std::size_t from, std::size_t n,
                         float dim_f, std::int32_t* reading);

// Projections p = V^T (w s), q = V2^T w on the factors (bands x kMaxRank each, zero padded), in
// double and single precision, and squares = {|w s|^2, |w|^2} (bands >= 1).
void project(const double* __restrict ws, const double* __restrict w, int bands,
             const double* __restrict v, const double* __restrict v2, double* __restrict p,
             double* __restrict q, float* __restrict pf, float* __restrict qf,
             double* __restrict squares);

}  // namespace pyrocam
