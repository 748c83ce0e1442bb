/* ratiotemp's lookup-table files at start: the table prebuilt beside the model
 * (<model>.lut, pyrocam-calib calibrate or prebuild) and the per-machine table cache. Both are read
 * by the library's EstimatorSelector; here is what the element says about them. */
#include <filesystem>
#include <string>

#include "pyrocam/runtime/estimator_check.h"
#include "pyrocam/runtime/prebuilt_tables.h"
#include "ratiotemp-private.h"

#define GST_CAT_DEFAULT gst_ratio_temp_debug

namespace pyrocam::gst::ratiotemp {

void set_table_files(pyrocam::EstimatorSelector& estimators, const pyrocam::ThermalModel& model,
                     const Settings& settings) {
  estimators.set_prebuilt_tables(pyrocam::prebuilt_tables_file(settings.model));
  estimators.set_table_cache(pyrocam::table_cache_file(
      model, settings.table_cache_set ? settings.table_cache : pyrocam::default_table_cache_dir()));
}

void report_table_files(GstRatioTemp* self, const pyrocam::EstimatorSelector& estimators,
                        const std::string& model_path, bool lut_built, bool lut_used,
                        bool cache_off) {
  if (!lut_built) return;
  const std::string prebuilt = pyrocam::prebuilt_tables_file(model_path);
  if (!estimators.prebuilt_problem().empty()) {
    /* Never a wrong reading: the table is filled from the network as pixels need it. */
    GST_ELEMENT_WARNING(self, RESOURCE, READ,
                        ("Prebuilt lookup table %s not used: %s", prebuilt.c_str(),
                         estimators.prebuilt_problem().c_str()),
                        ("the first frames fill the table from the network instead (slower start); "
                         "pyrocam-calib prebuild --model %s writes the table again",
                         model_path.c_str()));
  } else if (estimators.prebuilt_blocks_read() > 0) {
    GST_INFO_OBJECT(self, "%zu table blocks from the prebuilt table %s",
                    estimators.prebuilt_blocks_read(), prebuilt.c_str());
  }
  if (!estimators.cache_problem().empty())
    GST_WARNING_OBJECT(self, "table cache not used: %s", estimators.cache_problem().c_str());
  GST_INFO_OBJECT(self, "%zu table blocks from the cache", estimators.cache_blocks_read());
  if (lut_used && estimators.prebuilt_blocks_read() == 0) {
    const std::string unwritable = estimators.table_cache_unwritable();
    if (!unwritable.empty())
      GST_ELEMENT_WARNING(self, RESOURCE, OPEN_WRITE,
                          ("The lookup table's cache cannot be kept (%s): every start fills the "
                           "table anew (seconds); give table-cache a folder that can be written, "
                           "or pyrocam-calib prebuild --model %s writes a table beside the model",
                           unwritable.c_str(), model_path.c_str()),
                          ("table cache not writable"));
  }
  std::error_code ec;
  if (lut_used && estimators.prebuilt_blocks_read() == 0 && estimators.cache_blocks_read() == 0 &&
      estimators.prebuilt_problem().empty() && !std::filesystem::exists(prebuilt, ec))
    GST_ELEMENT_WARNING(
        self, RESOURCE, NOT_FOUND,
        ("No prebuilt lookup table beside model %s, and %s: the first frames "
         "fill the table (seconds); pyrocam-calib prebuild --model %s writes one",
         model_path.c_str(),
         cache_off ? "no table cache (table-cache is empty)" : "none in the table cache",
         model_path.c_str()),
        ("%s not found", prebuilt.c_str()));
}

void warn_when_network_folds(GstRatioTemp* self, State& st) {
  if (st.method == pyrocam::Method::kLikelihood || st.fold_warned) return;
  st.fold_warned = true;
  const pyrocam::AboveRangeFold fold =
      pyrocam::fold_above_range(*st.model, st.estimators->estimator(st.method).estimator());
  if (fold.read_inside == 0) return;
  GST_ELEMENT_WARNING(
      self, RESOURCE, SETTINGS,
      ("%s: with method %s, model %s reads graybodies hotter than its range inside it (%.0f degC "
       "as %.0f degC): a surface hotter than %.0f degC would read wrong, not as no reading; use "
       "method=likelihood, or a model calibrated to a higher --max-temperature",
       GST_OBJECT_NAME(self), pyrocam::method_name(st.method).c_str(), st.model_path.c_str(),
       fold.worst_true_c, fold.worst_read_c, st.model->max_temperature_c),
      ("%zu of %zu noise-free graybodies up to 500 degC above the range read inside it",
       fold.read_inside, fold.samples));
}

}  // namespace pyrocam::gst::ratiotemp
