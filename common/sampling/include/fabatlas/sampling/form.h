// fabatlas/sampling/form.h — the sampled form: k-d trees over the bootstrap
// cells, every sample, every ΔG value (Fab Forms, Sec. 5.1).
//
// One k-d tree per bootstrap cell. Every node is an axis-aligned box in key
// space (design_space.h); every leaf is a hypercube with a sample at each of
// its 2^n corners. The valid region is the union of leaves whose corners are
// all valid (Fab Forms, Sec. 5.1; faces/edges are ignored here, they have zero
// volume).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fabatlas/sampling/design_space.h"
#include "fabatlas/sampling/sample_evaluator.h"

namespace fabatlas::sampling {

struct FormSample {
  PointKey key;
  std::vector<double> u;
  SampleOutcome outcome;
};

// Why a leaf was not split further.
enum class LeafStop {
  kNone,          // interior node
  kThreshold,     // max ΔG over the leaf's edges < dg_threshold
  kMaxDepth,      // depth == max_depth
  kUnsplittable,  // every direction at or above the threshold is at its
                  // finest resolution (adjacent discrete values)
  kBudget,        // the global sample budget ran out
};

struct FormNode {
  std::vector<std::int64_t> lo, hi;  // box in keys, per dimension
  int depth = 0;                     // splits from the bootstrap cell
  int split_dimension = -1;          // -1 for a leaf
  std::int64_t split_key = 0;
  int children[2] = {-1, -1};  // indices into FormTree::nodes (lo, hi side)
  LeafStop stop = LeafStop::kNone;
};

struct FormTree {
  std::vector<int> cell;        // bootstrap cell index per dimension
  std::vector<FormNode> nodes;  // nodes[0] is the bootstrap cell
};

struct Form {
  std::vector<Dimension> dimensions;
  int subdivisions = 5;
  // Samples in id order; ids are assigned in ascending key order within each
  // evaluation round, so they are deterministic.
  std::vector<FormSample> samples;
  std::map<PointKey, std::int64_t> sample_ids;
  // Bootstrap cells in lexicographic cell order (last dimension fastest).
  std::vector<FormTree> trees;
  // Every ΔG computed, keyed by (smaller id, larger id).
  std::map<std::pair<std::int64_t, std::int64_t>, double> geometry_changes;

  DesignSpace space() const { return DesignSpace(dimensions, subdivisions); }
};

// Ids of the 2^n corners of a node; corner c has bit d set when it lies on
// the hi side along dimension d.
std::vector<std::int64_t> CornerSampleIds(const Form& form, const FormNode& node);
// True if every corner of the leaf is valid.
bool IsAllValidLeaf(const Form& form, const FormNode& node);

struct LeafRef {
  int tree = -1;
  int node = -1;
};
// The leaf containing point u (parameter values; enumerated = index). Points
// on a shared face go to the hi-side leaf except on the upper domain bound.
// Returns nullopt outside the bounded space.
std::optional<LeafRef> LocateLeaf(const Form& form, const std::vector<double>& u);
// Same, with the form's space passed in (saves rebuilding it per query).
std::optional<LeafRef> LocateLeaf(const Form& form, const DesignSpace& space, const std::vector<double>& u);
// u lies in an all-valid leaf (the estimated valid region, Fab Forms Sec. 5.1).
bool InEstimatedValidRegion(const Form& form, const std::vector<double>& u);
bool InEstimatedValidRegion(const Form& form, const DesignSpace& space, const std::vector<double>& u);

}  // namespace fabatlas::sampling
