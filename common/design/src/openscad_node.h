// Internal: the `openscad` node (docs/openscad.md). OpenSCAD evaluates the
// model to its CSG tree (`.csg` export, no render); fabatlas evaluates that
// tree with its own level-set operations, keying every CSG subtree by
// (τ, ρ) so it is cached like any subtree of a design (Fab Forms Sec. 6).
// Subtrees with no native equivalent are rendered by OpenSCAD alone.
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/mesh/triangle_mesh.h"
#include "operations.h"

namespace fabatlas::design {

// A mesh that entered the sample from outside fabatlas (a polyhedron of the
// model, OpenSCAD's render of a subtree, an imported file): what the
// watertight check inspects (checks.cc).
struct OutsideMesh {
  std::string what;  // e.g. "model.scad: OpenSCAD's render of text(...)"
  std::string key;   // content key (the subtree's), for remembering reports
  std::shared_ptr<const mesh::TriangleMesh> mesh;
};

// The outside meshes a subtree (by key) contained when it was computed, kept
// for the process, so that a subtree later found in a cache still brings its
// outside meshes to the watertight check. Thread-safe.
void RememberOutside(const std::string& subtree_key, const std::vector<OutsideMesh>& meshes);
void RecallOutside(const std::string& subtree_key, std::vector<OutsideMesh>* out);

// The CSG root key an `openscad` node (by its key) had when it was computed,
// kept for the process, so that the node's record found in a cache names
// the same child as when it was computed (the cache graph requires one set
// of children per key). Recall returns "" when this process never computed
// the node. Thread-safe; one pair of keys per distinct node evaluated.
void RememberCsgRoot(const std::string& node_key, const std::string& csg_root_key);
std::string RecallCsgRoot(const std::string& node_key);

struct OpenScadNodeContext {
  geometry::GridSpec grid;
  SubtreeCache* cache = nullptr;               // looked up and offered per CSG subtree
  std::vector<SubtreeRecord>* records = nullptr;  // CSG subtree records are appended (post-order)
  std::vector<OutsideMesh>* outside = nullptr;    // outside meshes are appended
  std::string path;                             // the node's record path; CSG subtrees are PATH/csg/...
};

// Record ops of CSG subtrees: "csg:NAME" evaluated with level sets,
// "csg-openscad:NAME" rendered by OpenSCAD (no native equivalent below it).
inline constexpr const char* kCsgNativeOp = "csg:";
inline constexpr const char* kCsgRenderedOp = "csg-openscad:";

struct OpenScadNodeResult {
  geometry::Solid solid;
  std::string root_key;        // the CSG root's key (the node's one child record); empty for render: openscad
  double export_seconds = 0;   // OpenSCAD's .csg export (or STL render) wall time
};

// `args` holds file, set (with OpenSCAD literals), render. Throws
// SampleFailure(no_geometry) when OpenSCAD rejects the model at this sample,
// DesignFault when OpenSCAD is missing.
OpenScadNodeResult EvaluateOpenScadNode(const Node& node, const ResolvedArgs& args, const std::filesystem::path& dir,
                                        OpenScadNodeContext& context);

}  // namespace fabatlas::design
