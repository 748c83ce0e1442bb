// Per-pixel temperature estimators over band signals (METHOD.md section 5), shared by the
// ratiotemp element and `pyrocam-calib measure`.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pyrocam/core/physics.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

enum class Method {
  kMlp,         // the paper's network on normalised ratios (the reference)
  kLut,         // a 2-D lookup table of the network (colour cameras: two ratios)
  kLikelihood,  // maximum-likelihood fit of T and scale to the band signals
};
Method parse_method(const std::string& name);  // "mlp", "lut", "likelihood"
std::string method_name(Method m);

class TemperatureEstimator {
 public:
  // Shares the model; throws InputError without one.
  explicit TemperatureEstimator(std::shared_ptr<const ThermalModel> model);
  virtual ~TemperatureEstimator() = default;

  // signals: one value per band, DN after dark subtraction; +inf marks a saturated band, NaN
  // an invalid one. Returns degC, or NaN for no reading (a band dim or saturated where the
  // method needs it, or a result outside the model's temperature range).
  virtual double temperature_c(const double* signals) const = 0;

  // Band-planar batch: planes[b][i] for i < n. Writes degC or NaN.
  virtual void estimate(const float* const* planes, std::size_t n, float* out_c) const;

  const ThermalModel& model() const { return *model_; }
  const std::shared_ptr<const ThermalModel>& shared_model() const { return model_; }

  // Combined systematic standard uncertainty of a reading at t_c, degC (calibration and
  // emissivity terms): the model's table (UncertaintyModel::systematic_u_c); a reading corrected
  // for an emissivity slope has its own emissivity term (emissivity.h).
  virtual double systematic_u_c(double t_c) const;

