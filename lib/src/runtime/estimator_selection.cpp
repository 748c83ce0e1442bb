#include "pyrocam/runtime/estimator_selection.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <stdexcept>

#include "pyrocam/core/error.h"
#include "runtime/estimator_kinds.h"
#include "runtime/lut_tables.h"
#include "runtime/shared_model.h"

namespace pyrocam {

MethodRequest parse_method_request(const std::string& name) {
  if (name == "auto") return MethodRequest::kAuto;
  if (name == "mlp") return MethodRequest::kMlp;
  if (name == "lut") return MethodRequest::kLut;
  if (name == "likelihood") return MethodRequest::kLikelihood;
  throw InputError("unknown method '" + name + "' (use auto, mlp, lut or likelihood)");
}

std::string method_request_name(MethodRequest request) {
  switch (request) {
    case MethodRequest::kAuto:
      return "auto";
    case MethodRequest::kMlp:
      return "mlp";
    case MethodRequest::kLut:
      return "lut";
    case MethodRequest::kLikelihood:
      return "likelihood";
  }
  return "?";
}

std::string lut_disagreement(const LocusAgreement& a) {
  if (!(a.max_difference_c > kLutToleranceC ||
        a.validity_differs * 100 > kLutValidityPercent * a.samples))
    return "";
  char what[256];
  std::snprintf(what, sizeof what,
                "its lookup table differs from its network by up to %.1f degC (at %.0f degC on "
                "the model's locus; one reads where the other does not at %zu of %zu samples)",
                a.max_difference_c, a.worst_temperature_c, a.validity_differs, a.samples);
  return what;
}

std::string lut_check_verdict() {
  // Names the limits, so that a cache checked against other limits is checked again.
  char word[64];
  std::snprintf(word, sizeof word, "lut-check-passed:%gC:%zu%%", kLutToleranceC,
                kLutValidityPercent);
  return word;
}

EstimatorSelector::EstimatorSelector(std::shared_ptr<const ThermalModel> model)
    : model_(std::move(model)) {
  require_model(model_, "estimator selection");
}

// The lookup table on the grid its prebuilt table names, when that file is one of this model's:
// the grid need not be derived again (null otherwise).
std::unique_ptr<PlaneEstimator> EstimatorSelector::lut_on_prebuilt_grid() const {
  lut::TableFields f;
  std::error_code ec;
  if (prebuilt_file_.empty() || !std::filesystem::exists(prebuilt_file_, ec) ||
      !lut::read_table_fields(prebuilt_file_, f) || f.fingerprint != model_->fingerprint ||
      f.space != static_cast<int>(model_->mlp.output_transform()))
    return nullptr;
  try {
    const TemperatureEstimator::TableGrid grid{f.x0, f.y0, f.h * lut::kBlockCells, f.across,
                                               f.down};
    return std::make_unique<PlaneEstimator>(model_, make_lut_estimator_on_grid(model_, grid),
                                            Method::kLut);
  } catch (const InputError&) {
    return nullptr;  // load_tables says why
  }
}

std::string EstimatorSelector::prepare(Method m) {
  if (m == Method::kLut && lut_checked_ && !lut_problem_.empty()) return lut_problem_;
  auto& slot = estimators_[static_cast<std::size_t>(m)];
  try {
    bool on_file_grid = false;
    if (!slot && m == Method::kLut && !lut_checked_) {
      slot = lut_on_prebuilt_grid();
      on_file_grid = slot != nullptr;
    }
    if (!slot) slot = std::make_unique<PlaneEstimator>(model_, m);
    if (m != Method::kLut || lut_checked_) return "";
    // The prebuilt table first, then the cache's blocks beyond it (a cache written after it was
    // read holds its blocks first).
    const auto load = [&](const std::string& file, std::size_t& read, std::string& problem) {
      std::error_code ec;
      if (file.empty() || !std::filesystem::exists(file, ec)) return;
      try {
        read = slot->estimator().load_tables(file);
      } catch (const InputError& e) {
        problem = e.what();
      }
    };
    load(prebuilt_file_, prebuilt_read_, prebuilt_problem_);
    if (on_file_grid && !prebuilt_problem_.empty())
      slot = std::make_unique<PlaneEstimator>(model_, m);  // the grid of a file not used: derived
    load(cache_file_, cache_read_, cache_problem_);
    // A table file of this model's table (its fingerprint, grid and version, checksummed) that
    // records that the table passed this very check: the check's answer would be the same.
    const std::string passed = lut_check_verdict();
    if (cache_read_ + prebuilt_read_ > 0 && slot->estimator().tables_verdict() == passed) {
      lut_checked_ = lut_check_skipped_ = true;
      return "";
    }
    const auto mlp = make_estimator(model_, Method::kMlp);
    lut_problem_ = lut_disagreement(compare_on_locus(*model_, slot->estimator(), *mlp));
    lut_checked_ = true;
    if (!lut_problem_.empty()) {
      slot.reset();
      return lut_problem_;
    }
    slot->estimator().set_tables_verdict(passed);
    return "";
  } catch (const std::exception& e) {
    // A method that does not fit the model (the table needs two ratios) is a choice's problem,
    // not an error of the caller.
    slot.reset();
    return e.what();
  }
}

EstimatorSelector::Choice EstimatorSelector::select(MethodRequest request) {
  Choice c;
  switch (request) {
    case MethodRequest::kMlp:
      c.method = Method::kMlp;
      break;
    case MethodRequest::kLut:
      c.method = Method::kLut;
      break;
    case MethodRequest::kLikelihood:
      c.method = Method::kLikelihood;
      break;
    case MethodRequest::kAuto:
      if (model_->profile().normalisation.numerators.size() == 2) {
        c.fallback = prepare(Method::kLut);
        if (c.fallback.empty()) {
          c.method = Method::kLut;
          return c;
        }
      }
      c.method = Method::kLikelihood;
      break;
  }
  c.problem = prepare(c.method);
  return c;
}

PlaneEstimator& EstimatorSelector::estimator(Method m) {
  const auto& slot = estimators_[static_cast<std::size_t>(m)];
  if (!slot) throw std::logic_error("estimator " + method_name(m) + " was not selected");
  return *slot;
}

std::string EstimatorSelector::table_cache_unwritable() const {
  if (cache_file_.empty()) return "";
  const std::filesystem::path folder = std::filesystem::path(cache_file_).parent_path();
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) return "cannot make its folder " + folder.string() + ": " + ec.message();
  if (::access(folder.c_str(), W_OK) != 0) return "its folder " + folder.string() + " is read-only";
  return "";
}

