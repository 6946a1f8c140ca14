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

// What a subtree computed with a subtree cache was (its record without path
// and time) and where its children sit below it, kept for the process, so
// that the subtree later found in the cache is recorded with the same
// children (the cache graph requires one set of children per key) and with
// the records of all its descendants, as sampling promises
// (EvaluateOptions::lookup_before_children = false): the cache plan may keep
// any descendant of a hit, and a cluster job's coordinator takes a kept
// subtree's geometry from a valid sample that lists it. Kept for the CSG
// subtrees of `openscad` nodes and for the nodes themselves (their one child
// is the CSG root, "/csg" below them); other design nodes evaluate their
// children before looking themselves up. Thread-safe; one entry (about
// 300 B) per distinct subtree computed, kept for the process.
struct ComputedSubtree {
  std::string topology, op;
  std::size_t bytes = 0;
  std::vector<std::string> children;     // keys, in tree order
  std::vector<std::string> child_paths;  // each child's path below this one ("/0", "/csg")
};
void RememberSubtree(const std::string& key, ComputedSubtree subtree);

// When this process computed `key`: sets *children to its children and, when
// `records` is not null, appends the records of its descendants (post-order,
// from_cache, 0 s, paths below `path`); returns false (nothing changed)
// otherwise.
bool RecallDescendants(const std::string& key, const std::string& path, std::vector<SubtreeRecord>* records,
                       std::vector<std::string>* children);

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
