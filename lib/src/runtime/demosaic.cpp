#include "pyrocam/runtime/demosaic.h"

#include <algorithm>
#include <array>
#include <cstdint>

#include "detail/vector_clones.h"
#include "pyrocam/core/error.h"

namespace pyrocam {
namespace {

// How many samples of each band one mosaic period holds.
std::vector<int> band_members(const MosaicLayout& layout) {
  std::vector<int> members(static_cast<std::size_t>(layout.band_count()), 0);
  for (int b : layout.band_map) ++members[static_cast<std::size_t>(b)];
  return members;
}

void prepare_planes(std::vector<cv::Mat>& planes, int bands, cv::Size size) {
  planes.resize(static_cast<std::size_t>(bands));
  for (cv::Mat& p : planes) p.create(size, CV_32F);  // no-op when it already fits
}

// One sensor row's samples into the band rows they belong to: out[cx][x] = row[x * pw + cx]
// (one pass over the row, which stays in cache, instead of one strided pass per band).
PYROCAM_VECTOR_CLONES
void deinterleave_row(const float* __restrict row, int pw, int out_w, float* const* out) {
  if (pw == 5) {  // the snapshot cameras: four cells at a time, a 5 x 4 transpose in vectors
    typedef float Four __attribute__((vector_size(16), aligned(4), may_alias));
    float* __restrict o0 = out[0];
    float* __restrict o1 = out[1];
    float* __restrict o2 = out[2];
    float* __restrict o3 = out[3];
    float* __restrict o4 = out[4];
    const auto load = [](const float* at) { return *reinterpret_cast<const Four*>(at); };
    const auto store = [](float* at, Four v) { *reinterpret_cast<Four*>(at) = v; };
    int x = 0;
    for (; x + 4 <= out_w; x += 4) {
      const float* in = row + 5 * x;
      const Four v0 = load(in), v1 = load(in + 4), v2 = load(in + 8), v3 = load(in + 12),
                 v4 = load(in + 16);
      // Band k of cell c is sample 5c + k: vector (5c + k) / 4, lane (5c + k) % 4.
      store(o0 + x,
            __builtin_shufflevector(__builtin_shufflevector(v0, v1, 0, 5, 0, 0),
                                    __builtin_shufflevector(v2, v3, 2, 7, 0, 0), 0, 1, 4, 5));
      store(o1 + x,
            __builtin_shufflevector(__builtin_shufflevector(v0, v1, 1, 6, 0, 0),
                                    __builtin_shufflevector(v2, v4, 3, 4, 0, 0), 0, 1, 4, 5));
      store(o2 + x,
            __builtin_shufflevector(__builtin_shufflevector(v0, v1, 2, 7, 0, 0),
                                    __builtin_shufflevector(v3, v4, 0, 5, 0, 0), 0, 1, 4, 5));
      store(o3 + x,
            __builtin_shufflevector(__builtin_shufflevector(v0, v2, 3, 4, 0, 0),
                                    __builtin_shufflevector(v3, v4, 1, 6, 0, 0), 0, 1, 4, 5));
      store(o4 + x,
            __builtin_shufflevector(__builtin_shufflevector(v1, v2, 0, 5, 0, 0),
                                    __builtin_shufflevector(v3, v4, 2, 7, 0, 0), 0, 1, 4, 5));
    }
    for (; x < out_w; ++x) {
      const float* in = row + 5 * x;
      o0[x] = in[0], o1[x] = in[1], o2[x] = in[2], o3[x] = in[3], o4[x] = in[4];
    }
    return;
  }
  for (int x = 0; x < out_w; ++x)
    for (int cx = 0; cx < pw; ++cx) out[cx][x] = row[x * pw + cx];
}

// Each band is the mean of its pixels in each period cell; rows of cells in parallel.
void bin_cells(const cv::Mat& in, const MosaicLayout& layout, std::vector<cv::Mat>& planes) {
  const int pw = layout.period_width, ph = layout.period_height;
  const int bands = layout.band_count();
  const std::vector<int> members = band_members(layout);
  const bool one_each = std::all_of(members.begin(), members.end(), [](int m) { return m == 1; });
  const int out_w = planes[0].cols, out_h = planes[0].rows;
  auto rows = [&](const cv::Range& range) {
    std::vector<float*> out(static_cast<std::size_t>(pw));
    for (int y = range.start; y < range.end; ++y) {
      if (one_each) {  // a snapshot mosaic: every sample is its band's reading
        for (int cy = 0; cy < ph; ++cy) {
          for (int cx = 0; cx < pw; ++cx)
            out[static_cast<std::size_t>(cx)] =
                planes[static_cast<std::size_t>(
                           layout.band_map[static_cast<std::size_t>(cy * pw + cx)])]
                    .ptr<float>(y);
          deinterleave_row(in.ptr<float>(y * ph + cy), pw, out_w, out.data());
        }
        continue;
      }
      for (int b = 0; b < bands; ++b) {
        float* o = planes[static_cast<std::size_t>(b)].ptr<float>(y);
        const float scale = 1.0f / static_cast<float>(members[static_cast<std::size_t>(b)]);
        bool first = true;
        for (int cy = 0; cy < ph; ++cy) {
          const float* row = in.ptr<float>(y * ph + cy);
          for (int cx = 0; cx < pw; ++cx) {
            if (layout.band_map[static_cast<std::size_t>(cy * pw + cx)] != b) continue;
            const float* src = row + cx;
            if (first) {
              for (int x = 0; x < out_w; ++x) o[x] = src[x * pw];
              first = false;
            } else {
              for (int x = 0; x < out_w; ++x) o[x] += src[x * pw];
            }
          }
        }
        if (scale != 1.0f)
          for (int x = 0; x < out_w; ++x) o[x] *= scale;
      }
    }
  };
  if (static_cast<double>(in.total()) < 512.0 * 512.0)
    rows(cv::Range(0, out_h));
  else
    cv::parallel_for_(cv::Range(0, out_h), rows, 4.0);
}

// How a band is obtained at a pixel of a given parity.
enum class Op { kSelf, kHorizontal, kVertical, kDiagonal, kCross };

template <Op kOp>
inline float eval(const float* up, const float* mid, const float* down, int x) {
  switch (kOp) {
    case Op::kSelf:
      return mid[x];
    case Op::kHorizontal:
      return 0.5f * (mid[x - 1] + mid[x + 1]);
    case Op::kVertical:
      return 0.5f * (up[x] + down[x]);
    case Op::kDiagonal:
      return 0.25f * ((up[x - 1] + up[x + 1]) + (down[x - 1] + down[x + 1]));
    case Op::kCross:
      return 0.25f * ((up[x] + down[x]) + (mid[x - 1] + mid[x + 1]));
  }
  return 0.f;
}

// One output row of one band: even columns by kEven, odd ones by kOdd, in one contiguous pass.
template <Op kEven, Op kOdd>
void bilinear_row(const float* up, const float* mid, const float* down, float* o, int width) {
  int x = 0;
  for (; x + 1 < width; x += 2) {
    o[x] = eval<kEven>(up, mid, down, x);
    o[x + 1] = eval<kOdd>(up, mid, down, x + 1);
  }
  if (x < width) o[x] = eval<kEven>(up, mid, down, x);
}

using RowFn = void (*)(const float*, const float*, const float*, float*, int);

template <Op kEven>
RowFn row_fn(Op odd) {
  switch (odd) {
    case Op::kSelf:
      return bilinear_row<kEven, Op::kSelf>;
    case Op::kHorizontal:
      return bilinear_row<kEven, Op::kHorizontal>;
    case Op::kVertical:
      return bilinear_row<kEven, Op::kVertical>;
    case Op::kDiagonal:
      return bilinear_row<kEven, Op::kDiagonal>;
    case Op::kCross:
      return bilinear_row<kEven, Op::kCross>;
  }
  return nullptr;
}

RowFn row_fn(Op even, Op odd) {
  switch (even) {
    case Op::kSelf:
      return row_fn<Op::kSelf>(odd);
    case Op::kHorizontal:
      return row_fn<Op::kHorizontal>(odd);
    case Op::kVertical:
      return row_fn<Op::kVertical>(odd);
    case Op::kDiagonal:
      return row_fn<Op::kDiagonal>(odd);
    case Op::kCross:
      return row_fn<Op::kCross>(odd);
  }
  return nullptr;
}

// The same at column x of a row `width` wide, mirroring neighbours outside it (the first and last
// columns).
float eval_mirrored(Op op, const float* up, const float* mid, const float* down, int x, int width) {
  const int left = x == 0 ? 1 : x - 1, right = x == width - 1 ? width - 2 : x + 1;
  switch (op) {
    case Op::kSelf:
      return mid[x];
    case Op::kHorizontal:
      return 0.5f * (mid[left] + mid[right]);
    case Op::kVertical:
      return 0.5f * (up[x] + down[x]);
    case Op::kDiagonal:
      return 0.25f * ((up[left] + up[right]) + (down[left] + down[right]));
    case Op::kCross:
      return 0.25f * ((up[x] + down[x]) + (mid[left] + mid[right]));
  }
  return 0.f;
}

// Bilinear Bayer interpolation straight from the mosaic's rows: the inner loops cover the
// columns 2 .. width-3, which need no bounds checks, and the two columns on each side are done
// one by one with mirrored neighbours (rows above the first and below the last are mirrored by
// choosing the row). The operation of each band, row parity and column parity is fixed by the
// pattern and chosen once, outside the loops.
class BayerBilinear {
 public:
  explicit BayerBilinear(const MosaicLayout& layout) {
    for (int b = 0; b < 3; ++b)
      for (int py = 0; py < 2; ++py) {
        for (int px = 0; px < 2; ++px) ops_[b][py][px] = op_for(layout, b, px, py);
        rows_[b][py] = row_fn(ops_[b][py][0], ops_[b][py][1]);
      }
  }

