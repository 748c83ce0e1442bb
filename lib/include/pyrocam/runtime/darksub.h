// Dark-frame subtraction with saturation marking: the first step from raw camera gray values to
// signals (METHOD.md section 3 and 5). The result is float32 DN; a pixel whose raw value reached
// the saturation level (before subtraction) is +INFINITY, a pixel without a reading NaN.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <string>

#include "pyrocam/core/noise_model.h"

namespace pyrocam {

// The largest raw value of a bit depth: 2^bits - 1.
int full_scale_dn(int bit_depth);
// The default saturation level: 220/255 of the full scale (the paper's 220 of 255 for 8 bits),
// rounded. Throws InputError for a bit depth outside 1..16.
double default_saturation_level(int bit_depth);

// The samples a subtraction marked saturated: how many, the smallest rectangle holding them
// (empty when none), and which tiles of a kSaturationTiles x kSaturationTiles grid over the
// frame hold any (two far-apart spots span a rectangle between them that holds none).
inline constexpr int kSaturationTiles = 64;
struct SaturatedSamples {
  std::size_t count = 0;
  cv::Rect bounds;
  std::array<std::uint64_t, kSaturationTiles> tiles{};  // [tile row]: bit = tile column
};
// The tile column (row) of sample column x (row y) of a frame `size` samples wide (high).
inline int saturation_tile_of(int x, int size) {
  return static_cast<int>(static_cast<std::int64_t>(x) * kSaturationTiles / size);
}
// The samples of tile (row, column) of a width x height frame.
inline cv::Rect saturation_tile_rect(int row, int column, int width, int height) {
  const auto first = [](int tile, int size) {
    return static_cast<int>((static_cast<std::int64_t>(tile) * size + kSaturationTiles - 1) /
                            kSaturationTiles);
  };
  return cv::Rect(cv::Point(first(column, width), first(row, height)),
                  cv::Point(first(column + 1, width), first(row + 1, height)));
}

// out = raw - dark per pixel as CV_32F, with +INF where raw >= saturation_level. raw is CV_8U or
// CV_16U (any stride), dark CV_32F of the same size (a NaN in the dark gives NaN). out is
// (re)allocated only if its size or type differs, so it may wrap a caller's buffer. Throws
// InputError on a size or type mismatch naming both sizes.
SaturatedSamples subtract_dark(const cv::Mat& raw, const cv::Mat& dark, double saturation_level,
                               cv::Mat& out);

// The same with a constant dark level (no dark frame to read: less memory traffic).
SaturatedSamples subtract_dark_level(const cv::Mat& raw, double level_dn, double saturation_level,
                                     cv::Mat& out);

// The saturated (+INF) samples of a CV_32F dark-subtracted mosaic, e.g. after fusing a bracket.
// Throws InputError for another type.
SaturatedSamples find_saturated(const cv::Mat& signal);

// Evidence on the phase of a Bayer mosaic: the sums of each place of the 2x2 cell over lit cells
// (no sample saturated or NaN, the cell's mean at least `lit_dn`) inside a body (the cells left,
// right and below within 20 % of the cell's sum: an edge lights a cell's columns or rows
// unequally) of every `cell_row_step`-th row of cells from `first_cell_row` (0 to the step less
// one), in a CV_32F dark-subtracted mosaic whose cells start at (0, 0); and per diagonal of the
// cell, how many of those cells have the diagonal's two samples at least `bright_dn` on average,
// and how many of these differ by more than 12 % of their mean plus 2 standard deviations of
// their difference's noise (`noise`, the noisiest band's: at a high analogue gain few electrons
// make 20 % of full scale; where samples behind one filter, 10 pixels apart inside a body,
// scatter more than it says, as at a gain it does not know, by their measured scatter). Adds to
// `sums`; stops after `max_cells` lit cells (a bright plate has tens of thousands a frame, and
// judging them all cost 8 ms of a 2048x2048 frame).
struct BayerCellSums {
  double at[2][2] = {};  // [row][column] in the cell
  std::size_t cells = 0;
  // [0]: the diagonal (0,0)-(1,1); [1]: the anti-diagonal (0,1)-(1,0).
  std::size_t bright[2] = {}, apart[2] = {};
};
void add_bayer_cell_sums(const cv::Mat& signal, float lit_dn, float bright_dn, int first_cell_row,
                         int cell_row_step, const SignalNoise& noise, BayerCellSums& sums,
                         std::size_t max_cells = std::numeric_limits<std::size_t>::max());
// Whether the sums say that the greens sit on the other diagonal of the cell than `pattern`
// (rggb, bggr, grbg or gbrg) puts them: the pattern's two green places differ by more than 10 %
// while the other two agree within 3 %. Samples behind one filter agree (a sensor's green
// imbalance is a percent or two); a red and a blue one do not on a glowing body (the colour
// camera's blue, mostly its near-infrared leak there, reads 24 % above its red at 800 degC). So the
// mosaic was shifted by one row or one column (a crop at the top or left by an odd number of
// pixels), and read as it is its temperatures look right and are wrong. (A shift by both, or a
// flip, which trades red for blue, keeps the greens in place and is not seen.) False for another
// pattern or sums that tell nothing.
bool bayer_greens_elsewhere(const BayerCellSums& sums, const std::string& pattern);
// Whether the sums say that the frames are no Bayer mosaic of `pattern`: in more than a quarter
// of at least 64 bright cells, the two samples where the pattern puts its greens are apart (12 %
// of their mean plus 2 noise standard deviations). Two samples behind one filter, a pixel apart
// inside a body, differ by their noise and a sensor's green imbalance (a percent or two): a
// cell is apart with the probability of normal noise beyond 2 sigma, 4.6 %, and more than a
// quarter of 64 such cells then has a probability below 1e-6 (binomial). Neighbours on a snapshot
// mosaic (5x5: 25 filters, no two neighbours alike) differ by tens of percent:
// 63-100 % of cells on the simulated cameras' plates at 700-2500 degC. Read as a Bayer mosaic,
// such frames give temperatures that look right and are wrong. False for another pattern or
// too few cells.
bool bayer_greens_disagree(const BayerCellSums& sums, const std::string& pattern);

// Converts a dark image read from a file (CV_8U/CV_16U) to the CV_32F dark subtract_dark takes.
cv::Mat dark_from_image(const cv::Mat& image);

// Averages raw frames into a dark frame (lens cap on). All frames must have the size of the first.
class DarkAccumulator {
 public:
  void reset();
  // Adds one CV_8U/CV_16U frame; throws InputError if its size differs from the first frame's.
  void add(const cv::Mat& raw);
  int count() const { return count_; }
  // Mean of the frames added so far as CV_32F; throws InputError when none was added.
  cv::Mat mean() const;

 private:
  cv::Mat sum_;  // CV_64F
  int count_ = 0;
};

}  // namespace pyrocam
