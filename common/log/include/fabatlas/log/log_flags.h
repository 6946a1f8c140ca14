// fabatlas/log/log_flags.h — the --log-level and --log-format options every
// long-running fabatlas binary takes (CLI11), applied to log::Configure.
//   log::LogFlags flags;
//   flags.Add(app);            // before parsing
//   flags.Apply();             // after parsing; throws InputError for bad values
//   catch (const InputError& e) { return flags.BadInputExit("fabatlas-worker", "worker_exit", e); }
#pragma once

#include <CLI/CLI.hpp>

#include <exception>
#include <iostream>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/log/log.h"

namespace fabatlas::log {

struct LogFlags {
  std::string level = "info";
  std::string format = "text";

  void Add(CLI::App& app) {
    app.add_option("--log-level", level, "lowest level written to stderr: debug, info, warn, error, off")
        ->capture_default_str();
    app.add_option("--log-format", format,
                   "text (one readable line per event) or json (one JSON object per line, for log pipelines)")
        ->capture_default_str();
  }
  void Apply() const { Configure({ParseLevel(level), ParseFormat(format)}); }

  // A program's exit on bad input, as one line on stderr: under
  // --log-format json a log line `event` with the error and the exit status,
  // else "<program>: <error>". Returns kExitBadInput (2).
  int BadInputExit(const std::string& program, const std::string& event, const std::exception& e) const {
    return ErrorExit(program, event, e, kExitBadInput);
  }
  // The same line for another exit status; returns it.
  int ErrorExit(const std::string& program, const std::string& event, const std::exception& e, int status) const {
    if (format == "json")
      Error(event, {{"error", e.what()}, {"status", status}});
    else
      std::cerr << program << ": " << e.what() << "\n";
    return status;
  }
};

}  // namespace fabatlas::log
