// Ratio-scaled brightness readings for Bayer mosaics.
//
// A two-colour reading needs every band at one place, so demosaicking spreads each reading over
// a footprint of several pixels, and where the temperature field has a kink (a melt pool's
// peak, where a flat front meets a steep tail) the bands' footprints sample it differently: the
// ratio amplifies that mismatch about eight-fold and the core reads tens of degrees off,
// depending on which Bayer column the peak falls on.
//
// A single band needs no other band: log s_b = e_b + log m_b(T), with m_b the model's modelled
// rate of band b and e_b everything the ratio cancels (exposure, geometry, emissivity, the
// band's calibration scale). Where e_b is known, each sample's own value gives a temperature at
// that very pixel (a brightness temperature), with about an eighth of the ratio's sensitivity
// to noise. e_b is what the ratio readings provide: at each pixel of band b that reads,
// log s - log m_b(T_ratio). Averaged over a window it is smooth, while the brightness readings
// keep the full resolution of the mosaic.
//
// So each pixel reads T = m_b^-1(s / exp(mean e_b)), the mean taken over the pixels of the same
// Bayer phase (R, Gr, Gb or B: the two greens kept apart, so that their imbalance cannot make a
// pattern) within a window of (4r + 1) x (4r + 1) pixels. The assumption is the ratio's own one,
// on a larger scale: the emissivity (and the spectral shape of the light) is the same over the
// window. On a uniform surface the readings' mean is the ratio's, and their noise is that of one
// sample. Across an emissivity step inside the window (a liquid pool beside its solid track)
// the pixels near the step read biased by the step's share of the mean, up to
// (window fraction) x d ln(emissivity) x lambda T^2 / c2, where the ratio itself reads right:
// which is why it is not on by default.
//
// A pixel keeps the ratio's reading mask: it reads only where the ratio read. Where its own
// sample is saturated, below the profile's dim threshold or outside the model's range, it takes
// the mean of its four neighbours' brightness readings, or keeps its ratio reading without any.
//
// Measured (simulated colour camera, its true QE, likelihood fit, radius 2; tests/lib and the
// targets suite): on plates without temporal noise 2.4-2.7 times less rms error than the
// ratio's, the same mean; with noise 2.4-2.8 times less spread; the simulator's melt-pool
// cores' median 63 -> 22 degC rms over 25 frames exposed for the peak. On a plate whose
// emissivity steps from 0.3 to 0.6 the ratio reads 3-4 columns at the step wrong (up to
// -270 degC at 2000 degC); the brightness readings 9-11, up to -110 degC 3-6 pixels from the
// step, where the ratio reads within 10 degC. The uncertainty the estimators give for a reading
// is the ratio's, which covers these readings' noise with room to spare, not the step's bias.
//
// The pass streams each phase's rows once, its windows' sums kept as running column sums; a
// 2048 x 2048 frame with readings over 90 % of it costs about 25 ms of one core here, a third
// of that at 36 %, little on a melt pool (only the rows and columns between readings count).
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace pyrocam {

struct ThermalModel;
struct MosaicLayout;

class ScaledBrightness {
 public:
  static constexpr int kMaxWindowRadius = 8;  // Bayer cells: a 33 x 33 pixel window

  // For the model's Bayer mosaic, window radius r in Bayer cells (1..kMaxWindowRadius). Throws
  // InputError for a snapshot mosaic or a radius out of range.
  ScaledBrightness(const ThermalModel& model, int window_radius);
  // The same for mosaics of `layout`, a Bayer pattern of the model's bands that may start on
  // another cell than the model's (a camera's readout window at an odd row or column).
  ScaledBrightness(const ThermalModel& model, int window_radius, const MosaicLayout& layout);

  int window_radius() const { return radius_; }
  int window_pixels() const { return 4 * radius_ + 1; }  // side of the window, pixels

  // In place. `temperature_c`: the ratio readings, CV_32F degC (NaN: no reading), one per
  // sensor pixel; `signal`: the dark-subtracted mosaic they were read from (CV_32F, +INF
  // saturated, NaN no reading). Throws InputError unless both are CV_32F of the same size, a
  // whole number of Bayer cells.
  void apply(const cv::Mat& signal, cv::Mat& temperature_c);
  // The same on CV_16U 0.1 K codes (0: no reading).
  void apply_codes(const cv::Mat& signal, cv::Mat& codes);

  // The model's log rate of band b at t_c (natural log, DN/s at emissivity 1), and its inverse:
  // NaN outside the model's range. For tests.
  double log_rate(int band, double t_c) const;
  double temperature_of_log_rate(int band, double log_rate) const;

 private:
  struct BandTables {
    std::vector<float> log_rate;     // per degC from min_c_
    std::vector<float> temperature;  // uniform in log rate from log_lo
    float log_lo = 0, log_hi = 0, inv_log_step = 0;
  };
  void check(const cv::Mat& signal, const cv::Mat& readings, int type) const;
  template <class Readings>
  void apply_to(const cv::Mat& signal, cv::Mat& readings);

  int radius_ = 2;
  int phase_band_[4] = {0, 0, 0, 0};  // band of phase (x & 1) + 2 (y & 1)
  float dim_dn_ = 0;
  float min_c_ = 0, max_c_ = 0;
  std::vector<BandTables> bands_;
  cv::Mat state_[4];  // per Bayer phase and cell: 1 brightness reading, 2 ratio kept, 0 none
  // Per Bayer phase: rows of log samples, scales, weights and sums; per row, whether a cell
  // kept its ratio reading.
  std::vector<float> scratch_[4];
  std::vector<std::uint8_t> kept_[4];
};

}  // namespace pyrocam
