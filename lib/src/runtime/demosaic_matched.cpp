// Moment-matched Bayer demosaicking (DemosaicMethod::kMatched).
//
// Why: a band interpolated from its neighbours is a local mean, so on a curved signal (a melt
// pool's peak, a cooling tail) it is off by half its kernel's second moment times the band's
// curvature, while a band taken at the pixel itself is not. Bilinear demosaicking gives the
// three bands second moments of 0 (self), 0.5 (cross) and 1 (diagonal) pixel^2, so their
// ratio is off by the curvature of one band's log signal, about ten times that of the log
// ratio between the colour camera's bands: at a few-pixel hot spot the reading is 100 degC
// and more too hot. Here every band of every pixel comes from a symmetric kernel with the same
// second moment (1 pixel^2 along each axis, none across), so the curvature terms of the bands
// cancel down to that of the log ratio itself: the reading is that of the temperature field
// seen through one common blur, as an optical blur would give.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>
#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"
#include "pyrocam/runtime/demosaic.h"

namespace pyrocam {
namespace {

// The kernels by where the band's samples lie around the pixel. Each has weights summing to
// 1, first moments 0 and second moments 1 pixel^2 along x and y, 0 across (the unit test
// checks this on a quadratic). Row sums: r0 the pixel's row, v the rows 1 above and below
// added, c those 2 above and below added.
enum class Kernel {
  kSelfAxial,     // R or B at its own pixel: itself 1/2, its samples 2 away along the axes 1/8
  kSelfDiagonal,  // G at its own pixel: itself 2/9, diagonals 5/36, 2 away along the axes 1/18
  kHorizontal,    // left and right 3/8, the same columns 2 rows away 1/16
  kVertical,      // above and below 3/8, the same rows 2 columns away 1/16
  kDiagonal,      // the four diagonals 1/4
  kCross,         // G at R or B: the four next 3/16, the eight a knight's move away 1/32
};

// The kernels work on rows split by column parity, so that every output column is computed
// once and the loops stay contiguous: for an output column x, `s` holds the samples of x's
// parity (s[i] is x - 2, s[i + 1] x itself, s[i + 2] x + 2) and `t` those of the other parity
// (t[i] is x - 1, t[i + 1] x + 1), each for the pixel's row (r0), the rows 1 above and below
// added (v) and those 2 above and below added (c).
template <Kernel kK>
inline float apply(const float* s, const float* t, const float* vs, const float* vt,
                   const float* cs, const float* ct, int i) {
  switch (kK) {
    case Kernel::kSelfAxial:
      return 0.5f * s[i + 1] + 0.125f * ((s[i] + s[i + 2]) + cs[i + 1]);
    case Kernel::kSelfDiagonal:
      return (2.f / 9) * s[i + 1] + (5.f / 36) * (vt[i] + vt[i + 1]) +
             (1.f / 18) * ((s[i] + s[i + 2]) + cs[i + 1]);
    case Kernel::kHorizontal:
      return 0.375f * (t[i] + t[i + 1]) + 0.0625f * (ct[i] + ct[i + 1]);
    case Kernel::kVertical:
      return 0.375f * vs[i + 1] + 0.0625f * (vs[i] + vs[i + 2]);
    case Kernel::kDiagonal:
      return 0.25f * (vt[i] + vt[i + 1]);
    case Kernel::kCross:
      return 0.1875f * ((t[i] + t[i + 1]) + vs[i + 1]) +
             0.03125f * ((vs[i] + vs[i + 2]) + (ct[i] + ct[i + 1]));
  }
  return 0.f;
}

// One kernel over the n output columns of one parity.
template <Kernel kK>
PYROCAM_VECTOR_CLONES void kernel_row(const float* __restrict s, const float* __restrict t,
                                      const float* __restrict vs, const float* __restrict vt,
                                      const float* __restrict cs, const float* __restrict ct,
                                      float* __restrict o, int n) {
  for (int i = 0; i < n; ++i) o[i] = apply<kK>(s, t, vs, vt, cs, ct, i);
}

using RowFn = void (*)(const float*, const float*, const float*, const float*, const float*,
                       const float*, float*, int);

RowFn row_fn(Kernel k) {
  switch (k) {
    case Kernel::kSelfAxial:
      return kernel_row<Kernel::kSelfAxial>;
    case Kernel::kSelfDiagonal:
      return kernel_row<Kernel::kSelfDiagonal>;
    case Kernel::kHorizontal:
      return kernel_row<Kernel::kHorizontal>;
    case Kernel::kVertical:
      return kernel_row<Kernel::kVertical>;
    case Kernel::kDiagonal:
      return kernel_row<Kernel::kDiagonal>;
    case Kernel::kCross:
      return kernel_row<Kernel::kCross>;
  }
  return nullptr;
}

// out = even[0], odd[0], even[1], ...; -INF (no signal) becomes 0 (dim) when `no_signal`.
// With `stream`, the stores bypass the cache (see demosaic_matched_bayer); the caller fences.
PYROCAM_VECTOR_CLONES
void interleave(const float* __restrict even, const float* __restrict odd, float* __restrict out,
                int width, bool no_signal, bool stream) {
  constexpr float kMinusInf = -std::numeric_limits<float>::infinity();
  const int pairs = width / 2;
  int i0 = 0;
#if defined(__SSE2__)
  const auto misaligned = reinterpret_cast<std::uintptr_t>(out) & 15;
  if (stream && no_signal && (misaligned == 0 || misaligned == 8) && pairs > 0) {
    if (misaligned == 8) {  // one pair the usual way, then every store is on 16 bytes
      out[0] = even[0] == kMinusInf ? 0.f : even[0];
      out[1] = odd[0] == kMinusInf ? 0.f : odd[0];
      i0 = 1;
    }
    const __m128 minus_inf = _mm_set1_ps(kMinusInf);
    for (; i0 + 4 <= pairs; i0 += 4) {
      __m128 e = _mm_loadu_ps(even + i0), o = _mm_loadu_ps(odd + i0);
      e = _mm_andnot_ps(_mm_cmpeq_ps(e, minus_inf), e);  // -INF to 0 (+0: its bits cleared)
      o = _mm_andnot_ps(_mm_cmpeq_ps(o, minus_inf), o);
      _mm_stream_ps(out + 2 * i0, _mm_unpacklo_ps(e, o));
      _mm_stream_ps(out + 2 * i0 + 4, _mm_unpackhi_ps(e, o));
    }
  }
#else
  (void)stream;
#endif
  if (no_signal) {
    for (int i = i0; i < pairs; ++i) {
      out[2 * i] = even[i] == kMinusInf ? 0.f : even[i];
      out[2 * i + 1] = odd[i] == kMinusInf ? 0.f : odd[i];
    }
  } else {
    for (int i = 0; i < pairs; ++i) {
      out[2 * i] = even[i];
      out[2 * i + 1] = odd[i];
    }
  }
  if (width & 1) out[width - 1] = no_signal && even[pairs] == kMinusInf ? 0.f : even[pairs];
}

// even = row[0], row[2], ...; odd = row[1], row[3], ... (n samples); with `no_signal`, samples
// below it become -INF.
PYROCAM_VECTOR_CLONES
void split_row(const float* __restrict row, int n, float no_signal, float* __restrict even,
               float* __restrict odd) {
  constexpr float kMinusInf = -std::numeric_limits<float>::infinity();
  for (int j = 0; j < n / 2; ++j) {
    const float a = row[2 * j], b = row[2 * j + 1];
    even[j] = a < no_signal ? kMinusInf : a;
    odd[j] = b < no_signal ? kMinusInf : b;
  }
  if (n & 1) even[n / 2] = row[n - 1] < no_signal ? kMinusInf : row[n - 1];
}

// Whether any of split_row's samples (n_even and n_odd of them) has light: not -INF, its mark of
// a sample below the no-signal level. A mark of darksub's (NaN, +INF) counts as light: the
// kernels carry it to the band value as they do any sample with light.
PYROCAM_VECTOR_CLONES
bool any_lit(const float* __restrict even, int n_even, const float* __restrict odd, int n_odd) {
  constexpr float kMinusInf = -std::numeric_limits<float>::infinity();
  std::int32_t lit = 0;
  for (int i = 0; i < n_even; ++i) lit |= even[i] == kMinusInf ? 0 : 1;
  for (int i = 0; i < n_odd; ++i) lit |= odd[i] == kMinusInf ? 0 : 1;
  return lit != 0;
}

// a + b element by element (the row sums v and c).
PYROCAM_VECTOR_CLONES
void add_rows(const float* __restrict a, const float* __restrict b, float* __restrict out, int n) {
  for (int i = 0; i < n; ++i) out[i] = a[i] + b[i];
}

Kernel kernel_for(const MosaicLayout& layout, int band, int px, int py) {
  auto is = [&](int x, int y) { return layout.band_at(x & 1, y & 1) == band; };
  if (is(px, py)) return is(px + 1, py + 1) ? Kernel::kSelfDiagonal : Kernel::kSelfAxial;
  if (is(px + 1, py)) return is(px, py + 1) ? Kernel::kCross : Kernel::kHorizontal;
  if (is(px, py + 1)) return Kernel::kVertical;
  return Kernel::kDiagonal;
}

}  // namespace

std::vector<cv::Point> matched_footprint(const MosaicLayout& layout, int band, int px, int py) {
  std::vector<cv::Point> at;
  auto pairs = [&](int dx, int dy) {  // (dx, dy) with every sign
    for (int sx : {-1, 1})
      for (int sy : {-1, 1})
        if ((sx > 0 || dx != 0) && (sy > 0 || dy != 0)) at.push_back({sx * dx, sy * dy});
  };
  switch (kernel_for(layout, band, px, py)) {
    case Kernel::kSelfAxial:
      at.push_back({0, 0}), pairs(2, 0), pairs(0, 2);
      break;
    case Kernel::kSelfDiagonal:
      at.push_back({0, 0}), pairs(1, 1), pairs(2, 0), pairs(0, 2);
      break;
    case Kernel::kHorizontal:
      pairs(1, 0), pairs(1, 2);
      break;
    case Kernel::kVertical:
      pairs(0, 1), pairs(2, 1);
      break;
    case Kernel::kDiagonal:
      pairs(1, 1);
      break;
    case Kernel::kCross:
      pairs(1, 0), pairs(0, 1), pairs(1, 2), pairs(2, 1);
      break;
  }
  return at;
}

namespace {

// What MatchedBayer::run keeps from one call to the next: the ring of split input rows and their
// flags, the row sums, the outputs' halves and a half row of zeros; next_row is the input row
// the ring would load next.
struct MatchedRing {
  std::vector<float> buffer;
  std::vector<std::uint8_t> lit, out_lit;
  int next_row = std::numeric_limits<int>::min();
};

// Matched Bayer demosaicking of ranges of output rows, for a whole frame or a strip of one.
//
// The cold background around a melt pool or a filament is most of the frame: a block of output
// columns whose kernels reach only samples without light has every band value -INF, i.e. 0,
// which is written without running the kernels. Blocks of kBlock column pairs; output pair i
// reads the input pairs i..i+2, so output block K reads input blocks K and K + 1.
class MatchedBayer {
 public:
  static constexpr int kReach = 2, kBlock = kMatchedBlockColumns / 2;

