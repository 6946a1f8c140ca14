// The subcommands of `fabatlas`, one family per file. Each Add* function
// registers its subcommands on the app; their callbacks set `exit_code` and
// throw fabatlas::InputError for bad input (main prints it as one line and
// exits with status 2).
#pragma once

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

#include "fabatlas/design/design.h"

namespace fabatlas::cli {

// validate, eval, dg (cli/design_commands.cc).
void AddDesignCommands(CLI::App& app, int& exit_code);

// sample: a whole precompute job in this process on a thread pool
// (cli/sample_commands.cc).
void AddSampleCommands(CLI::App& app, int& exit_code);

// run, submit, status, watch, cancel, fetch, jobs: jobs on the cluster
// (cli/job_commands.cc).
void AddJobCommands(CLI::App& app, int& exit_code);

// inspect: an artifact's Table 3 / Fig. 14 rows and Fig. 13 PNG
// (cli/inspect_commands.cc).
void AddInspectCommands(CLI::App& app, int& exit_code);

// optimise: the best valid design for an objective (cli/optimise_commands.cc).
void AddOptimiseCommands(CLI::App& app, int& exit_code);

// inspect --pareto: the Pareto front of two properties over the artifact's
// valid samples (under `limits`), written as CSV and PNG (defaults: the
// artifact's path with .pareto.csv / .pareto.png); one line on stdout.
void WritePareto(const std::filesystem::path& artifact, const std::string& axes, const std::string& csv,
                 const std::string& png, const std::string& limits);

// prototype: solve a works-like prototype, export STL (cli/prototype_commands.cc).
void AddPrototypeCommands(CLI::App& app, int& exit_code);

// serve, export: the web customiser and its API over HTTP, the design at a
// point as a file (cli/viewer_commands.cc).
void AddViewerCommands(CLI::App& app, int& exit_code);

// The artifact an ART argument names, as serve, export and inspect take it:
// the file itself, or the run directory holding exactly one *.fabatlas.
// Throws InputError naming `arg` otherwise.
std::filesystem::path ArtifactPath(const std::string& arg);

// assemble: solve a FabHacks assembly program (cli/assembly_commands.cc).
void AddAssemblyCommands(CLI::App& app, int& exit_code);

// import-scad: an OpenSCAD Customizer model as a design (cli/scad_commands.cc).
void AddScadCommands(CLI::App& app, int& exit_code);

// resolve: a reconfigurable's collisions resolved (cli/resolve_commands.cc).
void AddResolveCommands(CLI::App& app, int& exit_code);

// True for an OpenSCAD model path (.scad).
bool IsScadModel(const std::string& path);
// A design file, or an OpenSCAD model imported on the fly (warnings on stderr).
design::Design LoadDesignOrModel(const std::string& path);
// A job file as given, or for an OpenSCAD model the job of its on-the-fly
// import written into `dir` (scad::WriteImportedJob).
std::string JobOrModel(const std::string& path, const std::string& dir);

}  // namespace fabatlas::cli