  // Output rows [y0, y1) of a mosaic at least 2x2, calling `rows_done` (if any) after each
  // block of kBlockRows.
  void run(const cv::Mat& mosaic, std::vector<cv::Mat>& planes, int y0, int y1,
           const std::function<void(int, int)>* rows_done = nullptr) const {
    for (int b0 = y0; b0 < y1; b0 += kBlockRows) {
      const int b1 = std::min(b0 + kBlockRows, y1);
      run_rows(mosaic, planes, b0, b1);
      if (rows_done) (*rows_done)(b0, b1);
    }
  }

 private:
  // Small enough that the block's mosaic rows stay in cache for rows_done (18 rows of a
  // 2048-pixel float mosaic: 144 KiB).
  static constexpr int kBlockRows = 16;

  void run_rows(const cv::Mat& mosaic, std::vector<cv::Mat>& planes, int y0, int y1) const {
    const int width = mosaic.cols, height = mosaic.rows;
    // Mirrored without repeating the edge.
    auto row = [&](int y) {
      return mosaic.ptr<float>(y < 0 ? -y : y >= height ? 2 * height - 2 - y : y);
    };
    const int inner_end = width >= 6 ? width - 2 : 0;  // inner columns [2, inner_end)
    for (int y = y0; y < y1; ++y) {
      const float* up = row(y - 1);
      const float* mid = row(y);
      const float* down = row(y + 1);
      for (int b = 0; b < 3; ++b) {
        float* out = planes[static_cast<std::size_t>(b)].ptr<float>(y);
        const auto& ops = ops_[b][y & 1];
        if (inner_end) rows_[b][y & 1](up + 2, mid + 2, down + 2, out + 2, inner_end - 2);
        for (int x = 0; x < width; ++x) {
          if (x == 2 && inner_end) x = inner_end;
          out[x] = eval_mirrored(ops[x & 1], up, mid, down, x, width);
        }
      }
    }
  }

