// Files a design needs beyond those its node arguments name (see
// data_files.h).
#include "fabatlas/design/data_files.h"

#include <string>

#include "assembly_node.h"
#include "fabatlas/assembly/part_library.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/scad/model_files.h"

namespace fabatlas::design {

namespace fs = std::filesystem;

std::vector<DataFile> IndirectDataFiles(const Node& node, const fs::path& design_dir) {
  std::vector<DataFile> out;
  if (node.op == "openscad") {
    // What the model includes, uses and imports, beside the model.
    auto it = node.args.find("file");
    if (it == node.args.end()) return out;
    const fs::path model = design_dir / it->second.text;
    std::error_code ec;
    if (!fs::is_regular_file(model, ec)) return out;
    const fs::path model_dir = fs::path(it->second.text).parent_path();
    for (const scad::ModelFile& f : scad::ModelFiles(model))
      out.push_back({(model_dir / f.relative).lexically_normal(), f.source});
    return out;
  }
  if (node.op != "assembly") return out;
  auto text = [&](const char* name) {
    auto it = node.args.find(name);
    return it == node.args.end() ? std::string() : it->second.text;
  };
  const std::string file = text("file");
  if (file.empty()) return out;
  fs::path library = fs::path(file).lexically_normal();  // relative to the design
  if (text("family").empty()) {
    // A program: its part library, as the program names it.
    const fs::path program = design_dir / file;
    library = fs::relative(fs::path(assembly::ProgramLibraryPath(program.string())), design_dir).lexically_normal();
    out.push_back({library, design_dir / library});
  }
  const std::string meshes = text("meshes");
  const fs::path here = AssemblyMeshDir(meshes, design_dir);
  const fs::path there = meshes.empty() ? fs::path(kBundledMeshDir) : fs::path(meshes);
  for (const std::string& name : assembly::PartLibraryMeshes((design_dir / library).string()))
    out.push_back({(there / name).lexically_normal(), here / name});
  return out;
}

}  // namespace fabatlas::design