std::size_t EstimatorSelector::save_table_cache() const {
  const auto& lut = estimators_[static_cast<std::size_t>(Method::kLut)];
  if (!lut || cache_file_.empty()) return 0;
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(cache_file_).parent_path(), ec);
  if (ec)
    throw InputError("cannot make the folder of the table cache " + cache_file_ + ": " +
                     ec.message());
  return lut->estimator().save_tables(cache_file_);
}

std::string default_table_cache_dir() {
  const char* xdg = std::getenv("XDG_CACHE_HOME");
  if (xdg != nullptr && *xdg == '/') return std::string(xdg) + "/pyrocam";
  const char* home = std::getenv("HOME");
  if (home != nullptr && *home != '\0') return std::string(home) + "/.cache/pyrocam";
  return "";
}

std::string table_cache_file(const ThermalModel& model, const std::string& dir) {
  if (dir.empty() || model.fingerprint.empty()) return "";
  return dir + "/lut-" + model.fingerprint + ".bin";
}

Method choose_method(std::shared_ptr<const ThermalModel> model, MethodRequest request,
                     std::string* fallback) {
  EstimatorSelector selector(std::move(model));
  const EstimatorSelector::Choice c = selector.select(request);
  if (!c.problem.empty())
    throw InputError("method " + method_name(c.method) +
                     " cannot be used with this model: " + c.problem);
  if (fallback) *fallback = c.fallback;
  return c.method;
}

}  // namespace pyrocam
