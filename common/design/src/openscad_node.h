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

// What a subtree computed with a subtree cache keeps beside its geometry in
// the cache entry (subtree_cache.h, CachedSubtree::trace), so that a later
// hit brings what the computation brought and its memory is bounded by the
// cache's budget:
//  - for the CSG subtrees of `openscad` nodes and the nodes themselves (their
//    one child is the CSG root, "/csg" below them), the subtree's record
//    without path and time and its children's traces: a hit is recorded
//    with the same children (the cache graph requires one set of children
//    per key) and with the records of all its descendants, as sampling
//    promises (EvaluateOptions::lookup_before_children = false), because
//    the cache plan may keep any descendant of a hit and a cluster job's
//    coordinator takes a kept subtree's geometry from a valid sample that
//    lists it. Other design nodes evaluate their children before looking
//    themselves up and keep no record (`op` empty);
//  - the meshes that entered the subtree from outside fabatlas, so that a
//    hit still brings them to the watertight check.
// Immutable once built; shared between a parent's trace and its children's.
struct SubtreeTrace {
  std::string topology, op;                                       // op empty: no record kept
  std::size_t bytes = 0;                                          // the subtree's grid bytes (its record's)
  std::vector<std::string> children;                              // keys, in tree order
  std::vector<std::string> child_paths;                           // each child's path below this one ("/0", "/csg")
  std::vector<std::shared_ptr<const SubtreeTrace>> child_traces;  // per child; null: none kept
  std::vector<OutsideMesh> outside;  // every outside mesh of the subtree, in evaluation order
};

// The cache entry of a computed subtree: its solid and `trace` (dropped when
// it holds nothing), with the trace's memory counted (its strings, its
// meshes and its children's traces: a mesh shared with a descendant's entry
// is counted in both, so a budget bounds the memory from above).
CachedSubtree EntryOf(geometry::Solid solid, std::shared_ptr<const SubtreeTrace> trace);

// Appends the records of the descendants `trace` holds (post-order,
// from_cache, 0 s, paths below `path`) to *records.
void AppendDescendantRecords(const SubtreeTrace& trace, const std::string& path, std::vector<SubtreeRecord>* records);

struct OpenScadNodeContext {
  geometry::GridSpec grid;
  SubtreeCache* cache = nullptr;                  // looked up and offered per CSG subtree
  std::vector<SubtreeRecord>* records = nullptr;  // CSG subtree records are appended (post-order)
  std::vector<OutsideMesh>* outside = nullptr;    // outside meshes are appended
  std::vector<std::string>* warnings = nullptr;   // what OpenSCAD would warn, and the mesh road's fallbacks
  bool confine_model_files = false;               // EvaluateOptions::confine_model_files
  std::string path;                               // the node's record path; CSG subtrees are PATH/csg/...
  std::vector<Part>* parts = nullptr;             // when set: the model's bodies and colour regions (PartTrees)
};

// Record ops of CSG subtrees: "csg:NAME" evaluated by fabatlas (exact
// meshes on the mesh road, level sets on the level-set road),
// "csg-openscad:NAME" rendered by OpenSCAD (no native equivalent below it),
// "csg-levelset:NAME" a boolean of the mesh road that fell back to level sets
// (an operand is a level set, or the exact booleans could not take it).
inline constexpr const char* kCsgNativeOp = "csg:";
inline constexpr const char* kCsgRenderedOp = "csg-openscad:";
inline constexpr const char* kCsgLevelSetOp = "csg-levelset:";

struct OpenScadNodeResult {
  geometry::Solid solid;
  std::string root_key;  // the CSG root's key (the node's one child record); empty for render: openscad
  std::shared_ptr<const SubtreeTrace> root_trace;  // the CSG root's, when computed with a cache
  double export_seconds = 0;                       // OpenSCAD's .csg export (or STL render) wall time
};

// `args` holds file, set (with OpenSCAD literals), render. Throws
// SampleFailure(no_geometry) when OpenSCAD rejects the model at this sample,
// DesignFault when OpenSCAD is missing.
OpenScadNodeResult EvaluateOpenScadNode(const Node& node, const ResolvedArgs& args, const std::filesystem::path& dir,
                                        OpenScadNodeContext& context);

}  // namespace fabatlas::design