  static Op op_for(const MosaicLayout& layout, int band, int px, int py) {
    auto is = [&](int x, int y) { return layout.band_at(x & 1, y & 1) == band; };
    if (is(px, py)) return Op::kSelf;
    if (is(px + 1, py)) return is(px, py + 1) ? Op::kCross : Op::kHorizontal;
    if (is(px, py + 1)) return Op::kVertical;
    return Op::kDiagonal;
  }

  std::array<std::array<RowFn, 2>, 3> rows_{};
  std::array<std::array<std::array<Op, 2>, 2>, 3> ops_{};  // band, row parity, column parity
};

}  // namespace

DemosaicMethod parse_demosaic_method(const std::string& name) {
  if (name == "bilinear") return DemosaicMethod::kBilinear;
  if (name == "bin2x2") return DemosaicMethod::kBinCells;
  if (name == "matched") return DemosaicMethod::kMatched;
  if (name == "auto") return DemosaicMethod::kAuto;
  throw InputError("unknown demosaic method '" + name +
                   "' (use bilinear, bin2x2, matched or auto)");
}

const char* demosaic_method_name(DemosaicMethod method) {
  switch (method) {
    case DemosaicMethod::kBilinear:
      return "bilinear";
    case DemosaicMethod::kBinCells:
      return "bin2x2";
    case DemosaicMethod::kMatched:
      return "matched";
    case DemosaicMethod::kAuto:
      break;
  }
  return "auto";
}

DemosaicMethod resolve_demosaic_method(DemosaicMethod method, const MosaicLayout& /*layout*/) {
  if (method != DemosaicMethod::kAuto) return method;
  return DemosaicMethod::kMatched;
}

cv::Size demosaic_output_size(const MosaicLayout& layout, DemosaicMethod method, cv::Size input) {
  method = resolve_demosaic_method(method, layout);
  if (method != DemosaicMethod::kBinCells && layout.kind == MosaicLayout::Kind::kBayer)
    return input;
  return {input.width / layout.period_width, input.height / layout.period_height};
}

int demosaic_sample_reach(const MosaicLayout& layout, DemosaicMethod method) {
  method = resolve_demosaic_method(method, layout);
  const bool bayer = layout.kind == MosaicLayout::Kind::kBayer;
  if (method == DemosaicMethod::kMatched) return bayer ? 25 : 9;
  return method == DemosaicMethod::kBilinear && bayer ? 9 : 1;  // snapshots bin otherwise
}

DemosaicNoise demosaic_noise(const MosaicLayout& layout, DemosaicMethod method) {
  method = resolve_demosaic_method(method, layout);
  const int bands = layout.band_count(), pw = layout.period_width, ph = layout.period_height;
  DemosaicNoise noise;
  noise.bands = bands;
  const std::vector<int> members = band_members(layout);
  if (layout.kind == MosaicLayout::Kind::kBayer && method != DemosaicMethod::kBinCells) {
    // By how the band is obtained at the pixel (Op above; demosaic_matched.cpp's kernels): its
    // own sample (R or B, or G, whose matched kernel also takes its diagonals), the two nearest
    // along a row or a column, the four diagonals, G's four cross neighbours.
    const bool matched = method == DemosaicMethod::kMatched;
    const double self_rb = matched ? 0.5 * 0.5 + 4 * 0.125 * 0.125 : 1;
    const double self_g =
        matched ? (2. / 9) * (2. / 9) + 4 * (5. / 36) * (5. / 36) + 4 * (1. / 18) * (1. / 18) : 1;
    const double axial = matched ? 2 * 0.375 * 0.375 + 4 * 0.0625 * 0.0625 : 2 * 0.5 * 0.5;
    const double diagonal = 4 * 0.25 * 0.25;
    const double cross = matched ? 4 * 0.1875 * 0.1875 + 8 * 0.03125 * 0.03125 : 4 * 0.25 * 0.25;
    noise.period_width = pw, noise.period_height = ph;
    for (int y = 0; y < ph; ++y)
      for (int x = 0; x < pw; ++x) {
        const int own = layout.band_at(x, y);
        const bool own_green = members[static_cast<std::size_t>(own)] == 2;
        for (int b = 0; b < bands; ++b) {
          const bool green = members[static_cast<std::size_t>(b)] == 2;
          noise.factor.push_back(b == own    ? (green ? self_g : self_rb)
                                 : own_green ? axial
                                 : green     ? cross
                                             : diagonal);
        }
      }
    return noise;
  }
  // Binned: the mean of the band's members in the cell; matched snapshot cells then interpolate.
  const std::vector<double> registration = method == DemosaicMethod::kMatched
                                               ? snapshot_registration_variance(layout)
                                               : std::vector<double>(members.size(), 1.0);
  for (int b = 0; b < bands; ++b) {
    const auto i = static_cast<std::size_t>(b);
    noise.factor.push_back(registration[i] / std::max(members[i], 1));
  }
  return noise;
}

double demosaic_noise_area(const MosaicLayout& layout, DemosaicMethod method) {
  const DemosaicNoise noise = demosaic_noise(layout, method);
  const int phases = noise.period_width * noise.period_height;
  // Output pixels per mosaic period: every pixel of it, or one for a cell.
  const bool per_pixel = layout.kind == MosaicLayout::Kind::kBayer &&
                         resolve_demosaic_method(method, layout) != DemosaicMethod::kBinCells;
  const double outputs = per_pixel ? layout.period_width * layout.period_height : 1;
  const std::vector<int> members = band_members(layout);
  double spread = 0, factors = 0;
  for (int b = 0; b < noise.bands; ++b) {
    const auto i = static_cast<std::size_t>(b);
    if (members[i] == 0) continue;
    spread += outputs / members[i];
    double mean_factor = 0;
    for (int phase = 0; phase < phases; ++phase)
      mean_factor += noise.factor.empty()
                         ? 1
                         : noise.factor[static_cast<std::size_t>(phase * noise.bands + b)];
    factors += mean_factor / phases;
  }
  return factors > 0 ? std::max(1.0, spread / factors) : 1.0;
}

void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes, float no_signal_dn) {
  demosaic(mosaic, layout, method, planes, no_signal_dn, {});
}

