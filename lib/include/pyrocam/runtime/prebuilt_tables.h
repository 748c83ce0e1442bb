// A colour model's lookup table prebuilt for a fast start (docs/model-format.md, "Prebuilt lookup
// table"): the blocks that readings along the model's locus need, filled when the model is made
// (`pyrocam-calib calibrate`, `pyrocam-calib prebuild`) and kept beside it in the table cache's
// format, so that ratiotemp's first frame reads from a filled table instead of filling it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "pyrocam/runtime/estimators.h"
#include "pyrocam/runtime/model.h"

namespace pyrocam {

// Where a model's prebuilt table lives: the model's path with ".lut" added.
std::string prebuilt_tables_file(const std::string& model_path);

// How far from the locus, in standard deviations of a ratio's noise, the prebuilt table reaches.
inline constexpr double kPrebuiltSigmas = 4;
// Blocks a prebuilt table holds at most by default: three quarters of what the lookup table's
// files may give it (8192, half its budget), so that the table cache can add 2048 of a run's own
// blocks. About 7 MB. The band reaches further than that (tens of thousands of blocks at 4
// standard deviations): the blocks nearest the locus are those most pixels read.
inline constexpr std::size_t kPrebuiltBlocks = 6144;

// The lookup table's blocks (of `grid`, TemperatureEstimator::table_grid) that single pixels of
// the model's camera read near its locus, nearest first: those within `sigmas` standard
// deviations of some 1 degC locus sample's noise-free ratios (Mahalanobis distance in the log
// ratios, whose noise the shared reference correlates), the noise being the EMVA 1288 model's
// at the dimmest exposure that reads (the dimmest band at the inference dim threshold, at the
// profile's gain), where it is widest. Throws InputError unless the model has two ratios.
std::vector<std::uint32_t> locus_band(const ThermalModel& model,
                                      const TemperatureEstimator::TableGrid& grid,
                                      double sigmas = kPrebuiltSigmas);

struct PrebuiltTables {
  std::size_t blocks = 0;  // written; 0 when none
  std::string problem;     // why none was written; "" when one was
};

// Fills a lookup table of the model with its locus_band (at most the table cache's budget of
// blocks, nearest first), checks it against the network as ratiotemp would (lut_check_verdict: the
// verdict goes into the file, so that ratiotemp need not check it again) and writes it to `file`
// atomically. Writes nothing, and removes a `file` left from an earlier model, when the model
// has no lookup table (not two ratios) or its table fails the check: `problem` says why. A
// `file` there that is not a table (the model itself, given as the table's path) is neither
// removed nor overwritten: `problem` names it. Throws
// InputError when the file cannot be written or the model has no fingerprint (not loaded from
// a file).
PrebuiltTables prebuild_tables(std::shared_ptr<const ThermalModel> model, const std::string& file,
                               std::size_t max_blocks = kPrebuiltBlocks);

}  // namespace pyrocam