  // Whether the likelihood fit may read a pixel from the bands left when some are saturated,
  // missing or dim (at least two of them): kOff (the default) never, such a pixel has no
  // reading with every method; kSafe when a pair of the bands left has a ratio monotonic over
  // the model's whole range (decided from the model's locus: the shipped 5x5 camera has many
  // such pairs, the shipped colour camera none, its three ratios turning over between 1000 and
  // 1500 degC, where a pair can pin the fit near its turning point, a reading that looks right
  // and is not), and when the noise alone leaves that reading within max_partial_sigma_c (one
  // standard deviation, from the fit's chi2 curvature: a few noisy bands at the dim end of a
  // melt pool otherwise read hundreds of degrees off, within their own uncertainty); kAny with
  // any two. The network and its table always need every band (PlaneEstimator::
  // set_partial_bands reads such pixels by the fit). A band below the dim threshold but above
  // the no-signal level is weighed by its noise, not dropped (likelihood_fit.h).
  enum class PartialBands { kOff, kSafe, kAny };
  // kSafe's limit on a reading at t_c: kMaxPartialSigmaC at kPartialSigmaReferenceC, growing
  // as the square of the absolute temperature. Band ratios fix 1/T (Wien), so a pixel's
  // standard deviation grows about so with the temperature it reads: a limit of one precision
  // in 1/T keeps or refuses a pixel whatever its noise makes it read. A limit in degrees cut
  // into the spread of a uniform surface instead, keeping only the pixels that the noise moved
  // lower (the 5x5 camera at 2500 degC, brightest band at 40 % of its range: 16 % read, 41 degC
  // low).
  static constexpr double kMaxPartialSigmaC = 50;
  static constexpr double kPartialSigmaReferenceC = 1500;
  static double max_partial_sigma_c(double t_c) {
    const double ratio = (t_c + kZeroCelsius) / (kPartialSigmaReferenceC + kZeroCelsius);
    return kMaxPartialSigmaC * ratio * ratio;
  }
  void set_partial_bands(PartialBands p) {
    partial_ = p;
    min_bands_ = p == PartialBands::kOff ? bands_ : 2;
  }
  void set_allow_partial(bool allow) {
    set_partial_bands(allow ? PartialBands::kAny : PartialBands::kOff);
  }
  // Whether a pixel with unusable bands can ever read under the current rule (the likelihood
  // fit: kAny with more than two bands, kSafe with a monotonic pair in the model).
  virtual bool can_read_partial() const { return false; }
  // Bytes of the tables the estimator holds (the lookup table grows as pixels need its blocks,
  // up to 16384 of 1.2 KB; past that, pixels in blocks not yet filled are read by the network
  // itself, which differs from the table by at most about 0.5 degC: which pixels those are then
  // depends on the frames seen before).
  virtual std::size_t memory_bytes() const { return 0; }
  // The lookup table's filled blocks kept between runs (ratiotemp's table cache), so that a
  // second run of a model starts with the blocks the first one needed. save_tables writes them
  // to `path` atomically (a temporary file, then a rename) when it holds blocks that `path` did
  // not give it, and returns how many it wrote (0: nothing new, or a model without a
  // fingerprint). load_tables adds a file's blocks and returns how many; it throws InputError,
  // adding none, for a file that is not such a cache, is truncated or altered (checksum), was
  // made for another model (fingerprint), grid or version, or holds other values than this
  // machine computes (its first and last blocks are computed again and compared bit for bit:
  // another build's arithmetic or byte order). A block read back holds the values a block filled
  // here would, so readings do not change. The prebuilt table shipped beside a model
  // (prebuilt_tables.h) is such a file too. Other methods keep no tables.
  virtual std::size_t save_tables(const std::string& path) const;
  virtual std::size_t load_tables(const std::string& path) const;
  // A word (no white space; "" for none) kept with the tables in their file: the check the
  // tables passed (EstimatorSelector). load_tables sets it from the file; a file whose verdict
  // differs from the one it gave is written again even without new blocks.
  virtual void set_tables_verdict(const std::string& verdict) const;
  virtual std::string tables_verdict() const { return ""; }
  // The lookup table's grid of blocks over its two ratios (s_n0 / ref, s_n1 / ref): block (i, j),
  // index j * across + i, covers [x0 + i * size, x0 + (i + 1) * size) by [y0 + j * size, ...).
  // All 0 for methods without a table.
  struct TableGrid {
    double x0 = 0, y0 = 0, block_size = 0;
    int across = 0, down = 0;
  };
  virtual TableGrid table_grid() const { return {}; }
  // Fills now, in this order, the lookup table's blocks with these indices (those of a prebuilt
  // table, prebuilt_tables.h) until the table holds as many blocks as its file keeps (half its
  // budget: 8192); returns how many it holds (an empty list: how many it holds now). The values are
  // those a block filled when a pixel needs it gets. Throws InputError for an index outside the
  // grid. Other methods: 0.
  virtual std::size_t fill_tables(const std::vector<std::uint32_t>& blocks) const;

  // The analogue gain the signals were taken with, as a factor over the profile's (10^(dB / 20);
  // 1, the default, for frames at 0 dB): the shot noise in DN per electron scales by it
  // (noise_model.h), so the likelihood fit's weights and the uncertainty do. Ratios, and so the
  // readings of the network and its table, do not depend on it. Not while an estimate runs.
  // Throws InputError unless it is a positive number.
  virtual void set_analogue_gain(double factor);
  double analogue_gain() const { return analogue_gain_; }

 protected:
  // All bands finite and at least the dim threshold.
  bool all_bands_valid(const double* signals) const;
  double in_range(double t_c) const;

  std::shared_ptr<const ThermalModel> model_;  // never null
  int bands_;
  double dim_dn_;
  int min_bands_;  // bands the likelihood fit needs (set_partial_bands)
  PartialBands partial_ = PartialBands::kOff;
  double analogue_gain_ = 1.0;
};

// Throws InputError without a model or when the method does not fit the model (the lookup table
// needs exactly two ratios).
std::unique_ptr<TemperatureEstimator> make_estimator(std::shared_ptr<const ThermalModel> model,
                                                     Method method);

// The likelihood fit by its definition, scanning every coarse and every 1 degC locus sample:
// slow, the reference that the fast fit of make_estimator(model, Method::kLikelihood) is tested
// and benchmarked against (same answers to 0.01 degC, same no-reading decisions).
std::unique_ptr<TemperatureEstimator> make_exhaustive_likelihood_estimator(
    std::shared_ptr<const ThermalModel> model);

}  // namespace pyrocam
