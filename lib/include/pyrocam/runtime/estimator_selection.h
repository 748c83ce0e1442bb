// Which per-pixel estimator reads a model's images (METHOD.md section 5): the rule behind
// ratiotemp's method=auto and `pyrocam-calib measure --method auto`, and the check the lookup
// table must pass against the network before it is trusted.
#pragma once

#include <array>
#include <memory>
#include <string>

#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/plane_estimator.h"

namespace pyrocam {

// A method, or auto: the lookup table where the model has two ratios (colour cameras) and the
// table passes its check, else the likelihood fit.
enum class MethodRequest { kAuto, kMlp, kLut, kLikelihood };
// "auto", "mlp", "lut", "likelihood"; throws InputError for anything else.
MethodRequest parse_method_request(const std::string& name);
std::string method_request_name(MethodRequest request);

// The lookup table is used only where it gives the network's answer: within this many degC at
// every 1 degC sample of the model's locus (brightest band at 150 DN, noise-free) ...
constexpr double kLutToleranceC = 1.0;
// ... and reading where the network reads (or not) at all but 1 % of them (the range ends).
constexpr std::size_t kLutValidityPercent = 1;

// "" when a lookup table's agreement with its network (compare_on_locus(model, lut, mlp)) is
// within the limits above, else why not: by how much and where it differs.
std::string lut_disagreement(const LocusAgreement& agreement);

// The verdict the table cache keeps for a table that passed the check above
// (TemperatureEstimator::set_tables_verdict): a cache of the model that holds it spares the next
// run the check.
std::string lut_check_verdict();

// Builds a model's estimators as they are asked for and keeps them, so that switching back is
// free and the lookup table is checked once. They share the model; not thread-safe.
class EstimatorSelector {
 public:
  struct Choice {
    Method method = Method::kLikelihood;  // what the request resolves to
    std::string problem;                  // why that method cannot be used; "" when it can
    std::string fallback;  // auto: why not the lookup table, when the model has two ratios
  };

  explicit EstimatorSelector(std::shared_ptr<const ThermalModel> model);
  // Resolves a request and builds its estimator (the lookup table: and checks it, once).
  // Never throws for a method that does not fit the model: Choice::problem says why.
  Choice select(MethodRequest request);
  // The estimator of a method that select() returned without a problem.
  PlaneEstimator& estimator(Method method);
  // Keeps the lookup table's blocks in `file` between runs (table_cache_file): read when the
  // table is built, before its check (which then checks them too, unless the file records that
  // this model's table passed it); "" (the default): none.
  void set_table_cache(std::string file) { cache_file_ = std::move(file); }
  // A table prebuilt for the model (prebuilt_tables.h: the model's path + ".lut"), read when the
  // lookup table is built, before the cache (whose blocks then add to it), and spared the check
  // as the cache is, and the grid it names spares deriving the table's (a third of its start);
  // "" (the default): none. A file that is not there is no problem; one that
  // cannot be used (not such a file, altered, another model's, values this machine would not
  // compute) adds nothing, and prebuilt_problem() says why.
  void set_prebuilt_tables(std::string file) { prebuilt_file_ = std::move(file); }
  std::size_t prebuilt_blocks_read() const { return prebuilt_read_; }
  const std::string& prebuilt_problem() const { return prebuilt_problem_; }
  // Blocks the cache gave, and why it gave none when it was there but unusable ("" otherwise).
  std::size_t cache_blocks_read() const { return cache_read_; }
  const std::string& cache_problem() const { return cache_problem_; }
  // Whether the lookup table's check was not run again because the cache or the prebuilt table
  // recorded that this model's table passed it.
  bool lut_check_skipped() const { return lut_check_skipped_; }
  // Why the cache file cannot be written at stop (its folder cannot be made, or is read-only);
  // "" where it can, or there is none. Makes the folder.
  std::string table_cache_unwritable() const;
  // Writes the table's blocks to the cache file when it holds blocks the file did not give it
  // (creating the folder); returns how many it wrote. Throws InputError when it cannot.
  std::size_t save_table_cache() const;

 private:
  std::string prepare(Method method);
  std::unique_ptr<PlaneEstimator> lut_on_prebuilt_grid() const;

  std::shared_ptr<const ThermalModel> model_;
  std::array<std::unique_ptr<PlaneEstimator>, 3> estimators_;  // by Method
  std::string cache_file_, cache_problem_, prebuilt_file_, prebuilt_problem_;
  std::size_t cache_read_ = 0, prebuilt_read_ = 0;
  bool lut_checked_ = false;
  bool lut_check_skipped_ = false;
  std::string lut_problem_;  // why the lookup table is not used, once checked
};

// For one-shot tools: the method a request resolves to for a model (auto builds and checks the
// lookup table; `fallback`, when given, receives why it is not used). Throws InputError when
// the method cannot be used with the model.
Method choose_method(std::shared_ptr<const ThermalModel> model, MethodRequest request,
                     std::string* fallback = nullptr);

// Where the lookup table's filled blocks are kept between runs by default (ratiotemp
// table-cache, pyrocam-calib calibrate): $XDG_CACHE_HOME/pyrocam, else $HOME/.cache/pyrocam; ""
// when neither variable is set.
std::string default_table_cache_dir();
// A model's cache file in `dir` (TemperatureEstimator::save_tables): dir/lut-FINGERPRINT.bin;
// "" for an empty dir or a model without a fingerprint (not loaded from a file).
std::string table_cache_file(const ThermalModel& model, const std::string& dir);

}  // namespace pyrocam
