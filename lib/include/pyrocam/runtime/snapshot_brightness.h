// Ratio-scaled brightness readings for snapshot (5x5) band planes.
//
// The same idea as scaled_brightness.h for Bayer mosaics, on a camera whose every cell has all
// its bands. A band's log signal is its scale plus the model's log rate at the temperature:
// log s_b = e_b + log m_b(T), e_b holding the exposure, the geometry, the emissivity and the
// band's calibration. Where the likelihood fit reads a cell, it gives e_b = log s_b - log m_b(T)
// for each band that reads there. Those scales, averaged over a window of (2r + 1) x (2r + 1)
// cells per band, are the cell's; its temperature is then the one whose log rates, moved by
// them, fit its bands' log signals best (least squares weighed by each log signal's inverse
// variance, Gauss-Newton from the fit's reading). That reading needs no ratio: the noise of a
// cell's 25 bands moves it by a few tenths of a degree where the ratio's moves it by tens, and
// what is left is the mean of the window's ratio errors, which fall with the window's area.
//
// The assumption is the ratio's own, on a larger scale: the emissivity (and the spectral shape of
// the light) is the same over the window. Across an emissivity step inside the window the cells
// near it read biased by the step's share of the window's mean, where the ratio itself reads
// right: which is why it is off by default.
//
// A cell keeps the fit's reading mask: it reads only where the fit read. It keeps the fit's
// reading where no band's scale is known over its window, or where the brightness reading would
// leave the model's range.
//
// Measured (simulated 5x5 camera, its true QE, likelihood fit with partial bands, matched
// demosaicking, radius 2; tests/lib and the targets suite): on plates a third of the fit's
// spread, the same mean; parabolic melt pools with peaks of 1500-2500 degC exposed for the peak,
// the core's median within 10 degC of the truth in 39 of 40 frames (37 with the fit's readings).
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "pyrocam/core/profile.h"

namespace pyrocam {

struct ThermalModel;

class SnapshotBrightness {
 public:
  static constexpr int kMaxWindowRadius = 8;  // cells: a 17 x 17 cell window

  // For the model's snapshot camera, window radius r in cells (1..kMaxWindowRadius). Throws
  // InputError for a Bayer camera, a radius out of range, or a band whose modelled signal does
  // not rise over the model's range.
  SnapshotBrightness(const ThermalModel& model, int window_radius);

  // The analogue gain the frames were taken with, as a factor (analogue_gain_factor): it scales
  // each sample's shot noise and noise floor in DN, which weigh the bands. 1 until set.
  void set_analogue_gain(double factor);

  int window_radius() const { return radius_; }
  int window_cells() const { return 2 * radius_ + 1; }  // side of the window, cells

  // In place. `planes`: the band planes the readings were made from, one per model band, CV_32F
  // (+INF saturated, NaN no reading), as demosaic25 gives them; `temperature_c`: CV_32F degC
  // (NaN: no reading) of the planes' size. Throws InputError on a band count, size or type that
  // does not match.
  void apply(const std::vector<cv::Mat>& planes, cv::Mat& temperature_c);
  // The same on CV_16U 0.1 K codes (0: no reading), as ratiotemp writes them.
  void apply_codes(const std::vector<cv::Mat>& planes, cv::Mat& codes);

 private:
  void check(const std::vector<cv::Mat>& planes, const cv::Mat& readings, int type) const;

  int radius_ = 2;
  CameraProfile profile_;
  double gain_ = 1;
  double dim_dn_ = 0;
  double min_c_ = 0, max_c_ = 0;
  std::vector<std::vector<float>> log_rate_;   // per band, per degC from min_c_
  std::vector<double> shot_gain_, floor_dn2_;  // per band: a sample's variance
  // Per band and cell: the log signal (NaN: the band does not read there) and the window's mean
  // scale (NaN: none).
  std::vector<cv::Mat> log_signal_, mean_scale_;
  struct Scratch {  // one thread's
    std::vector<float> ring_scale, ring_count;
    std::vector<double> column_scale, column_count;
    std::vector<float> at, on, num, den, target, weight;
  };
  std::vector<Scratch> scratch_;

  // apply on the rectangle that holds every reading (views of the frame).
  void apply_within(const std::vector<cv::Mat>& planes, cv::Mat& temperature_c);
  // Band b's log signals and window-mean scales (log_signal_, mean_scale_).
  void scale_band(const cv::Mat& plane, int b, const cv::Mat& readings, Scratch& scratch);
  // The brightness readings of row y.
  void read_row(const std::vector<cv::Mat>& planes, int y, cv::Mat& temperature_c,
                Scratch& scratch) const;
};

}  // namespace pyrocam
