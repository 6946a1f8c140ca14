// fabatlas/scad/import_design.h — an OpenSCAD Customizer model as a fabatlas
// design (docs/openscad.md): Customizer parameters with a slider or a
// dropdown become exposed parameters, everything else stays at the model's
// values, and the tree is one `openscad` node passing the exposed values.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace fabatlas::scad {

// A range given on the command line (`--expose name=lo:hi[:step]`): lo < hi;
// step 0 when none was given. Integer when lo, hi, step and the model's
// value are whole (step 1 when none), else real (the step is noted only).
struct ExposeRange {
  double lo = 0, hi = 0, step = 0;
};

struct ImportOptions {
  // Parameters to expose, exactly these, in file order. Empty: the automatic
  // choice (ChooseExposed below). Named parameters may also be hidden ones
  // with a widget, booleans (exposed as the enum [false, true]) or numbers
  // given a range in `ranges`.
  std::vector<std::string> expose;
  // Ranges for named parameters (each also in `expose`): gives a number
  // without a slider annotation a range, or replaces a slider's.
  std::map<std::string, ExposeRange> ranges;
  // The dimension budget: at most this many exposed parameters, 1..16
  // (sampling::kMaxDimensions). The automatic choice stops there; more names
  // in `expose` are an error.
  int max_dims = 6;
  // How the design names the model file (relative to the design file).
  // Empty: the model's file name (design written beside the model).
  std::string model_reference;
  // Level-set voxel size, mm (> 0). 0: from the model's size at its defaults,
  // `largest bounding-box edge / 150` within [0.5, 0.6] (5/8 and 3/4 of the
  // min_thickness check's 0.8 mm), rounded to 0.05 mm; 0.5 when unknown.
  double voxel_size = 0;
  // Largest bounding-box edge of the model at its defaults (mm), used when
  // voxel_size is 0; 0 = unknown (voxel 0.5 mm).
  double model_size = 0;
  // The job file's name for the design (the design's file name).
  std::string design_file_name = "design.yaml";
};

struct ImportSummary {
  std::string design_yaml;            // the design file's text
  std::string job_yaml;               // a job file beside it naming design_file_name
  std::vector<std::string> warnings;  // "FILE:LINE: ..." malformed annotations, presets not kept
  std::vector<std::string> exposed;   // parameter names, in file order
  std::vector<std::string> fixed;     // parameters kept at the model's values
  // One line per parameter, in file order: "exposed NAME: ..." or "fixed NAME
  // = VALUE: why" (what import-scad prints).
  std::vector<std::string> decisions;
  int presets = 0;  // parameter sets kept as presets
};

// Adds one `--expose` item to `options`: `name` or `name=lo:hi[:step]` (numbers
// as C's strtod reads them). Throws fabatlas::InputError ("--expose ITEM:
// ...", one line) for an empty name, a malformed range, lo >= hi or step <= 0.
void AddExposeItem(const std::string& item, ImportOptions& options);

// Reads MODEL.scad (and MODEL.json beside it when present).
//
// The automatic choice (no `expose`): the parameters with a slider or a
// dropdown, outside [Hidden] and not $-variables, in the order of their
// Customizer groups (tabs, by first appearance in the file; parameters before
// any group first) and within a group in file order, up to `max_dims`; every
// other parameter stays fixed at the model's value, and `decisions` says why.
// A model with nothing to expose (no annotation, as most models written before
// the Customizer) imports with `parameters: {}`: a one-sample design, the
// model at its own values, every number listed under `fixed`.
// The job beside the design plans the geometry cache (OPT-MAX under the
// default budget) and carries the example jobs' materials (PLA, PETG, resin).
//
// Throws fabatlas::InputError (one line naming the file, and the line of the
// parameter when it is about one) for an unreadable model, a --expose name the
// model does not have, a name without a range (neither a widget nor a range
// given), a range on a parameter that is not a number, a range that does not
// hold the model's value, more names than max_dims, or max_dims outside
// 1..16.
ImportSummary ImportScad(const std::filesystem::path& model, const ImportOptions& options);

}  // namespace fabatlas::scad

namespace fabatlas::scad {

// A model imported on the fly as a job: writes into `dir` (created) a copy of
// the model (and of MODEL.json when present) as STEM.scad, the design
// STEM.yaml naming it and the job STEM.job.yaml naming the design, so the
// job travels as a bundle like any other. The files the model includes,
// uses and imports (model_files.h) are copied beside it at the relative paths
// OpenSCAD finds them by.
// Returns the job file's path; warnings go to `summary` when given.
std::filesystem::path WriteImportedJob(const std::filesystem::path& model, const std::filesystem::path& dir,
                                       ImportOptions options, ImportSummary* summary = nullptr);

}  // namespace fabatlas::scad
