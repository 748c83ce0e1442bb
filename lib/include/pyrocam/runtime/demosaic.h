// From a dark-subtracted mosaic (CV_32F, one value per sensor pixel) to band planes.
//
// Marks propagate by IEEE arithmetic: a band value computed from any +INF (saturated) input is
// +INF, from any NaN input NaN (NaN wins over +INF), because every output is a mean of inputs
// with positive weights.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "pyrocam/core/mosaic.h"

namespace pyrocam {

enum class DemosaicMethod {
  // Bayer: full resolution; the missing bands at each pixel are the mean of the nearest pixels
  // of that band (2 horizontal or vertical, or 4 diagonal for R/B; 4 cross neighbours for G).
  // Borders are mirrored without repeating the edge pixel, which keeps the pattern. Snapshot
  // mosaics: as kBinCells.
  kBilinear,
  // One reading per mosaic period (macro-pixel): each band is the mean of the pixels of that
  // band in the cell. Bayer: half resolution, R, mean of both G, B per 2x2 cell. Snapshot
  // mosaics: one reading per macro-pixel, each band where it sits in the cell (as the paper).
  kBinCells,
  // Every band of every output pixel through a symmetric kernel of the same spread, so that on
  // a curved signal (a hot spot) the bands' interpolation errors cancel in their ratio instead
  // of shifting it, and in a gradient a snapshot cell's bands are read at one place (see
  // demosaic_matched.cpp). Bayer: full resolution, 5x5 footprint, second moment 1 pixel^2 along
  // each axis. Snapshot: one reading per macro-pixel, each band binned and then interpolated to
  // the cell's centre over 3x3 cells, variance 0.25 cell^2 along each axis. Marks spread over
  // the larger footprint.
  kMatched,
  // kMatched, for snapshot mosaics (it costs little there and reads their melt pools) and for
  // Bayer: bilinear's extra readings on small pools and steep sides are largely wild (the
  // simulated pool at 160x120: 52 % of them more than 150 degC off, against 1.4 % with
  // kMatched), so a pool a few pixels across has few readings, but right ones.
  kAuto,
};

// The method `method` stands for on `layout` (kAuto resolved; the others as they are).
DemosaicMethod resolve_demosaic_method(DemosaicMethod method, const MosaicLayout& layout);

// "bilinear", "bin2x2", "matched", "auto".
DemosaicMethod parse_demosaic_method(const std::string& name);
// The name parse_demosaic_method takes for `method`.
const char* demosaic_method_name(DemosaicMethod method);

// Output plane size: the input size for bilinear, else floor(input / period) (pixels of an
// incomplete trailing cell are dropped).
cv::Size demosaic_output_size(const MosaicLayout& layout, DemosaicMethod method, cv::Size input);

// How many output pixels one mosaic sample reaches at most (its noise is shared by that many
// readings): 25 for matched Bayer (5x5 kernels), 9 for bilinear Bayer (3x3) and for matched
// snapshot cells (3x3 cells), 1 for binning (and snapshots with any other method, which bin).
int demosaic_sample_reach(const MosaicLayout& layout, DemosaicMethod method);

// What demosaicking does to the noise of each band value: the variance of the value relative
// to that of one sample at the same signal (the sum of its kernel's squared weights, over the
// band's members in a cell where it bins them), by where the output pixel sits in the mosaic's
// period. A reading's uncertainty (uncertainty.h) scales each band's sample variance by it:
// matched Bayer demosaicking averages every band over several samples (0.14-0.31), bilinear the
// bands it interpolates (0.25-0.5), matched snapshot cells over 3x3 cells.
struct DemosaicNoise {
  int period_width = 1, period_height = 1, bands = 0;
  std::vector<double> factor;  // per phase (y * period_width + x), the bands' factors; empty: 1
  // The factors of the output pixel (x, y), or nullptr where every band's is 1.
  const double* at(int x, int y) const {
    if (factor.empty()) return nullptr;
    const auto phase =
        static_cast<std::size_t>((y % period_height) * period_width + x % period_width);
    return &factor[phase * static_cast<std::size_t>(bands)];
  }
};
DemosaicNoise demosaic_noise(const MosaicLayout& layout, DemosaicMethod method);

// The area (in output pixels) that one reading's noise is spread over, for the noise of a
// region's statistics. A band value weighs its samples with weights whose squares sum to its
// factor above, and the readings a sample feeds weigh it 1 / (its band's density) in all, so a
// region much larger than the kernels is worth that many times fewer independent readings than
// it has pixels: per band 1 / (density x mean factor); the bands combined as if each added
// equally to a reading's noise, sum(1 / density) / sum(mean factor). 1 for binning, 13.9 for
// matched Bayer, 5.7 for bilinear Bayer, 3.3 for matched snapshot cells (nir5x5-reference).
double demosaic_noise_area(const MosaicLayout& layout, DemosaicMethod method);

// Fills one CV_32F plane per band (plane index = the layout's band index: R, G, B for Bayer).
// `planes` may wrap a caller's buffer: planes of the right size and type are written in place,
// others are (re)allocated. Snapshot layouts are always binned. Throws InputError if the mosaic
// is not CV_32F or is smaller than one period.
// kMatched only: a finite band value computed from any sample below `no_signal_dn` (see
// no_signal_level_dn) is 0, so it reads as dim: at an edge to a cold background its kernel
// mixes lit and unlit samples into a ratio of no temperature.
void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes,
              float no_signal_dn = -std::numeric_limits<float>::infinity());

