// The `openscad` node (openscad_node.h, docs/openscad.md): the model's CSG
// tree from fabatlas's own evaluation of the model or OpenSCAD's export,
// evaluated by csg::CsgEvaluation (csg_evaluation.h), or OpenSCAD's own
// render with `render: openscad`; and the model's parts.
#include "openscad_node.h"

#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>

#include "csg_evaluation.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/csg_tree.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/scad/evaluate_model.h"
#include "fabatlas/scad/model_files.h"
#include "fabatlas/scad/part_trees.h"
#include "fabatlas/sha256.h"

namespace fabatlas::design {
namespace {

namespace fs = std::filesystem;
using geometry::Solid;
using Overrides = std::vector<std::pair<std::string, std::string>>;

// A temporary directory removed when it goes out of scope.
struct WorkDir {
  fs::path path;
  explicit WorkDir(const std::string& where) {
    char tmpl[] = "/tmp/fabatlas-openscad-XXXXXX";
    if (!::mkdtemp(tmpl)) throw DesignFault(where + ": cannot create a temporary directory for openscad");
    path = tmpl;
  }
  ~WorkDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// A file's bytes (empty when it cannot be read).
std::string FileText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// The node's `set` values as OpenSCAD's overrides (name, OpenSCAD literal).
Overrides OverridesOf(const ResolvedArgs& args) {
  Overrides overrides;
  if (auto it = args.values.find("set"); it != args.values.end())
    for (std::size_t i = 0; i < it->second.keys.size(); ++i)
      overrides.emplace_back(it->second.keys[i], it->second.literals[i]);
  return overrides;
}

// OpenSCAD's export of the model to `out` (its CSG tree or its STL render).
// A parser error is the model's, whatever the values: bad input (one line
// naming the model and OpenSCAD's line, exit 2), where a failure at these
// values only (an assert) fails the sample.
void RunOpenScadOn(const Node& node, const fs::path& model, const fs::path& out, const Overrides& overrides,
                   scad::OpenScadRun& run) {
  try {
    if (!scad::RunOpenScad(model, out, overrides, &run)) {
      const std::size_t parser = run.log_tail.find("Parser error");
      if (parser != std::string::npos) {
        std::string line;
        if (const std::size_t at = run.log_tail.rfind("line "); at != std::string::npos)
          line = ":" + run.log_tail.substr(at + 5, run.log_tail.find_first_not_of("0123456789", at + 5) - (at + 5));
        throw DesignFault(model.string() + line + ": OpenSCAD rejects the model: " + run.log_tail.substr(parser));
      }
      throw SampleFailure(kNoGeometry, node.place.str() + ": openscad failed: " + run.log_tail);
    }
  } catch (const SampleFailure&) {
    throw;
  } catch (const DesignFault&) {
    throw;
  } catch (const InputError& e) {
    throw DesignFault(node.place.str() + ": " + e.what());
  }
}

// The model at these overrides exported: with `native`, its CSG tree's text
// into *csg, from fabatlas's own evaluation of the model where it
// implements the model's language (evaluate_model.h), else OpenSCAD's
// export (written to `out`); without, OpenSCAD's STL render in `out`.
// What OpenSCAD would warn of while reading the model (an include it skips)
// goes to *warnings when given. Returns the export's wall time in seconds.
double ExportModel(const Node& node, const fs::path& model, const Overrides& overrides, bool native,
                   const fs::path& out, std::string* csg, std::vector<std::string>* warnings) {
  scad::ModelEvaluation own;
  if (native) own = scad::EvaluateModel(model, overrides);
  if (!own.bad_input.empty()) throw DesignFault(own.bad_input);
  if (own.evaluated) {
    if (warnings) warnings->insert(warnings->end(), own.warnings.begin(), own.warnings.end());
    *csg = std::move(own.csg);
    return own.seconds;
  }
  // OpenSCAD draws an unknown colour name in its default colour (a
  // warning --quiet hides); the designer meant a colour: bad input here too.
  if (const std::string bad = scad::UnknownColourName(FileText(model), model.string()); !bad.empty())
    throw DesignFault(bad);
  scad::OpenScadRun run;
  RunOpenScadOn(node, model, out, overrides, run);
  if (native) *csg = FileText(out);
  return run.seconds;
}

// `render: openscad`: OpenSCAD's STL render of the model, an outside mesh.
Solid RenderedModel(const Node& node, const ResolvedArgs& args, const fs::path& model, const fs::path& stl,
                    OpenScadNodeContext& context) {
  mesh::TriangleMesh m;
  try {
    m = mesh::ReadMesh(stl);
  } catch (const InputError& e) {
    throw SampleFailure(kNoGeometry, node.place.str() + ": OpenSCAD's STL: " + e.what());
  }
  if (context.outside) {
    std::string key = Sha256Hex(args.Canonical());
    context.outside->push_back(
        {model.filename().string() + ": OpenSCAD's render", key, std::make_shared<const mesh::TriangleMesh>(m)});
  }
  return geometry::FromMesh(context.grid, m);
}

// The model's parts (OpenScadNodeContext::parts) from its CSG tree `root`
// and its evaluated solid `whole`: each part evaluated apart (its subtrees
// keyed and cached as any), then made disjoint from the parts before it;
// one part is the solid itself.
void EvaluateParts(const scad::CsgNode& root, const Solid& whole, const fs::path& model, const fs::path& work,
                   bool mesh_road, OpenScadNodeContext& context) {
  const std::vector<scad::PartTree> trees = scad::PartTrees(root);
  int bodies = 0;
  std::map<int, int> regions;  // per body
  for (const auto& t : trees) {
    bodies = std::max(bodies, t.body);
    ++regions[t.body];
  }
  OpenScadNodeContext quiet = context;  // no records, warnings or outside meshes twice
  quiet.records = nullptr;
  quiet.outside = nullptr;
  quiet.warnings = nullptr;
  quiet.parts = nullptr;
  csg::CsgEvaluation parts(quiet, model, work, mesh_road);
  std::vector<Solid> earlier;
  for (const auto& t : trees) {
    Solid solid;
    if (trees.size() == 1) {
      solid = whole;
    } else {
      const scad::CsgNode part = scad::ParseCsg(t.csg, model.string() + " (part)");
      solid = parts.Evaluate3(part, csg::kIdentity, context.path + "/part", /*need_solid=*/true).solid;
    }
    Solid own = parts.Minus(solid, earlier);
    if (!solid.empty()) earlier.push_back(std::move(solid));
    if (own.empty()) continue;
    Part p;
    p.name = "body" + std::to_string(t.body);
    if (regions[t.body] > 1) p.name += "-" + scad::HexColour(t.rgba).substr(1);
    p.coloured = t.coloured;
    p.rgba = t.rgba;
    p.mesh = own.ToMesh();
    if (!p.mesh.triangles.empty()) context.parts->push_back(std::move(p));
  }
}

}  // namespace

OpenScadNodeResult EvaluateOpenScadNode(const Node& node, const ResolvedArgs& args, const fs::path& dir,
                                        OpenScadNodeContext& context) {
  const fs::path model = dir / args.Text("file");
  // A job bundle is all a worker's evaluation reads: a model naming a file
  // outside its directory is refused before anything reads that file, here
  // as at submit (model_files.h).
  if (context.confine_model_files) {
    try {
      scad::ModelFiles(model);
    } catch (const InputError& e) {
      throw DesignFault(e.what());
    }
  }
  const Overrides overrides = OverridesOf(args);
  WorkDir work(node.place.str());
  const std::string render = args.Text("render", "mesh");
  const bool native = render != "openscad";  // mesh (native) or levelset: fabatlas evaluates the CSG tree
  const fs::path out = work.path / (native ? "model.csg" : "model.stl");
  OpenScadNodeResult result;
  std::string text;
  result.export_seconds = ExportModel(node, model, overrides, native, out, &text, context.warnings);
  if (!native) {
    result.solid = RenderedModel(node, args, model, out, context);
    return result;
  }
  scad::CsgNode root;
  try {
    root = scad::ParseCsg(text, model.string() + " (OpenSCAD's CSG export)");
  } catch (const InputError& e) {
    throw SampleFailure(kNoGeometry, e.what());
  }
  csg::CsgEvaluation evaluation(context, model, work.path, /*mesh_road=*/render != "levelset");
  csg::CsgEvaluation::Result r = evaluation.Evaluate3(root, csg::kIdentity, context.path + "/csg", /*need_solid=*/true);
  result.solid = r.solid;
  result.root_key = r.key;
  result.root_trace = r.trace;
  if (context.parts) context.parts->clear();
  if (context.parts && !result.solid.empty())
    EvaluateParts(root, result.solid, model, work.path, /*mesh_road=*/render != "levelset", context);
  return result;
}

}  // namespace fabatlas::design
