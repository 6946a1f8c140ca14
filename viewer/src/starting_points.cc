#include "fabatlas/viewer/starting_points.h"

#include <algorithm>
#include <limits>
#include <map>
#include <queue>
#include <random>
#include <set>

#include "fabatlas/viewer/snap.h"

namespace fabatlas::viewer {

namespace {

using Graph = std::vector<std::vector<std::pair<int, double>>>;  // node -> (neighbour, weight)
constexpr double kInf = std::numeric_limits<double>::infinity();

std::vector<double> Dijkstra(const Graph& g, int source) {
  std::vector<double> dist(g.size(), kInf);
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  dist[source] = 0;
  queue.push({0, source});
  while (!queue.empty()) {
    auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    for (auto [w, weight] : g[v])
      if (d + weight < dist[w]) {
        dist[w] = d + weight;
        queue.push({dist[w], w});
      }
  }
  return dist;
}

}  // namespace

std::vector<std::int64_t> StartingPoints(const sampling::Form& form, const StartingPointOptions& options) {
  // Nodes: valid samples.
  std::vector<std::int64_t> ids;
  std::map<std::int64_t, int> node_of;
  for (size_t i = 0; i < form.samples.size(); ++i)
    if (form.samples[i].outcome.valid) {
      node_of[static_cast<std::int64_t>(i)] = static_cast<int>(ids.size());
      ids.push_back(static_cast<std::int64_t>(i));
    }
  if (ids.empty() || options.count < 1) return {};
  Graph g(ids.size());
  std::set<std::pair<int, int>> seen;
  for (const auto& tree : form.trees)
    for (const auto& node : tree.nodes) {
      if (node.split_dimension >= 0) continue;
      const auto corners = sampling::CornerSampleIds(form, node);
      const int n = static_cast<int>(node.lo.size());
      for (size_t c = 0; c < corners.size(); ++c)
        for (int d = 0; d < n; ++d) {
          const size_t o = c ^ (size_t{1} << d);
          if (o < c) continue;
          const auto a = node_of.find(corners[c]), b = node_of.find(corners[o]);
          if (a == node_of.end() || b == node_of.end()) continue;
          if (!seen.insert({a->second, b->second}).second) continue;
          const double w = CachedGeometryChange(form, corners[c], corners[o]) + 1e-6;
          g[a->second].push_back({b->second, w});
          g[b->second].push_back({a->second, w});
        }
    }

  // Randomised farthest-point sampling.
  std::mt19937 rng(options.seed);
  const int first = std::uniform_int_distribution<int>(0, static_cast<int>(ids.size()) - 1)(rng);
  std::vector<int> seeds{first};
  std::vector<double> nearest = Dijkstra(g, first);
  std::vector<int> region(ids.size(), 0);
  while (static_cast<int>(seeds.size()) < std::min<int>(options.count, static_cast<int>(ids.size()))) {
    int far = -1;
    for (size_t v = 0; v < ids.size(); ++v)
      if (far < 0 || nearest[v] > nearest[far]) far = static_cast<int>(v);
    if (nearest[far] == 0) break;
    const std::vector<double> d = Dijkstra(g, far);
    for (size_t v = 0; v < ids.size(); ++v)
      if (d[v] < nearest[v]) {
        nearest[v] = d[v];
        region[v] = static_cast<int>(seeds.size());
      }
    seeds.push_back(far);
  }

  // Graph centroid of each region.
  std::vector<std::vector<int>> members(seeds.size());
  for (size_t v = 0; v < ids.size(); ++v) members[region[v]].push_back(static_cast<int>(v));
  std::vector<std::pair<size_t, std::int64_t>> picked;  // (region size, sample id)
  for (auto& nodes : members) {
    if (nodes.empty()) continue;
    std::vector<int> candidates = nodes;
    if (static_cast<int>(candidates.size()) > options.centroid_candidates) {
      std::shuffle(candidates.begin(), candidates.end(), rng);
      candidates.resize(options.centroid_candidates);
      std::sort(candidates.begin(), candidates.end());
    }
    int best = -1;
    double best_sum = kInf;
    for (int c : candidates) {
      const std::vector<double> d = Dijkstra(g, c);
      double sum = 0;
      for (int v : nodes) sum += d[v] == kInf ? 1e9 : d[v];
      if (sum < best_sum) {
        best_sum = sum;
        best = c;
      }
    }
    picked.push_back({nodes.size(), ids[best]});
  }
  std::stable_sort(picked.begin(), picked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::int64_t> out;
  for (const auto& p : picked) out.push_back(p.second);
  return out;
}

}  // namespace fabatlas::viewer
