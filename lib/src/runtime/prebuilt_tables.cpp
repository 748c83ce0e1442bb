#include "pyrocam/runtime/prebuilt_tables.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <utility>

#include "detail/portable_math.h"
#include "pyrocam/core/error.h"
#include "pyrocam/core/locus.h"
#include "pyrocam/core/noise_model.h"
#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/estimator_selection.h"
#include "runtime/shared_model.h"

namespace pyrocam {

std::string prebuilt_tables_file(const std::string& model_path) { return model_path + ".lut"; }

std::vector<std::uint32_t> locus_band(const ThermalModel& model,
                                      const TemperatureEstimator::TableGrid& grid, double sigmas) {
  const CameraProfile& profile = model.profile();
  const Normalisation& n = profile.normalisation;
  if (n.numerators.size() != 2 || !(grid.block_size > 0))
    throw InputError("a prebuilt lookup table needs a model with exactly two ratios");
  const Locus locus = make_locus(model.camera, model.min_temperature_c, model.max_temperature_c, 1);
  const double dim = profile.thresholds.inference_dim_dn;
  // Each block's distance from the locus: the least, over the locus samples, of the Mahalanobis
  // distance (squared) from the sample's noise-free log ratios to the block's nearest point.
  const std::size_t slots =
      static_cast<std::size_t>(grid.across) * static_cast<std::size_t>(grid.down);
  std::vector<double> distance2(slots, std::numeric_limits<double>::infinity());
  const auto block_range = [&](double lo, double hi, double origin, int blocks) {
    const auto at = [&](double ratio) {
      return static_cast<int>(
          std::clamp(std::floor((ratio - origin) / grid.block_size), 0.0, blocks - 1.0));
    };
    return std::make_pair(at(lo), at(hi));
  };
  for (Eigen::Index i = 0; i < locus.size(); ++i) {
    // Relative variances of the numerators and the reference at the dimmest exposure that
    // reads: the covariance of the two log ratios, which share the reference.
    const Eigen::VectorXd rates = locus.rates.row(i).transpose();
    const double scale = dim / rates.minCoeff();
    double ref = 0, ref_var = 0;
    for (int b : n.reference) {
      ref += rates[b] * scale;
      ref_var += signal_variance_dn2(profile, b, rates[b] * scale);
    }
    const double vr = ref_var / (ref * ref);
    double v[2];
    for (int k = 0; k < 2; ++k) {
      const double s = rates[n.numerators[static_cast<std::size_t>(k)]] * scale;
      v[k] = signal_variance_dn2(profile, n.numerators[static_cast<std::size_t>(k)], s) / (s * s);
    }
    const double c00 = v[0] + vr, c11 = v[1] + vr, c01 = vr;
    const double det = c00 * c11 - c01 * c01;
    if (!(det > 0) || !std::isfinite(det)) continue;
    const double cx = locus.ratios(i, 0), cy = locus.ratios(i, 1);
    const double lx = portable::log(cx), ly = portable::log(cy);
    const auto [i0, i1] =
        block_range(cx * portable::exp(-sigmas * std::sqrt(c00)),
                    cx * portable::exp(sigmas * std::sqrt(c00)), grid.x0, grid.across);
    const auto [j0, j1] =
        block_range(cy * portable::exp(-sigmas * std::sqrt(c11)),
                    cy * portable::exp(sigmas * std::sqrt(c11)), grid.y0, grid.down);
    for (int j = j0; j <= j1; ++j)
      for (int bi = i0; bi <= i1; ++bi) {
        const double x_lo = grid.x0 + bi * grid.block_size, y_lo = grid.y0 + j * grid.block_size;
        const double dx = portable::log(std::clamp(cx, x_lo, x_lo + grid.block_size)) - lx;
        const double dy = portable::log(std::clamp(cy, y_lo, y_lo + grid.block_size)) - ly;
        const double d2 = (c11 * dx * dx - 2 * c01 * dx * dy + c00 * dy * dy) / det;
        double& slot =
            distance2[static_cast<std::size_t>(j) * static_cast<std::size_t>(grid.across) +
                      static_cast<std::size_t>(bi)];
        slot = std::min(slot, d2);
      }
  }
  std::vector<std::uint32_t> blocks;
  for (std::size_t k = 0; k < slots; ++k)
    if (distance2[k] <= sigmas * sigmas) blocks.push_back(static_cast<std::uint32_t>(k));
  std::stable_sort(blocks.begin(), blocks.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return distance2[a] < distance2[b]; });
  return blocks;
}

namespace {

// Whether `file` holds a lookup table of any version (a file that ratiotemp's cache or prebuild
// wrote), so that prebuild never removes nor overwrites another file given as its table.
bool holds_a_table(const std::string& file) {
  static constexpr char kAnyVersion[] = "pyrocam lookup-table cache ";
  std::ifstream in(file, std::ios::binary);
  char head[sizeof kAnyVersion - 1] = {};
  return in.read(head, sizeof head) && std::string(head, sizeof head) == kAnyVersion;
}

}  // namespace

PrebuiltTables prebuild_tables(std::shared_ptr<const ThermalModel> model, const std::string& file,
                               std::size_t max_blocks) {
  const ThermalModel& m = require_model(model, "prebuilt lookup table");
  if (m.fingerprint.empty())
    throw InputError("a prebuilt lookup table needs a model loaded from its file (fingerprint)");
  PrebuiltTables r;
  std::error_code ec;
  if (std::filesystem::exists(file, ec) &&
      !(std::filesystem::is_regular_file(file, ec) && std::filesystem::file_size(file, ec) == 0) &&
      !holds_a_table(file)) {
    r.problem =
        file + (std::filesystem::is_directory(file, ec)
                    ? " is a folder, not a lookup table file: left as it is"
                    : " exists and is not a lookup table (the model itself?): left as it is");
    return r;
  }
  const auto drop_stale = [&] {
    std::error_code ignored;
    std::filesystem::remove(file, ignored);  // a table of an earlier model: never read again
  };
  if (m.profile().normalisation.numerators.size() != 2) {
    r.problem = "the model has " + std::to_string(m.profile().normalisation.numerators.size()) +
                " ratios: method lut, and so its table, needs two (colour camera)";
    drop_stale();
    return r;
  }
  const auto lut = make_estimator(model, Method::kLut);
  std::vector<std::uint32_t> band = locus_band(m, lut->table_grid());
  if (band.size() > max_blocks) band.resize(max_blocks);
  lut->fill_tables(band);
  const auto mlp = make_estimator(model, Method::kMlp);
  r.problem = lut_disagreement(compare_on_locus(m, *lut, *mlp));
  if (!r.problem.empty()) {
    drop_stale();
    return r;
  }
  lut->set_tables_verdict(lut_check_verdict());
  r.blocks = lut->save_tables(file);
  return r;
}

}  // namespace pyrocam