  MatchedBayer(const cv::Mat& mosaic, const MosaicLayout& layout, float no_signal_dn)
      : mosaic_(mosaic), no_signal_dn_(no_signal_dn) {
    mark_no_signal_ = no_signal_dn > -std::numeric_limits<float>::infinity();
    for (int b = 0; b < 3; ++b)
      for (int py = 0; py < 2; ++py)
        for (int px = 0; px < 2; ++px) rows_of_[b][py][px] = row_fn(kernel_for(layout, b, px, py));
    width_ = mosaic.cols, height_ = mosaic.rows, padded_width_ = width_ + 2 * kReach;
    // Padded column p goes to half row p / 2 of its parity: even (p even) or odd.
    half_ = padded_width_ / 2 + 1;
    n_even_ = (width_ + 1) / 2, n_odd_ = width_ / 2;  // output columns of each parity
    blocks_ = (half_ + kBlock - 1) / kBlock;
    out_blocks_ = (n_even_ + kBlock - 1) / kBlock;
  }

  int out_blocks() const { return out_blocks_; }
  int width() const { return width_; }

  // Output rows [y0, y1): band b of row y into out(b, y) (a row of the mosaic's width). With
  // `stream` the stores bypass the cache and are fenced at the end. With `lit`, one flag per
  // row and output block from row y0 on: whether a sample its kernels reach has light; the
  // blocks without are then left unwritten (their values are 0), else written as 0. `ring_state`
  // carries the input rows from one call to the next: a call starting where the last one ended
  // reads none of them again.
  template <class Out>
  void run(int y0, int y1, const Out& out, bool stream, std::uint8_t* lit_out,
           MatchedRing& ring_state) const {
    // The five input rows around the output row, split by parity: a ring, each row read once;
    // then the row sums v and c and the outputs, split too.
    const int half = half_;
    std::vector<float>& buffer = ring_state.buffer;
    // Per ring row and input block: whether a sample has light (all do without the level).
    std::vector<std::uint8_t>& lit = ring_state.lit;
    std::vector<std::uint8_t>& out_lit = ring_state.out_lit;
    const auto floats = static_cast<std::size_t>(2 * (5 + 2 + 2) * half + half);
    if (buffer.size() != floats || lit.size() != static_cast<std::size_t>(5 * blocks_)) {
      buffer.assign(floats, 0.f);  // the last half row: band values of blocks without light
      lit.assign(static_cast<std::size_t>(5 * blocks_), 1);
      out_lit.assign(static_cast<std::size_t>(out_blocks_), 1);
      ring_state.next_row = std::numeric_limits<int>::min();
    }
    auto slot = [&](int yy) { return (yy + 2 * kReach) % 5; };
    auto ring = [&](int yy) { return buffer.data() + slot(yy) * 2 * half; };
    float* v = buffer.data() + 10 * half;  // even half, then odd half
    float* c = v + 2 * half;
    float* out_even = c + 2 * half;
    float* out_odd = out_even + half;
    const float* zeros = out_odd + half;
    // The row padded by kReach columns each side, split by parity straight from the mosaic:
    // padded column p is the mosaic's p - kReach (kReach is even, so the parities agree),
    // mirrored without repeating the edge, which keeps the pattern (as the bilinear method). A
    // sample without signal becomes -INF, which every kernel sum carries to the band value (with
    // a saturated +INF sample: NaN, no reading); the band value then reads as dim.
    static_assert(kReach % 2 == 0, "the padded row's parities are the mosaic's");
    auto load = [&](int yy) {
      const float* src =
          mosaic_.ptr<float>(cv::borderInterpolate(yy, height_, cv::BORDER_REFLECT_101));
      float* even = ring(yy);
      float* odd = even + half;
      split_row(src, width_, no_signal_dn_, even + kReach / 2, odd + kReach / 2);
      auto edge = [&](float* half_row, int x) {
        const float value = src[cv::borderInterpolate(x, width_, cv::BORDER_REFLECT_101)];
        *half_row = value < no_signal_dn_ ? -std::numeric_limits<float>::infinity() : value;
      };
      // Padded column p is at (p odd ? odd : even)[p / 2].
      const auto at = [&](int p) { return (p & 1 ? odd : even) + p / 2; };
      for (int k = 1; k <= kReach; ++k) {
        edge(at(kReach - k), -k);
        edge(at(kReach + width_ - 1 + k), width_ - 1 + k);
      }
      if (!mark_no_signal_) return;
      std::uint8_t* row_lit = lit.data() + slot(yy) * blocks_;
      for (int k = 0; k < blocks_; ++k) {
        const int p0 = 2 * kBlock * k, p1 = std::min(padded_width_, p0 + 2 * kBlock);
        row_lit[k] =
            p0 < p1 && any_lit(even + p0 / 2, (p1 - p0 + 1) / 2, odd + p0 / 2, (p1 - p0) / 2);
      }
    };
    if (ring_state.next_row != y0 + kReach)
      for (int yy = y0 - kReach; yy < y0 + kReach; ++yy) load(yy);
    for (int y = y0; y < y1; ++y) {
      load(y + kReach);
      ring_state.next_row = y + kReach + 1;
      if (mark_no_signal_) {
        std::fill(out_lit.begin(), out_lit.end(), 0);
        for (int s = 0; s < 5; ++s) {
          const std::uint8_t* row_lit = lit.data() + s * blocks_;
          for (int k = 0; k < out_blocks_; ++k)
            out_lit[k] |= row_lit[k] | (k + 1 < blocks_ ? row_lit[k + 1] : 0);
        }
      }
      if (lit_out)
        std::copy(out_lit.begin(), out_lit.end(),
                  lit_out + static_cast<std::ptrdiff_t>(y - y0) * out_blocks_);
      const float *r0_even = ring(y), *r0_odd = r0_even + half;
      const float *v_even = v, *v_odd = v + half, *c_even = c, *c_odd = c + half;
      for (int k0 = 0; k0 < out_blocks_;) {
        int k1 = k0 + 1;
        while (k1 < out_blocks_ && out_lit[k1] == out_lit[k0]) ++k1;
        // Output pairs [i0, i1): columns [2 i0, x1).
        const int i0 = kBlock * k0, i1 = std::min(kBlock * k1, n_even_);
        const int x1 = std::min(2 * i1, width_);
        if (!out_lit[k0]) {
          if (!lit_out)
            for (int b = 0; b < 3; ++b)
              interleave(zeros, zeros, out(b, y) + 2 * i0, x1 - 2 * i0, true, stream);
          k0 = k1;
          continue;
        }
        const int sums = std::min(i1 + 2, half) - i0;  // the row sums' pairs the kernels read
        add_rows(ring(y - 1) + i0, ring(y + 1) + i0, v + i0, sums);
        add_rows(ring(y - 1) + half + i0, ring(y + 1) + half + i0, v + half + i0, sums);
        add_rows(ring(y - 2) + i0, ring(y + 2) + i0, c + i0, sums);
        add_rows(ring(y - 2) + half + i0, ring(y + 2) + half + i0, c + half + i0, sums);
        const int n_e = i1 - i0, n_o = std::max(0, std::min(i1, n_odd_) - i0);
        for (int b = 0; b < 3; ++b) {
          const auto& fn = rows_of_[b][y & 1];
          // Output column 2i: padded 2i + 2, so x - 2 is even[i] and x - 1 odd[i]; column
          // 2i + 1: padded 2i + 3, so x - 2 is odd[i] and x - 1 even[i + 1].
          fn[0](r0_even + i0, r0_odd + i0, v_even + i0, v_odd + i0, c_even + i0, c_odd + i0,
                out_even + i0, n_e);
          fn[1](r0_odd + i0, r0_even + 1 + i0, v_odd + i0, v_even + 1 + i0, c_odd + i0,
                c_even + 1 + i0, out_odd + i0, n_o);
          interleave(out_even + i0, out_odd + i0, out(b, y) + 2 * i0, x1 - 2 * i0, mark_no_signal_,
                     stream);
        }
        k0 = k1;
      }
    }
#if defined(__SSE2__)
    if (stream) _mm_sfence();  // the streamed rows are complete before another thread reads
#endif
  }

