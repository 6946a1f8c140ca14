// fabatlas/cache/dependency_graph.h — the dependency graph of subtrees across
// all samples (Fab Forms Sec. 6.2, Fig. 8) and the cost of a cache H on it:
// n_H(X), T_H(r), E_H[preview] (Eq. 3) and the worst case max_r T_H(r).
//
// Plain data in, plain data out: the library knows nothing about geometry,
// workers or storage. Units: seconds and bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fabatlas::cache {

// One subtree root evaluated for one sample (design::SubtreeRecord reduced to
// what cache planning needs). The same key may be given many times (once per
// sample that evaluated it): BuildDependencyGraph merges them.
struct SubtreeNode {
  std::string key;                    // identity (τ, ρ): design::SubtreeRecord::key
  std::vector<std::string> children;  // keys of the child subtrees, in order;
                                      // a key given twice is evaluated twice
  double seconds = 0.0;               // t: root compute time given its children (s, >= 0)
  std::uint64_t bytes = 0;            // size of the subtree's stored geometry
  bool stored = true;                 // geometry was kept: a plan may choose it
};

// One valid sample: the subtree at the root of its design tree. Samples are
// the roots r of the graph; each is previewed with equal probability (Eq. 3).
struct SampleTree {
  std::string root;  // key of the root subtree
};

// The merged graph. Node ids are positions in ascending key order, so every
// result built on ids is independent of the order the input came in.
struct DependencyGraph {
  std::vector<std::string> keys;                // node id -> key, ascending
  std::vector<double> seconds;                  // t_i: mean over the merged records
  std::vector<std::uint64_t> bytes;             // largest over the merged records
  std::vector<char> stored;                     // any merged record stored
  std::vector<std::int64_t> child_begin;        // CSR: children of i are
  std::vector<std::int32_t> child_ids;          //   child_ids[child_begin[i] .. child_begin[i+1])
  std::vector<std::int32_t> sample_roots;       // sample index -> root node id
  std::vector<std::int32_t> topological_order;  // every parent before its children

  std::int64_t node_count() const { return static_cast<std::int64_t>(keys.size()); }
  std::int64_t sample_count() const { return static_cast<std::int64_t>(sample_roots.size()); }
  // Node id of a key, or -1.
  std::int32_t Find(const std::string& key) const;
};

// Merges the records (t_i = mean of the seconds given for a key, summed in
// ascending order so the result does not depend on input order; bytes = the
// largest) and links children and sample roots. Throws fabatlas::InputError
// naming the key when a child or root key has no record, a key is recorded
// with different children, seconds are negative or not finite, or the graph
// has a cycle.
DependencyGraph BuildDependencyGraph(const std::vector<SubtreeNode>& nodes, const std::vector<SampleTree>& samples);

// A cache H as a membership flag per node id (size node_count()).
using CacheSet = std::vector<char>;

// n_H(X) per node: how many times X's root is evaluated over all samples with
// cache H (Sec. 6.2): 0 for X in H; otherwise the samples rooted at X plus,
// over every parent p not in H, n_H(p) times the number of times p uses X.
std::vector<double> EvaluationCounts(const DependencyGraph& graph, const CacheSet& cache);

// T_H(r) per sample: the sum of t over every evaluation needed to preview the
// sample, traversing children from its root and stopping at nodes in H.
std::vector<double> PreviewSeconds(const DependencyGraph& graph, const CacheSet& cache);

struct CacheCost {
  double mean_seconds = 0.0;   // E_H[preview] of Eq. 3 = Σ t_i n_H(X_i) / |R|
  double worst_seconds = 0.0;  // max_r T_H(r)
  std::uint64_t bytes = 0;     // Σ bytes over H
  std::int64_t entries = 0;    // |H|
};

CacheCost EvaluateCache(const DependencyGraph& graph, const CacheSet& cache);

// H_TOP: the root subtree of every sample (top-level geometry, Fab Forms
// Sec. 8 "Subtree cache vs. top-level geometry cache"), stored or not.
CacheSet TopLevelCache(const DependencyGraph& graph);

}  // namespace fabatlas::cache
