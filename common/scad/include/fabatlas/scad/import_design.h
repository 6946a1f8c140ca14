// fabatlas/scad/import_design.h — an OpenSCAD Customizer model as a fabatlas
// design (docs/openscad.md): Customizer parameters with a slider or a
// dropdown become exposed parameters, everything else stays at the model's
// values, and the tree is one `openscad` node passing the exposed values.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace fabatlas::scad {

struct ImportOptions {
  // Parameters to expose. Empty: every parameter with a slider or a dropdown
  // outside the [Hidden] group. Named parameters may also be hidden ones with
  // a widget, or booleans (exposed as the enum [false, true]).
  std::vector<std::string> expose;
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
  std::string design_yaml;  // the design file's text
  std::string job_yaml;     // a job file beside it naming design_file_name
  std::vector<std::string> warnings;  // "FILE:LINE: ..." malformed annotations, presets not kept
  std::vector<std::string> exposed;   // parameter names, in file order
  std::vector<std::string> fixed;     // parameters kept at the model's values
  int presets = 0;                    // parameter sets kept as presets
};

// Reads MODEL.scad (and MODEL.json beside it when present). Throws
// fabatlas::InputError (one line naming the file) for an unreadable model, a
// --expose name the model does not have or that has no range, no parameter
// to expose, or more than 6 exposed parameters.
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
