// ComputeSweptVolume: the swept volume of one carve_swept node at a sample,
// as a task of its own (evaluate_sample.h).
#include <string>
#include <vector>

#include "expression.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/raw_mesh.h"
#include "fabatlas/sha256.h"
#include "fabatlas/swept/swept_volume.h"
#include "reconfigurable.h"
#include "tree_evaluation.h"

namespace fabatlas::design {

SweptVolumeResult ComputeSweptVolume(const Design& design, const Point& u, const std::string& node_path) {
  const std::string where = design.file.string() + ": swept volume task '" + node_path + "'";
  // Find the node: "root/i/j" or "object:NAME/i/j".
  const Node* node = nullptr;
  std::string rest;
  if (node_path.rfind("root", 0) == 0) {
    node = &design.tree;
    rest = node_path.substr(4);
  } else if (node_path.rfind("object:", 0) == 0) {
    const std::size_t slash = node_path.find('/');
    const DesignObject* object =
        design.FindObject(node_path.substr(7, slash == std::string::npos ? std::string::npos : slash - 7));
    if (object) node = &object->tree;
    rest = slash == std::string::npos ? "" : node_path.substr(slash);
  }
  while (node && !rest.empty()) {
    if (rest[0] != '/') {
      node = nullptr;
      break;
    }
    std::size_t next = rest.find('/', 1);
    const std::string index = rest.substr(1, next == std::string::npos ? std::string::npos : next - 1);
    if (index.empty() || index.find_first_not_of("0123456789") != std::string::npos || index.size() > 6 ||
        std::stoul(index) >= node->children.size()) {
      node = nullptr;
      break;
    }
    node = &node->children[std::stoul(index)];
    rest = next == std::string::npos ? "" : rest.substr(next);
  }
  if (!node || node->op != "carve_swept") throw InputError(where + ": no carve_swept node at that path");

  ConstraintSolveSummary solve = SolveConstraints(design, u);
  if (!solve.satisfiable)
    throw InputError(where + ": constraint '" + solve.worst_constraint + "' is not satisfiable here");
  Scope scope(ParameterNames(design));
  for (const auto& [name, value] : solve.values) scope.Set(name, value);
  std::vector<SubtreeRecord> records;
  EvaluateOptions options;
  TreeEvaluation tree(design, scope, options, records);
  auto text = [&](const char* key) {
    auto it = node->args.find(key);
    return it == node->args.end() ? std::string() : it->second.text;
  };
  auto number = [&](const char* key, double fallback) {
    auto it = node->args.find(key);
    return it == node->args.end() ? fallback : Expression(it->second.text, scope, it->second.place).Evaluate();
  };
  try {
    const geometry::Solid moving = tree.EvaluateObject(text("moving")).solid;
    const ResolvedTransition* transition = nullptr;
    for (const auto& t : tree.Transitions())
      if (t.name == text("transition")) transition = &t;
    const swept::RigidMotion still;
    const swept::RigidMotion& f_frame =
        text("frame").empty() ? still : transition->motions[ObjectIndex(design, text("frame"))];
    swept::SweptVolumeSummary summary;
    const mesh::TriangleMesh surface =
        SweptCutter(moving, transition->motions[ObjectIndex(design, text("moving"))], f_frame, number("offset", 0),
                    static_cast<int>(number("time_steps", 2)), tree.grid(), node->place, &summary);
    SweptVolumeResult r;
    r.volume = mesh::EnclosedVolume(surface);
    r.triangles = surface.triangles.size();
    r.time_steps = summary.time_steps;
    r.active_voxels = summary.active_voxels;
    r.surface_bytes = mesh::RawMeshBytes(surface);
    r.surface_sha256 = Sha256Hex(r.surface_bytes);
    return r;
  } catch (const SampleFailure& e) {
    throw InputError(where + ": " + e.what());
  }
}

}  // namespace fabatlas::design