 private:
  const cv::Mat& mosaic_;
  float no_signal_dn_;
  bool mark_no_signal_ = false;
  std::array<std::array<std::array<RowFn, 2>, 2>, 3> rows_of_{};  // band, row, column parity
  int width_ = 0, height_ = 0, padded_width_ = 0, half_ = 0, n_even_ = 0, n_odd_ = 0;
  int blocks_ = 0, out_blocks_ = 0;
};

}  // namespace

void demosaic_matched_bayer(const cv::Mat& mosaic, const MosaicLayout& layout, float no_signal_dn,
                            std::vector<cv::Mat>& planes) {
  const MatchedBayer matched(mosaic, layout, no_signal_dn);
  // Planes larger than the caches go to memory before the next element reads them: storing
  // them past the cache saves reading each line in first (a 2048x2048 frame: 7 instead of
  // 12 CPU ms). Small ones stay in the cache for it.
  const bool stream = 3.0 * 4.0 * static_cast<double>(mosaic.total()) >= 16.0 * 1024 * 1024;
  const auto out = [&](int b, int y) { return planes[static_cast<std::size_t>(b)].ptr<float>(y); };
  if (static_cast<double>(mosaic.total()) < 512.0 * 512.0) {
    MatchedRing ring;
    matched.run(0, mosaic.rows, out, stream, nullptr, ring);
  } else {
    cv::parallel_for_(
        cv::Range(0, mosaic.rows),
        [&](const cv::Range& r) {
          MatchedRing ring;
          matched.run(r.start, r.end, out, stream, nullptr, ring);
        },
        2.0);
  }
}

int matched_bayer_blocks(int width) {
  return ((width + 1) / 2 + MatchedBayer::kBlock - 1) / MatchedBayer::kBlock;
}

struct MatchedBayerRows::State {
  State(const cv::Mat& mosaic, const MosaicLayout& layout, float no_signal_dn)
      : matched(mosaic, layout, no_signal_dn) {}
  MatchedBayer matched;
  MatchedRing ring;
};

MatchedBayerRows::MatchedBayerRows(const cv::Mat& mosaic, const MosaicLayout& layout,
                                   float no_signal_dn) {
  if (mosaic.type() != CV_32F || layout.kind != MosaicLayout::Kind::kBayer || mosaic.cols < 2 ||
      mosaic.rows < 2)
    throw InputError("matched demosaicking of rows takes a CV_32F Bayer mosaic of 2x2 or more");
  state_ = std::make_unique<State>(mosaic, layout, no_signal_dn);
  rows_ = mosaic.rows;
}

MatchedBayerRows::~MatchedBayerRows() = default;

void MatchedBayerRows::rows(int y0, int y1, std::vector<cv::Mat>& strip,
                            std::vector<std::uint8_t>& lit) {
  if (!(0 <= y0 && y0 <= y1 && y1 <= rows_))
    throw InputError("rows " + std::to_string(y0) + ".." + std::to_string(y1) +
                     " are not rows of a mosaic of " + std::to_string(rows_));
  const MatchedBayer& matched = state_->matched;
  strip.resize(3);
  for (cv::Mat& plane : strip) plane.create(y1 - y0, matched.width(), CV_32F);
  lit.resize(static_cast<std::size_t>(y1 - y0) * static_cast<std::size_t>(matched.out_blocks()));
  matched.run(
      y0, y1, [&](int b, int y) { return strip[static_cast<std::size_t>(b)].ptr<float>(y - y0); },
      false, lit.data(), state_->ring);
}

void demosaic_matched_bayer_rows(const cv::Mat& mosaic, const MosaicLayout& layout,
                                 float no_signal_dn, int y0, int y1, std::vector<cv::Mat>& strip,
                                 std::vector<std::uint8_t>& lit) {
  MatchedBayerRows(mosaic, layout, no_signal_dn).rows(y0, y1, strip, lit);
}

namespace {

// Weights at cell offsets -1, 0, +1 for a band whose samples lie `f` cells from the cell's
// centre (|f| <= 0.5): zero mean about the centre, variance kCellVariance (the least that keeps
// every weight non-negative at |f| = 0.5).
constexpr double kCellVariance = 0.25;
std::array<float, 3> registration_weights(double f) {
  return {static_cast<float>((kCellVariance + f * f + f) / 2),
          static_cast<float>(1 - kCellVariance - f * f),
          static_cast<float>((kCellVariance + f * f - f) / 2)};
}
// One row through 3 taps, the ends mirrored without repeating the edge; samples below
// `no_signal` count as -INF (NaN compares false and stays).
PYROCAM_VECTOR_CLONES
void taps_row(const float* __restrict in, float* __restrict out, int n, float w0, float w1,
              float w2, float no_signal) {
  constexpr float kMinusInf = -std::numeric_limits<float>::infinity();
  auto at = [&](int x) { return in[x] < no_signal ? kMinusInf : in[x]; };
  if (n == 1) {
    out[0] = at(0);
    return;
  }
  out[0] = w0 * at(1) + w1 * at(0) + w2 * at(1);
  for (int x = 1; x + 1 < n; ++x) out[x] = w0 * at(x - 1) + w1 * at(x) + w2 * at(x + 1);
  out[n - 1] = w0 * at(n - 2) + w1 * at(n - 1) + w2 * at(n - 2);
}

// out = w0 up + w1 mid + w2 down, -INF (a sample without light) as 0 (dim).
PYROCAM_VECTOR_CLONES
void taps_column(const float* __restrict up, const float* __restrict mid,
                 const float* __restrict down, float* __restrict out, int n, float w0, float w1,
                 float w2) {
  constexpr float kMinusInf = -std::numeric_limits<float>::infinity();
  for (int x = 0; x < n; ++x) {
    const float v = w0 * up[x] + w1 * mid[x] + w2 * down[x];
    out[x] = v == kMinusInf ? 0.f : v;
  }
}

}  // namespace

namespace {

// Where a band's samples sit in the cell, in cells from its centre (x, y); false for a band
// without samples.
bool band_offset(const MosaicLayout& layout, int band, double& x, double& y) {
  const int pw = layout.period_width, ph = layout.period_height;
  double sx = 0, sy = 0;
  int members = 0;
  for (int j = 0; j < ph; ++j)
    for (int i = 0; i < pw; ++i)
      if (layout.band_at(i, j) == band) sx += i, sy += j, ++members;
  if (members == 0) return false;
  x = (sx / members - (pw - 1) / 2.0) / pw;
  y = (sy / members - (ph - 1) / 2.0) / ph;
  return true;
}

}  // namespace

std::vector<double> snapshot_registration_variance(const MosaicLayout& layout) {
  std::vector<double> variance(static_cast<std::size_t>(layout.band_count()), 1.0);
  for (int b = 0; b < layout.band_count(); ++b) {
    double fx, fy;
    if (!band_offset(layout, b, fx, fy)) continue;
    double sx = 0, sy = 0;
    for (float w : registration_weights(fx)) sx += static_cast<double>(w) * w;
    for (float w : registration_weights(fy)) sy += static_cast<double>(w) * w;
    variance[static_cast<std::size_t>(b)] = sx * sy;
  }
  return variance;
}

void register_snapshot_bands(const MosaicLayout& layout, float no_signal_dn,
                             std::vector<cv::Mat>& planes) {
  const int bands = static_cast<int>(planes.size());
  cv::parallel_for_(cv::Range(0, bands), [&](const cv::Range& range) {
    cv::Mat across;  // the rows through the horizontal taps
    for (int b = range.start; b < range.end; ++b) {
      double fx, fy;
      if (!band_offset(layout, b, fx, fy)) continue;
      const auto wx = registration_weights(fx);
      const auto wy = registration_weights(fy);
      cv::Mat& plane = planes[static_cast<std::size_t>(b)];
      const int w = plane.cols, h = plane.rows;
      across.create(h, w, CV_32F);
      for (int y = 0; y < h; ++y)
        taps_row(plane.ptr<float>(y), across.ptr<float>(y), w, wx[0], wx[1], wx[2], no_signal_dn);
      // A band drawn from a sample without light (an edge to a dark background) reads as dim.
      for (int y = 0; y < h; ++y)
        taps_column(across.ptr<float>(cv::borderInterpolate(y - 1, h, cv::BORDER_REFLECT_101)),
                    across.ptr<float>(y),
                    across.ptr<float>(cv::borderInterpolate(y + 1, h, cv::BORDER_REFLECT_101)),
                    plane.ptr<float>(y), w, wy[0], wy[1], wy[2]);
    }
  });
}

}  // namespace pyrocam
