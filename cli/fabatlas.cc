// fabatlas — the operator's and designer's command line. Subcommands live in
// cli/*_commands.cc; this file only dispatches and turns errors into one line
// on stderr with exit status 2 (bad input) or 1 (internal fault).
#include <CLI/CLI.hpp>

#include <iostream>

#include "commands.h"
#include "fabatlas/error.h"
#include "fabatlas/coordinator/version_text.h"

int main(int argc, char** argv) {
  CLI::App app{"fabatlas: precompute the valid, fabricable region of a parametric design"};
  app.require_subcommand(1);
  app.option_defaults()->always_capture_default();  // every --help shows the defaults
  app.set_version_flag("--version", fabatlas::coordinator::VersionText("fabatlas"));
  int exit_code = 0;
  fabatlas::cli::AddDesignCommands(app, exit_code);
  fabatlas::cli::AddSampleCommands(app, exit_code);
  fabatlas::cli::AddJobCommands(app, exit_code);
  fabatlas::cli::AddInspectCommands(app, exit_code);
  fabatlas::cli::AddPrototypeCommands(app, exit_code);
  fabatlas::cli::AddViewerCommands(app, exit_code);
  fabatlas::cli::AddOptimiseCommands(app, exit_code);
  fabatlas::cli::AddAssemblyCommands(app, exit_code);
  fabatlas::cli::AddScadCommands(app, exit_code);
  fabatlas::cli::AddResolveCommands(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : fabatlas::kExitBadInput;
  } catch (const fabatlas::InputError& e) {
    std::cerr << "fabatlas: " << e.what() << "\n";
    return fabatlas::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "fabatlas: internal error: " << e.what() << "\n";
    return 1;
  }
  return exit_code;
}
