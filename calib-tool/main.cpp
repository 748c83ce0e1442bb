// pyrocam-calib: makes calibration data and model files for the pyrocam GStreamer elements.
#include <iostream>
#include <string>

#include "commands.h"
#include "pyrocam/core/error.h"

int main(int argc, char** argv) {
  using namespace pyrocam::cli;
  CLI::App app{"pyrocam-calib: calibrate colour and 5x5 multispectral cameras as thermal imagers"};
  app.footer(
      "Exit codes: 0 ok, 1 failed, 2 bad usage.\n"
      "Example:\n  pyrocam-calib simulate campaign --profile rgb-reference --out furnace");
  app.set_version_flag("--version", std::string("pyrocam-calib ") + PYROCAM_VERSION);
  app.require_subcommand(1);
  GlobalOptions global;
  app.add_flag("-q,--quiet", global.quiet, "Print nothing but errors");
  Command selected;
  add_simulate_command(app, global, selected);
  add_calibrate_command(app, global, selected);
  add_measure_command(app, global, selected);
  add_export_command(app, global, selected);
  add_prebuild_command(app, global, selected);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // The first word that is not an option names the command: CLI11 says of an unknown one only
    // that a subcommand is required.
    for (int i = 1; i < argc; ++i) {
      const std::string word = argv[i];
      if (word.empty() || word[0] == '-') continue;
      bool known = false;
      for (const CLI::App* sub : app.get_subcommands({})) known = known || sub->get_name() == word;
      if (known) break;
      std::cerr << "pyrocam-calib: unknown command '" << word
                << "': simulate, calibrate, measure, export or prebuild (--help lists them)\n";
      return kExitUsage;
    }
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }
  try {
    return selected ? selected() : kExitUsage;
  } catch (const std::exception& e) {
    std::cerr << "pyrocam-calib: error: " << e.what() << "\n";
    return kExitFailed;
  }
}
