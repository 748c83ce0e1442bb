#include "pyrocam/demosaic.h"

#include <array>

#include "pyrocam/spectrum.h"

namespace pyrocam {
namespace {

void prepare_planes(std::vector<cv::Mat>& planes, int bands, cv::Size size) {
  planes.resize(static_cast<std::size_t>(bands));
  for (cv::Mat& p : planes) p.create(size, CV_32F);  // no-op when it already fits
}

// Each band is the mean of its pixels in each period cell.
void bin_cells(const cv::Mat& in, const MosaicLayout& layout, std::vector<cv::Mat>& planes) {
  const int pw = layout.period_width, ph = layout.period_height;
  const int bands = layout.band_count();
  std::vector<int> members(static_cast<std::size_t>(bands), 0);
  for (int b : layout.band_map) ++members[static_cast<std::size_t>(b)];
  const int out_w = planes[0].cols, out_h = planes[0].rows;
  for (int y = 0; y < out_h; ++y) {
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
}

// How a band is obtained at a pixel of a given parity.
enum class Op { kSelf, kHorizontal, kVertical, kDiagonal, kCross };

// Bilinear Bayer interpolation over a padded copy (1 pixel mirrored border) so that the inner
// loops need no bounds checks.
class BayerBilinear {
 public:
  explicit BayerBilinear(const MosaicLayout& layout) {
    for (int b = 0; b < 3; ++b)
      for (int py = 0; py < 2; ++py)
        for (int px = 0; px < 2; ++px) ops_[b][py][px] = op_for(layout, b, px, py);
  }

  void run(const cv::Mat& padded, std::vector<cv::Mat>& planes, int y0, int y1) const {
    const int width = planes[0].cols;
    for (int y = y0; y < y1; ++y) {
      const float* up = padded.ptr<float>(y) + 1;
      const float* mid = padded.ptr<float>(y + 1) + 1;
      const float* down = padded.ptr<float>(y + 2) + 1;
      for (int b = 0; b < 3; ++b) {
        float* o = planes[static_cast<std::size_t>(b)].ptr<float>(y);
        for (int px = 0; px < 2; ++px) {
          switch (ops_[b][y & 1][px]) {
            case Op::kSelf:
              for (int x = px; x < width; x += 2) o[x] = mid[x];
              break;
            case Op::kHorizontal:
              for (int x = px; x < width; x += 2) o[x] = 0.5f * (mid[x - 1] + mid[x + 1]);
              break;
            case Op::kVertical:
              for (int x = px; x < width; x += 2) o[x] = 0.5f * (up[x] + down[x]);
              break;
            case Op::kDiagonal:
              for (int x = px; x < width; x += 2)
                o[x] = 0.25f * ((up[x - 1] + up[x + 1]) + (down[x - 1] + down[x + 1]));
              break;
            case Op::kCross:
              for (int x = px; x < width; x += 2)
                o[x] = 0.25f * ((up[x] + down[x]) + (mid[x - 1] + mid[x + 1]));
              break;
          }
        }
      }
    }
  }

 private:
  static Op op_for(const MosaicLayout& layout, int band, int px, int py) {
    auto is = [&](int x, int y) { return layout.band_at(x & 1, y & 1) == band; };
    if (is(px, py)) return Op::kSelf;
    if (is(px + 1, py)) return is(px, py + 1) ? Op::kCross : Op::kHorizontal;
    if (is(px, py + 1)) return Op::kVertical;
    return Op::kDiagonal;
  }

  std::array<std::array<std::array<Op, 2>, 2>, 3> ops_{};
};

}  // namespace

DemosaicMethod parse_demosaic_method(const std::string& name) {
  if (name == "bilinear") return DemosaicMethod::kBilinear;
  if (name == "bin2x2") return DemosaicMethod::kBinCells;
  throw InputError("unknown demosaic method '" + name + "' (use bilinear or bin2x2)");
}

cv::Size demosaic_output_size(const MosaicLayout& layout, DemosaicMethod method, cv::Size input) {
  if (method == DemosaicMethod::kBilinear && layout.kind == MosaicLayout::Kind::kBayer)
    return input;
  return {input.width / layout.period_width, input.height / layout.period_height};
}

void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes) {
  if (mosaic.type() != CV_32F) throw InputError("demosaic: the mosaic must be CV_32F");
  if (mosaic.cols < layout.period_width || mosaic.rows < layout.period_height)
    throw InputError("demosaic: a " + std::to_string(mosaic.cols) + "x" +
                     std::to_string(mosaic.rows) + " mosaic is smaller than one " + layout.pattern +
                     " period");
  const cv::Size out_size = demosaic_output_size(layout, method, mosaic.size());
  prepare_planes(planes, layout.band_count(), out_size);
  if (method == DemosaicMethod::kBinCells || layout.kind != MosaicLayout::Kind::kBayer) {
    bin_cells(mosaic, layout, planes);
    return;
  }
  // thread_local: no allocation per frame once the size is known.
  thread_local cv::Mat padded;
  cv::copyMakeBorder(mosaic, padded, 1, 1, 1, 1, cv::BORDER_REFLECT_101);
  const BayerBilinear bilinear(layout);
  const int height = mosaic.rows;
  if (static_cast<double>(mosaic.total()) < 512.0 * 512.0) {
    bilinear.run(padded, planes, 0, height);
    return;
  }
  const cv::Mat& src = padded;
  cv::parallel_for_(
      cv::Range(0, height), [&](const cv::Range& r) { bilinear.run(src, planes, r.start, r.end); },
      2.0);
}

}  // namespace pyrocam
