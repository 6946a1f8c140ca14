// fabatlas import-scad — OpenSCAD Customizer models in (docs/openscad.md),
// and the on-the-fly import eval, sample, run and submit use for MODEL.scad.
#include <filesystem>
#include <algorithm>
#include <fstream>
#include <iostream>
#include <memory>
#include <sstream>

#include "commands.h"
#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/scad/import_design.h"
#include "fabatlas/scad/model_bounds.h"

namespace fabatlas::cli {

namespace {

namespace fs = std::filesystem;

struct ImportArgs {
  std::string model, out;
  std::vector<std::string> expose;  // NAME or NAME=lo:hi[:step]
  int max_dims = 6;
  double voxel = 0;
};

void PrintWarnings(const scad::ImportSummary& s) {
  for (const auto& w : s.warnings) std::cerr << "fabatlas: warning: " << w << "\n";
}

// The largest bounding-box edge (mm) of the model at its defaults: from its
// CSG tree without booleans (model_bounds.h), else from a coarse native
// evaluation (geometry only, voxel 1 mm, then 0.25 mm for models smaller than
// a few voxels); 0 when none gives geometry. The import picks its voxel size
// from it (docs/openscad.md, "Voxel size").
double MeasureModelSize(const std::string& model, const scad::ImportOptions& options) {
  fs::path path = model;
  if (const scad::CsgBox b = scad::ModelBounds(path); b.known && !b.empty)
    return std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
  for (double voxel : {1.0, 0.25}) {
    scad::ImportOptions probe = options;
    probe.voxel_size = voxel;
    scad::ImportSummary s = scad::ImportScad(model, probe);
    design::Design d = design::ParseDesign(s.design_yaml, path.parent_path() / (path.stem().string() + ".yaml"));
    design::EvaluateOptions preview;
    preview.run_checks = false;
    design::SampleResult r = design::EvaluateSample(d, design::DefaultPoint(d), preview);
    if (!r.valid || r.solid.empty()) continue;
    const geometry::Box3 box = r.solid.BoundingBox();
    return std::max({box.max[0] - box.min[0], box.max[1] - box.min[1], box.max[2] - box.min[2]});
  }
  return 0;
}

// `options` with the voxel size: `voxel`, else from the model's size.
scad::ImportOptions OptionsFor(const std::string& model, scad::ImportOptions options, double voxel) {
  options.voxel_size = voxel;
  if (voxel <= 0) options.model_size = MeasureModelSize(model, options);
  return options;
}

void ImportScadCommand(const ImportArgs& a) {
  if (!IsScadModel(a.model)) throw InputError(a.model + ": not an OpenSCAD model (.scad)");
  if (!(a.voxel >= 0)) throw InputError("--voxel must be a positive size in mm");
  const fs::path out = a.out;
  fs::path job = out;
  job.replace_extension(".job.yaml");
  scad::ImportOptions given;
  for (const auto& item : a.expose) scad::AddExposeItem(item, given);
  given.max_dims = a.max_dims;
  scad::ImportOptions options = OptionsFor(a.model, given, a.voxel);
  const fs::path out_dir = out.parent_path().empty() ? fs::path(".") : out.parent_path();
  options.model_reference = fs::relative(fs::absolute(a.model), fs::absolute(out_dir)).generic_string();
  options.design_file_name = out.filename().string();
  scad::ImportSummary s = scad::ImportScad(a.model, options);
  PrintWarnings(s);
  for (const auto& line : s.decisions) std::cout << line << "\n";
  auto write = [](const fs::path& p, const std::string& text) {
    std::ofstream f(p, std::ios::binary);
    f << text;
    if (!f) throw InputError(p.string() + ": cannot write");
  };
  // Lint what we wrote exactly as a user's design would be.
  design::ParseDesign(s.design_yaml, out);
  write(out, s.design_yaml);
  write(job, s.job_yaml);
  std::cout << "wrote " << a.out << " (" << s.exposed.size() << " exposed:";
  for (const auto& n : s.exposed) std::cout << " " << n;
  if (s.exposed.empty()) std::cout << " none, one sample";
  std::cout << "; " << s.fixed.size() << " fixed; " << s.presets << " presets) and " << job.string() << "\n";
}

}  // namespace

bool IsScadModel(const std::string& path) { return fs::path(path).extension() == ".scad"; }

design::Design LoadDesignOrModel(const std::string& path) {
  if (!IsScadModel(path)) return design::LoadDesign(path);
  scad::ImportSummary s = scad::ImportScad(path, OptionsFor(path, {}, 0));
  PrintWarnings(s);
  fs::path model = path;
  return design::ParseDesign(s.design_yaml, model.parent_path() / (model.stem().string() + ".yaml"));
}

std::string JobOrModel(const std::string& path, const std::string& dir) {
  if (!IsScadModel(path)) return path;
  scad::ImportSummary s;
  fs::path job = scad::WriteImportedJob(path, dir, OptionsFor(path, {}, 0), &s);
  PrintWarnings(s);
  return job.string();
}

void AddScadCommands(CLI::App& app, int& exit_code) {
  (void)exit_code;
  auto a = std::make_shared<ImportArgs>();
  auto* cmd =
      app.add_subcommand("import-scad", "make a design (and a job beside it) from an OpenSCAD Customizer model");
  cmd->add_option("model", a->model, "OpenSCAD model (.scad); MODEL.json beside it gives presets")->required();
  cmd->add_option("--out", a->out, "design YAML to write; the job goes to the same name with .job.yaml")->required();
  cmd->add_option(
         "--expose", a->expose,
         "parameters to expose, exactly these: NAME or NAME=lo:hi[:step] (a range for a number), comma-separated or "
         "repeated (default: the sliders and dropdowns outside [Hidden], by Customizer group then file order, up to "
         "--max-dims)")
      ->delimiter(',');
  cmd->add_option("--max-dims", a->max_dims,
                  "at most this many exposed parameters, 1..16 (default 6); the rest stay fixed");
  cmd->add_option("--voxel", a->voxel, "level-set voxel size in mm (default: from the model's size)");
  cmd->callback([a] { ImportScadCommand(*a); });
}

}  // namespace fabatlas::cli
