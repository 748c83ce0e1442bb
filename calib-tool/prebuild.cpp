// `pyrocam-calib prebuild`: the prebuilt lookup table of an existing model (calibrate writes one
// with every colour model), so that ratiotemp's first frame reads at once.
#include <iostream>
#include <memory>

#include "commands.h"
#include "pyrocam/runtime/prebuilt_tables.h"

namespace pyrocam::cli {
namespace {

// Writes a model's prebuilt lookup table to `out`: kExitOk, or kExitFailed with a note on stderr
// when the model has none.
int write_prebuilt_table(const std::string& model_path, const std::string& out,
                         std::size_t max_blocks, const GlobalOptions& global) {
  const auto model = std::make_shared<const ThermalModel>(load_model(model_path));
  const PrebuiltTables t = prebuild_tables(model, out, max_blocks);
  if (!t.problem.empty()) {
    // An error: printed with --quiet too.
    std::cerr << "pyrocam-calib: error: no prebuilt lookup table: " << t.problem << "\n";
    return kExitFailed;
  }
  if (!global.quiet) std::cout << "table:  " << out << " (" << t.blocks << " blocks)\n";
  return kExitOk;
}

}  // namespace

void add_prebuild_command(CLI::App& app, const GlobalOptions& global, Command& selected) {
  static std::string model, out;
  static std::size_t max_blocks = kPrebuiltBlocks;
  CLI::App* c = app.add_subcommand(
      "prebuild",
      "Prebuild a colour model's lookup table beside it (<model>.lut), for a fast start");
  c->footer(
      "Example:\n"
      "  pyrocam-calib prebuild --model rgb-model.json\n"
      "calibrate writes the table with every colour model; this makes one for a model made "
      "before, or again after the file was lost. ratiotemp reads it when it starts (method "
      "lut or auto). Exit 1, writing nothing, for a model without a lookup table (5x5) or "
      "whose table fails its check against the network.");
  c->add_option("--model", model, "Model file (.json)")->required()->check(CLI::ExistingFile);
  c->add_option("--out", out, "Table file to write (default: the model's path + .lut)");
  c->add_option("--max-blocks", max_blocks,
                "Blocks of the table to prebuild, nearest the locus first (1160 bytes each in "
                "the file; the table cache keeps 8192 blocks less these). The table's check "
                "against the network fills the blocks along the locus too (some hundreds), so "
                "the file holds at least those")
      ->check(CLI::Range(1, 8192))
      ->capture_default_str();
  c->callback([&global, &selected] {
    selected = [&global] {
      return write_prebuilt_table(model, out.empty() ? prebuilt_tables_file(model) : out,
                                  max_blocks, global);
    };
  });
}

}  // namespace pyrocam::cli