void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes, float no_signal_dn,
              const std::function<void(int, int)>& rows_done) {
  if (mosaic.type() != CV_32F) throw InputError("demosaic: the mosaic must be CV_32F");
  if (mosaic.cols < layout.period_width || mosaic.rows < layout.period_height)
    throw InputError("demosaic: a " + std::to_string(mosaic.cols) + "x" +
                     std::to_string(mosaic.rows) + " mosaic is smaller than one " + layout.pattern +
                     " period");
  method = resolve_demosaic_method(method, layout);
  const cv::Size out_size = demosaic_output_size(layout, method, mosaic.size());
  prepare_planes(planes, layout.band_count(), out_size);
  const auto all_done = [&] {
    if (rows_done) rows_done(0, out_size.height);
  };
  if (method == DemosaicMethod::kMatched && layout.kind != MosaicLayout::Kind::kBayer) {
    bin_cells(mosaic, layout, planes);
    register_snapshot_bands(layout, no_signal_dn, planes);
    all_done();
    return;
  }
  if (method == DemosaicMethod::kBinCells || layout.kind != MosaicLayout::Kind::kBayer) {
    bin_cells(mosaic, layout, planes);
    all_done();
    return;
  }
  if (method == DemosaicMethod::kMatched) {
    demosaic_matched_bayer(mosaic, layout, no_signal_dn, planes);
    all_done();
    return;
  }
  const BayerBilinear bilinear(layout);
  const int height = mosaic.rows;
  const std::function<void(int, int)>* done = rows_done ? &rows_done : nullptr;
  if (static_cast<double>(mosaic.total()) < 512.0 * 512.0) {
    bilinear.run(mosaic, planes, 0, height, done);
    return;
  }
  cv::parallel_for_(
      cv::Range(0, height),
      [&](const cv::Range& r) { bilinear.run(mosaic, planes, r.start, r.end, done); }, 2.0);
}

}  // namespace pyrocam
