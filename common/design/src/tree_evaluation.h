// Internal: the evaluation of a design's operation tree at one sample (Fab
// Forms Alg. 2, lines 7–9): bottom-up, every subtree keyed by (τ, ρ) (Sec. 6),
// recorded, looked up in and offered to the subtree cache; the objects and
// motions of reconfigurables and the assembly, for the checks.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "assembly_node.h"
#include "expression.h"
#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "openscad_node.h"
#include "operations.h"
#include "reconfigurable.h"

namespace fabatlas::design {

// Evaluates the operation tree bottom-up, keying every subtree by (τ, ρ).
// Not thread-safe; `d`, `scope`, `options` and `records` must outlive it.
class TreeEvaluation {
 public:
  TreeEvaluation(const Design& d, Scope& scope, const EvaluateOptions& options, std::vector<SubtreeRecord>& records)
      : design_(d), scope_(scope), options_(options), records_(&records) {
    grid_.voxel_size = d.voxel_size;
  }

  struct Result {
    geometry::Solid solid;
    std::string key, tau;
  };

  // An object of a reconfigurable in its body frame, evaluated once per sample.
  Result EvaluateObject(const std::string& name);

  const geometry::GridSpec& grid() const { return grid_; }

  // The design's first `assembly` node (depth first) solved at this sample.
  std::shared_ptr<const AssemblyOutcome> Assembly();

  // Meshes from outside fabatlas met while evaluating (for `watertight`).
  const std::vector<OutsideMesh>& Outside() const { return outside_; }
  const std::vector<std::string>& Warnings() const { return warnings_; }

  // Where subtree records go from now on.
  void RecordInto(std::vector<SubtreeRecord>* records) { records_ = records; }

  // The transitions' motions at this sample (resolved once).
  const std::vector<ResolvedTransition>& Transitions() {
    if (!transitions_) transitions_ = ResolveTransitions(design_, scope_);
    return *transitions_;
  }

  // The key and topology of a subtree and its children's keys, computed from the
  // resolved arguments alone (no geometry); memoised per node.
  struct Identity {
    std::string key, topology;  // topology = SHA-256 of τ, as Result::tau
    std::vector<std::string> children;
  };
  const Identity& IdentityOf(const Node& node);

  // The subtree `node` at record path `path`, its descendants recorded
  // before it (post-order).
  Result Evaluate(const Node& node, const std::string& path);

 private:
  // What carve_swept needs beyond its children: the moving object's
  // geometry and the resolved motions of the moving and frame objects.
  struct SweptOperands {
    Result moving;
    const ResolvedTransition* transition = nullptr;
    std::size_t moving_index = 0, frame_index = 0;
    bool has_frame = false;
  };

  // What a hit's trace brings (openscad_node.h, SubtreeTrace): the outside
  // meshes of its subtree and, for an `openscad` node (whose one child, its
  // CSG root, is known only once OpenSCAD has run), the child it had when
  // computed in `record` and, when `records` is not null, the records of the
  // CSG subtrees below it.
  void Recall(const Node& node, const CachedSubtree& hit, const std::string& path, SubtreeRecord& record,
              std::vector<SubtreeRecord>* records);

  static SubtreeRecord RecordOf(const Node& node, const Identity& id, const std::string& path);

  // Previews look a subtree up before evaluating its children, so a cached
  // subtree costs nothing below it (Fab Forms Sec. 6.2: traversal stops at
  // nodes in H): the hit, recorded; empty on a miss.
  std::optional<Result> LookUpBeforeChildren(const Node& node, const std::string& path);

  SweptOperands SweptOperandsOf(const ResolvedArgs& args);

  // Computes `node` from its children's solids (it was not found in the
  // cache): record.seconds its time (an `openscad` node's: OpenSCAD's
  // export), offered to the cache with its trace and the outside meshes met
  // since `outside_before`.
  geometry::Solid Compute(const Node& node, const ResolvedArgs& args, std::vector<Result>& children,
                          const SweptOperands& swept, bool parts_here, std::size_t outside_before,
                          const std::string& path, SubtreeRecord& record);

  // carve_swept: the union of its inputs carved by the moving object's swept volume.
  geometry::Solid CarveSweptNode(const Node& node, const ResolvedArgs& args, const std::vector<geometry::Solid>& inputs,
                                 const SweptOperands& swept);

  // An `openscad` node: its CSG subtrees are records (and cache entries) of
  // their own, before this one; *seconds is OpenSCAD's export; the node's
  // one child (its CSG root) goes into `record` and `trace` (when not null).
  geometry::Solid EvaluateOpenScad(const Node& node, const ResolvedArgs& args, const std::string& path, bool parts_here,
                                   SubtreeRecord& record, SubtreeTrace* trace, double* seconds);

  // The node's arguments evaluated at this sample (resolved_args.cc).
  ResolvedArgs Resolve(const Node& node);

  const Design& design_;
  Scope& scope_;
  const EvaluateOptions& options_;
  std::vector<SubtreeRecord>* records_;
  geometry::GridSpec grid_;
  std::map<const Node*, Identity> identities_;
  std::map<std::string, Result> objects_;
  std::vector<OutsideMesh> outside_;   // meshes from outside fabatlas met in this sample
  std::vector<std::string> warnings_;  // OpenSCAD's warnings and the mesh road's fallbacks, in evaluation order
  std::optional<std::vector<ResolvedTransition>> transitions_;
};

}  // namespace fabatlas::design