// The same, calling `rows_done(y0, y1)` once output rows [y0, y1) are written, from the thread
// that wrote them: for bilinear Bayer in blocks of a few rows, while the mosaic rows around
// them are still in cache (mark_mixed_pixels' pass, fused); for the other methods once, for
// all rows.
void demosaic(const cv::Mat& mosaic, const MosaicLayout& layout, DemosaicMethod method,
              std::vector<cv::Mat>& planes, float no_signal_dn,
              const std::function<void(int, int)>& rows_done);

// The mosaic samples (offsets from the pixel) that kMatched draws band `band` from at a pixel
// of column parity px and row parity py: its footprint, for the mixed-pixel check.
std::vector<cv::Point> matched_footprint(const MosaicLayout& layout, int band, int px, int py);

// kMatched for a snapshot layout, after binning: each band plane (cells) is interpolated to the
// cells' centres with separable 3x3-cell weights of zero mean and the same variance (0.25
// cell^2 along each axis) whatever the band's place in the cell (no checks: see demosaic).
void register_snapshot_bands(const MosaicLayout& layout, float no_signal_dn,
                             std::vector<cv::Mat>& planes);
// The sum of the squared weights register_snapshot_bands gives each band (what it does to the
// noise of a band value).
std::vector<double> snapshot_registration_variance(const MosaicLayout& layout);

// kMatched for a Bayer layout, into planes of the mosaic's size (no checks: see demosaic).
void demosaic_matched_bayer(const cv::Mat& mosaic, const MosaicLayout& layout, float dim_dn,
                            std::vector<cv::Mat>& planes);

// The fused path (demosaic25 linked to ratiotemp): kMatched Bayer demosaicking a strip of rows
// at a time, so that the band planes never leave the cache. Output rows [y0, y1) of
// demosaic_matched_bayer's planes, the same values bit for bit, into `strip` (three planes of
// y1 - y0 rows, (re)allocated when their size differs), and in `lit`, per row and block of
// kMatchedBlockColumns columns (matched_bayer_blocks(width) a row), 0 where every sample its
// kernels can reach is below `no_signal_dn` (within two rows, from two columns left of the block
// to the end of the next block), else 1. A block flagged 0 is left unwritten in `strip`: its
// band values are all 0 (dim).
// Throws InputError for a mosaic that is not a CV_32F Bayer mosaic of 2x2 or more, or rows
// outside it.
inline constexpr int kMatchedBlockColumns = 64;
int matched_bayer_blocks(int width);
void demosaic_matched_bayer_rows(const cv::Mat& mosaic, const MosaicLayout& layout,
                                 float no_signal_dn, int y0, int y1, std::vector<cv::Mat>& strip,
                                 std::vector<std::uint8_t>& lit);

// The same, strip after strip of one mosaic (which must outlive it): a strip that starts where
// the last one ended reads none of the mosaic's rows again (the kernels reach two rows each
// way, a fifth of a 16-row strip's reading).
class MatchedBayerRows {
 public:
  MatchedBayerRows(const cv::Mat& mosaic, const MosaicLayout& layout, float no_signal_dn);
  ~MatchedBayerRows();
  MatchedBayerRows(const MatchedBayerRows&) = delete;
  MatchedBayerRows& operator=(const MatchedBayerRows&) = delete;
  void rows(int y0, int y1, std::vector<cv::Mat>& strip, std::vector<std::uint8_t>& lit);

 private:
  struct State;
  std::unique_ptr<State> state_;
  int rows_ = 0;
};

}  // namespace pyrocam
