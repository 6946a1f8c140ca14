// Fab Forms Sec. 6.2: the subtree dependency graph and the cost of a cache.
#include "fabatlas/cache/dependency_graph.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "fabatlas/error.h"

namespace fabatlas::cache {

std::int32_t DependencyGraph::Find(const std::string& key) const {
  auto it = std::lower_bound(keys.begin(), keys.end(), key);
  if (it == keys.end() || *it != key) return -1;
  return static_cast<std::int32_t>(it - keys.begin());
}

DependencyGraph BuildDependencyGraph(const std::vector<SubtreeNode>& nodes, const std::vector<SampleTree>& samples) {
  DependencyGraph g;
  // Order the records by key (stable pointers into the input).
  std::vector<const SubtreeNode*> order(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) order[i] = &nodes[i];
  std::sort(order.begin(), order.end(), [](const SubtreeNode* a, const SubtreeNode* b) { return a->key < b->key; });
  std::vector<const SubtreeNode*> first;  // one record per key
  std::vector<double> times;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    times.clear();
    std::uint64_t bytes = 0;
    bool stored = false;
    for (; j < order.size() && order[j]->key == order[i]->key; ++j) {
      const SubtreeNode& n = *order[j];
      if (!std::isfinite(n.seconds) || n.seconds < 0)
        throw InputError("cache graph: subtree " + n.key + " has compute time " + std::to_string(n.seconds) +
                         " s (must be finite and >= 0)");
      if (n.children != order[i]->children)
        throw InputError("cache graph: subtree " + n.key + " is recorded with different children");
      times.push_back(n.seconds);
      bytes = std::max(bytes, n.bytes);
      stored = stored || n.stored;
    }
    std::sort(times.begin(), times.end());
    double sum = 0;
    for (double t : times) sum += t;
    g.keys.push_back(order[i]->key);
    g.seconds.push_back(sum / static_cast<double>(times.size()));
    g.bytes.push_back(bytes);
    g.stored.push_back(stored ? 1 : 0);
    first.push_back(order[i]);
    i = j;
  }
  const std::size_t n = g.keys.size();
  if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw InputError("cache graph: too many subtrees (" + std::to_string(n) + ")");
  g.child_begin.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    g.child_begin[i + 1] = g.child_begin[i] + static_cast<std::int64_t>(first[i]->children.size());
  }
  g.child_ids.resize(static_cast<std::size_t>(g.child_begin[n]));
  for (std::size_t i = 0; i < n; ++i) {
    std::int64_t at = g.child_begin[i];
    for (const std::string& c : first[i]->children) {
      std::int32_t id = g.Find(c);
      if (id < 0) throw InputError("cache graph: subtree " + g.keys[i] + " has child " + c + " with no record");
      g.child_ids[static_cast<std::size_t>(at++)] = id;
    }
  }
  for (std::size_t s = 0; s < samples.size(); ++s) {
    std::int32_t id = g.Find(samples[s].root);
    if (id < 0)
      throw InputError("cache graph: sample " + std::to_string(s) + " has root " + samples[s].root + " with no record");
    g.sample_roots.push_back(id);
  }
  // Kahn's algorithm, parents before children; smallest id first among ready
  // nodes is not needed for correctness, a FIFO keeps it deterministic.
  std::vector<std::int32_t> parents(n, 0);
  for (std::int32_t c : g.child_ids) ++parents[static_cast<std::size_t>(c)];
  g.topological_order.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    if (parents[i] == 0) g.topological_order.push_back(static_cast<std::int32_t>(i));
  for (std::size_t head = 0; head < g.topological_order.size(); ++head) {
    std::int32_t v = g.topological_order[head];
    for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e) {
      std::int32_t c = g.child_ids[static_cast<std::size_t>(e)];
      if (--parents[static_cast<std::size_t>(c)] == 0) g.topological_order.push_back(c);
    }
  }
  if (g.topological_order.size() != n) {
    for (std::size_t i = 0; i < n; ++i)
      if (parents[i] > 0) throw InputError("cache graph: subtree " + g.keys[i] + " lies on a dependency cycle");
  }
  return g;
}

namespace {
void CheckCacheSize(const DependencyGraph& g, const CacheSet& cache) {
  if (cache.size() != g.keys.size())
    throw InputError("cache set has " + std::to_string(cache.size()) + " flags for " + std::to_string(g.keys.size()) +
                     " subtrees");
}

// Requests per node: how many times the node is asked for (whether it is then
// computed or loaded from H).
std::vector<double> Requests(const DependencyGraph& g, const CacheSet& cache) {
  std::vector<double> q(g.keys.size(), 0.0);
  for (std::int32_t r : g.sample_roots) q[static_cast<std::size_t>(r)] += 1;
  for (std::int32_t v : g.topological_order) {
    if (cache[static_cast<std::size_t>(v)] || q[static_cast<std::size_t>(v)] == 0) continue;
    for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e)
      q[static_cast<std::size_t>(g.child_ids[static_cast<std::size_t>(e)])] += q[static_cast<std::size_t>(v)];
  }
  return q;
}
}  // namespace

std::vector<double> EvaluationCounts(const DependencyGraph& graph, const CacheSet& cache) {
  CheckCacheSize(graph, cache);
  std::vector<double> q = Requests(graph, cache);
  for (std::size_t i = 0; i < q.size(); ++i)
    if (cache[i]) q[i] = 0;
  return q;
}

std::vector<double> PreviewSeconds(const DependencyGraph& graph, const CacheSet& cache) {
  CheckCacheSize(graph, cache);
  // C(X): time to compute X from scratch given H below it, children first.
  std::vector<double> c(graph.keys.size(), 0.0);
  for (auto it = graph.topological_order.rbegin(); it != graph.topological_order.rend(); ++it) {
    std::int32_t v = *it;
    double sum = graph.seconds[static_cast<std::size_t>(v)];
    for (std::int64_t e = graph.child_begin[v]; e < graph.child_begin[v + 1]; ++e) {
      std::int32_t ch = graph.child_ids[static_cast<std::size_t>(e)];
      if (!cache[static_cast<std::size_t>(ch)]) sum += c[static_cast<std::size_t>(ch)];
    }
    c[static_cast<std::size_t>(v)] = sum;
  }
  std::vector<double> t;
  t.reserve(graph.sample_roots.size());
  for (std::int32_t r : graph.sample_roots)
    t.push_back(cache[static_cast<std::size_t>(r)] ? 0.0 : c[static_cast<std::size_t>(r)]);
  return t;
}

CacheCost EvaluateCache(const DependencyGraph& graph, const CacheSet& cache) {
  CacheCost cost;
  std::vector<double> t = PreviewSeconds(graph, cache);
  // Summed in ascending order: the mean does not depend on sample order.
  std::sort(t.begin(), t.end());
  double sum = 0;
  for (double x : t) {
    sum += x;
    cost.worst_seconds = std::max(cost.worst_seconds, x);
  }
  cost.mean_seconds = t.empty() ? 0.0 : sum / static_cast<double>(t.size());
  for (std::size_t i = 0; i < cache.size(); ++i)
    if (cache[i]) {
      cost.bytes += graph.bytes[i];
      ++cost.entries;
    }
  return cost;
}

CacheSet TopLevelCache(const DependencyGraph& graph) {
  CacheSet h(graph.keys.size(), 0);
  for (std::int32_t r : graph.sample_roots) h[static_cast<std::size_t>(r)] = 1;
  return h;
}

}  // namespace fabatlas::cache
