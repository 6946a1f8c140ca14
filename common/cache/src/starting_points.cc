// Customisation starting points, Fab Forms Sec. 7.4: randomised farthest-point
// sampling on the graph of valid samples (ΔG edge weights) and the graph
// centroid of each segment.
#include "fabatlas/cache/starting_points.h"

#include <algorithm>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <utility>

namespace fabatlas::cache {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

struct ValidGraph {
  std::vector<std::int64_t> ids;                         // local -> form sample id
  std::vector<std::vector<std::pair<int, double>>> adj;  // local adjacency, ΔG weights
};

ValidGraph BuildValidGraph(const sampling::Form& form) {
  ValidGraph vg;
  std::map<std::int64_t, int> local;
  for (std::size_t i = 0; i < form.samples.size(); ++i)
    if (form.samples[i].outcome.valid) {
      local[static_cast<std::int64_t>(i)] = static_cast<int>(vg.ids.size());
      vg.ids.push_back(static_cast<std::int64_t>(i));
    }
  vg.adj.resize(vg.ids.size());
  std::map<std::pair<int, int>, double> edges;
  const std::size_t dims = form.dimensions.size();
  for (const sampling::FormTree& tree : form.trees)
    for (const sampling::FormNode& node : tree.nodes) {
      if (node.children[0] >= 0) continue;  // interior
      std::vector<std::int64_t> corners = sampling::CornerSampleIds(form, node);
      for (std::size_t c = 0; c < corners.size(); ++c)
        for (std::size_t d = 0; d < dims; ++d) {
          if (c & (std::size_t{1} << d)) continue;
          std::int64_t a = corners[c], b = corners[c | (std::size_t{1} << d)];
          auto la = local.find(a), lb = local.find(b);
          if (la == local.end() || lb == local.end() || a == b) continue;
          auto dg = form.geometry_changes.find({std::min(a, b), std::max(a, b)});
          if (dg == form.geometry_changes.end()) continue;
          edges[{std::min(la->second, lb->second), std::max(la->second, lb->second)}] = dg->second;
        }
    }
  for (auto [e, w] : edges) {
    vg.adj[static_cast<std::size_t>(e.first)].push_back({e.second, w});
    vg.adj[static_cast<std::size_t>(e.second)].push_back({e.first, w});
  }
  return vg;
}

// Dijkstra from `source` over nodes with allowed(v); writes dist (kInf when
// not reached) for the nodes it reaches, starting from `dist` as given when
// `improve_only` (multi-source farthest-point update) or from kInf.
void Dijkstra(const ValidGraph& g, int source, std::vector<double>& dist, const std::function<bool(int)>& allowed,
              std::vector<int>* owner = nullptr, int owner_id = -1) {
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> heap;
  dist[static_cast<std::size_t>(source)] = 0;
  if (owner) (*owner)[static_cast<std::size_t>(source)] = owner_id;
  heap.push({0.0, source});
  while (!heap.empty()) {
    auto [d, v] = heap.top();
    heap.pop();
    if (d > dist[static_cast<std::size_t>(v)]) continue;
    for (auto [w, weight] : g.adj[static_cast<std::size_t>(v)]) {
      if (!allowed(w)) continue;
      double nd = d + weight;
      if (nd < dist[static_cast<std::size_t>(w)]) {
        dist[static_cast<std::size_t>(w)] = nd;
        if (owner) (*owner)[static_cast<std::size_t>(w)] = owner_id;
        heap.push({nd, w});
      }
    }
  }
}

// Sum of distances from v to the segment's members within the segment:
// (members not reached, sum over reached).
std::pair<std::int64_t, double> Spread(const ValidGraph& g, int v, const std::vector<int>& members,
                                       const std::function<bool(int)>& in_segment, std::vector<double>& dist) {
  for (int m : members) dist[static_cast<std::size_t>(m)] = kInf;
  Dijkstra(g, v, dist, in_segment);
  std::int64_t unreached = 0;
  double sum = 0;
  for (int m : members) {
    double d = dist[static_cast<std::size_t>(m)];
    if (d == kInf)
      ++unreached;
    else
      sum += d;
  }
  return {unreached, sum};
}

// Connected components of g, numbered by their lowest sample id.
std::vector<int> Components(const ValidGraph& g) {
  const int n = static_cast<int>(g.ids.size());
  std::vector<int> component(static_cast<std::size_t>(n), -1);
  int components = 0;
  for (int s = 0; s < n; ++s) {
    if (component[static_cast<std::size_t>(s)] >= 0) continue;
    std::vector<int> stack{s};
    component[static_cast<std::size_t>(s)] = components;
    while (!stack.empty()) {
      int v = stack.back();
      stack.pop_back();
      for (auto [w, _] : g.adj[static_cast<std::size_t>(v)])
        if (component[static_cast<std::size_t>(w)] < 0) {
          component[static_cast<std::size_t>(w)] = components;
          stack.push_back(w);
        }
    }
    ++components;
  }
  return component;
}

// Randomised farthest-point sampling on g (at least one node) from a random
// first seed: options.count seeds (at least one, more when components remain
// unreached), fewer when every node is a seed. *owner: each node's nearest
// seed (index into the result).
std::vector<int> FarthestPointSeeds(const ValidGraph& g, const StartingPointOptions& options, std::vector<int>* owner) {
  const int n = static_cast<int>(g.ids.size());
  auto everywhere = [](int) { return true; };
  std::mt19937_64 rng(options.seed);
  std::vector<double> dist(static_cast<std::size_t>(n), kInf);
  owner->assign(static_cast<std::size_t>(n), -1);
  std::vector<int> seeds;
  const int wanted = std::max(options.count, 1);
  int next = static_cast<int>(rng() % static_cast<std::uint64_t>(n));
  while (true) {
    int owner_id = static_cast<int>(seeds.size());
    seeds.push_back(next);
    Dijkstra(g, next, dist, everywhere, owner, owner_id);
    // The farthest sample from all seeds (unreached components first).
    int far = -1;
    for (int v = 0; v < n; ++v)
      if (far < 0 || dist[static_cast<std::size_t>(v)] > dist[static_cast<std::size_t>(far)]) far = v;
    double far_dist = dist[static_cast<std::size_t>(far)];
    if (far_dist == kInf) {
      next = far;
      continue;
    }
    if (static_cast<int>(seeds.size()) >= wanted || far_dist <= 0) break;
    next = far;
  }
  return seeds;
}

using SpreadValue = std::pair<std::int64_t, double>;  // (members not reached, sum of distances)

bool Better(SpreadValue a, SpreadValue b) { return a.first < b.first || (a.first == b.first && a.second < b.second); }

// The exact graph centroid of segment m (seed `seed`): the member of least
// spread, the lowest on ties, the seed when none beats it.
int ExactCentroid(const ValidGraph& g, int seed, const std::vector<int>& m, const std::function<bool(int)>& in_segment,
                  std::vector<double>& scratch) {
  int best = seed;
  auto best_spread = Spread(g, best, m, in_segment, scratch);
  for (int v : m) {
    auto sp = Spread(g, v, m, in_segment, scratch);
    if (Better(sp, best_spread) || (sp == best_spread && v < best)) {
      best = v;
      best_spread = sp;
    }
  }
  return best;
}

// An approximate graph centroid of segment m (seed `seed`) by double sweep:
// the middle of a long shortest path, then descent to a neighbour of less
// spread while there is one.
int SweptCentroid(const ValidGraph& g, int seed, const std::vector<int>& m, const std::function<bool(int)>& in_segment,
                  std::vector<double>& scratch) {
  const int n = static_cast<int>(g.ids.size());
  auto farthest = [&](int from, std::vector<double>& d) {
    for (int v : m) d[static_cast<std::size_t>(v)] = kInf;
    Dijkstra(g, from, d, in_segment);
    int far = from;
    for (int v : m)
      if (d[static_cast<std::size_t>(v)] != kInf && d[static_cast<std::size_t>(v)] > d[static_cast<std::size_t>(far)])
        far = v;
    return far;
  };
  std::vector<double> da(static_cast<std::size_t>(n), kInf), db(static_cast<std::size_t>(n), kInf);
  int a = farthest(seed, da);
  int b = farthest(a, da);
  farthest(b, db);
  double length = da[static_cast<std::size_t>(b)];
  int mid = a;
  double mid_score = kInf;
  for (int v : m) {
    double x = da[static_cast<std::size_t>(v)], y = db[static_cast<std::size_t>(v)];
    if (x == kInf || y == kInf) continue;
    double score = std::abs(x - length / 2) + std::abs(y - length / 2);
    if (score < mid_score) {
      mid = v;
      mid_score = score;
    }
  }
  int best = mid;
  auto best_spread = Spread(g, best, m, in_segment, scratch);
  for (bool moved = true; moved;) {
    moved = false;
    for (auto [w, _] : g.adj[static_cast<std::size_t>(best)]) {
      if (!in_segment(w)) continue;
      auto sp = Spread(g, w, m, in_segment, scratch);
      if (Better(sp, best_spread)) {
        best = w;
        best_spread = sp;
        moved = true;
        break;
      }
    }
  }
  return best;
}
}  // namespace

