// OpenSCAD's own renders and 2D outlines of CSG subtrees with no native
// equivalent, each run as a program of its own in the work directory
// (csg_evaluation.h).
#include "csg_evaluation.h"

#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include "fabatlas/error.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/model_files.h"
#include "fabatlas/scad/svg_outline.h"
#include "fabatlas/sha256.h"

namespace fabatlas::design::csg {

namespace fs = std::filesystem;

bool CsgEvaluation::ExportSubtree(const CsgNode& n, const std::string& stem, const std::string& extension,
                                  fs::path& out, scad::OpenScadRun& run) {
  LinkModelFiles();
  const fs::path program = work_ / (stem + "-" + std::to_string(++rendered_) + ".scad");
  out = program.string() + extension;
  {
    std::ofstream text(program);
    text << n.canonical << "\n";
  }
  return scad::RunOpenScad(program, out, {}, &run);
}

Solid CsgEvaluation::Rendered(const CsgNode& n, const Affine& m, const std::string& why) {
  fs::path stl;
  scad::OpenScadRun run;
  const bool rendered = ExportSubtree(n, "subtree", ".stl", stl, run);
  if (!rendered && mesh_road_) {
    // OpenSCAD renders the whole model, so a subtree it cannot render on
    // its own is one it leaves empty there ("Current top level object is
    // empty"): no material, named in the log.
    Warn(n.name + " (CSG line " + std::to_string(n.line) + "): OpenSCAD renders it to no material (" + run.log_tail +
         ")");
    return Solid();
  }
  if (!rendered)
    throw SampleFailure(kNoGeometry, model_.string() + ": OpenSCAD could not render " + n.name + " (CSG line " +
                                         std::to_string(n.line) + ", no native " + why + "): " + run.log_tail);
  mesh::TriangleMesh mm;
  try {
    mm = mesh::ReadMesh(stl);
  } catch (const InputError& e) {
    if (mesh_road_) {  // OpenSCAD renders this subtree to nothing: no material, as in OpenSCAD's own render
      Warn(n.name + " (CSG line " + std::to_string(n.line) + "): OpenSCAD renders it to no material (" + e.what() +
           ")");
      return Solid();
    }
    throw SampleFailure(kNoGeometry, model_.string() + ": OpenSCAD's render of " + n.name + ": " + e.what());
  }
  Outside(
      model_.filename().string() + ": OpenSCAD's render of " + n.name + " (CSG line " + std::to_string(n.line) + ")",
      Sha256Hex(n.canonical), mm);
  if (mesh_road_) return MeshOf(std::move(mm), m);
  return FromMesh(std::move(mm), m);
}

std::vector<Loop> CsgEvaluation::Outline2(const CsgNode& n) {
  static std::mutex mutex;
  static std::map<std::string, std::vector<Loop>> outlines;
  static std::size_t outline_bytes = 0;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = outlines.find(n.canonical); it != outlines.end()) return it->second;
  }
  fs::path svg;
  scad::OpenScadRun run;
  if (!ExportSubtree(n, "outline", ".svg", svg, run))
    throw NoNativeEquivalent{n.name + " (no 2D outline: " + run.log_tail + ")"};
  std::string text;
  {
    std::ifstream in(svg, std::ios::binary);
    std::stringstream ss;
    ss << in.rdbuf();
    text = ss.str();
  }
  std::vector<Loop> loops;
  try {
    loops = scad::ReadSvgOutline(text, model_.filename().string() + ": OpenSCAD's outline of " + n.name);
  } catch (const InputError& e) {
    throw NoNativeEquivalent{e.what()};
  }
  std::size_t bytes = n.canonical.size() + sizeof(std::vector<Loop>);
  for (const Loop& l : loops) bytes += sizeof(Loop) + l.size() * sizeof(scad::Point2);
  std::lock_guard<std::mutex> lock(mutex);
  if (outline_bytes + bytes > kOutlineBytes) {
    outlines.clear();
    outline_bytes = 0;
  }
  if (outlines.emplace(n.canonical, loops).second) outline_bytes += bytes;
  return loops;
}

void CsgEvaluation::LinkModelFiles() {
  if (linked_) return;
  linked_ = true;
  std::error_code ec;
  // A model evaluated where it lies may name files outside its directory
  // (OpenSCAD reads them; a job bundle refuses such a model at submit and
  // a worker before it reads anything, model_files.h): those are not linked.
  std::vector<scad::ModelFile> files;
  try {
    files = scad::ModelFiles(model_);
  } catch (const InputError&) {
  }
  for (const scad::ModelFile& f : files) {
    fs::create_directories((work_ / f.relative).parent_path(), ec);
    fs::create_symlink(fs::absolute(f.source), work_ / f.relative, ec);
  }
}

}  // namespace fabatlas::design::csg