std::vector<StartingPoint> ChooseStartingPoints(const sampling::Form& form, const StartingPointOptions& options) {
  std::vector<StartingPoint> out;
  ValidGraph g = BuildValidGraph(form);
  const int n = static_cast<int>(g.ids.size());
  if (n == 0) return out;
  const std::vector<int> component = Components(g);
  std::vector<int> owner;
  const std::vector<int> seeds = FarthestPointSeeds(g, options, &owner);

  // Graph centroid of each segment.
  std::vector<std::vector<int>> members(seeds.size());
  for (int v = 0; v < n; ++v) members[static_cast<std::size_t>(owner[static_cast<std::size_t>(v)])].push_back(v);
  std::vector<double> scratch(static_cast<std::size_t>(n), kInf);
  for (std::size_t s = 0; s < seeds.size(); ++s) {
    const std::vector<int>& m = members[s];
    const int id = static_cast<int>(s);
    auto in_segment = [&](int v) { return owner[static_cast<std::size_t>(v)] == id; };
    const int best = static_cast<std::int64_t>(m.size()) <= options.max_exact_centroid
                         ? ExactCentroid(g, seeds[s], m, in_segment, scratch)
                         : SweptCentroid(g, seeds[s], m, in_segment, scratch);
    StartingPoint p;
    p.sample_id = g.ids[static_cast<std::size_t>(best)];
    p.u = form.samples[static_cast<std::size_t>(p.sample_id)].u;
    p.seed_id = g.ids[static_cast<std::size_t>(seeds[s])];
    p.component = component[static_cast<std::size_t>(best)];
    p.segment_size = static_cast<std::int64_t>(m.size());
    out.push_back(std::move(p));
  }
  return out;
}

}  // namespace fabatlas::cache
