// Synthetic design-like dependency graphs for cache tests and benchmarks.
//
// A design with `parameters` exposed parameters, each taking `values` values;
// samples are random points of that grid. The tree has `parts` parts, each
// driven by its own random subset of the parameters (so parts are shared by
// every sample agreeing on that subset, like Fab Forms' chess pieces), each
// part built on a sub-part driven by one of its parameters, and a chain of
// unions on top (unique per sample). Times: parts 0.1-3 s, sub-parts 0.05-1 s,
// unions 0.01-0.5 s; bytes 1-100 MB. Deterministic for a given seed.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "fabatlas/cache/dependency_graph.h"

namespace fabatlas::cache::testing {

struct SyntheticDesign {
  int parameters = 3;
  int values = 4;
  int samples = 30;
  int parts = 3;
  std::uint64_t seed = 1;
};

struct SyntheticGraph {
  std::vector<SubtreeNode> nodes;
  std::vector<SampleTree> samples;
  std::vector<std::string> ops;  // per node, when read from a file
};

inline SyntheticGraph MakeSyntheticGraph(const SyntheticDesign& d) {
  std::mt19937_64 rng(d.seed);
  auto uniform = [&](double lo, double hi) {
    return lo + (hi - lo) * static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
  };
  auto bytes = [&] { return static_cast<std::uint64_t>(uniform(1e6, 1e8)); };
  // Each part's parameter subset (non-empty) and its sub-part's parameter.
  std::vector<std::vector<int>> depends(static_cast<std::size_t>(d.parts));
  std::vector<int> sub_depends(static_cast<std::size_t>(d.parts));
  for (int j = 0; j < d.parts; ++j) {
    for (int p = 0; p < d.parameters; ++p)
      if (rng() % 2) depends[static_cast<std::size_t>(j)].push_back(p);
    if (depends[static_cast<std::size_t>(j)].empty())
      depends[static_cast<std::size_t>(j)].push_back(
          static_cast<int>(rng() % static_cast<std::uint64_t>(d.parameters)));
    auto& dep = depends[static_cast<std::size_t>(j)];
    sub_depends[static_cast<std::size_t>(j)] = dep[rng() % dep.size()];
  }
  SyntheticGraph g;
  std::map<std::string, bool> made;
  std::vector<int> u(static_cast<std::size_t>(d.parameters));
  for (int s = 0; s < d.samples; ++s) {
    for (auto& x : u) x = static_cast<int>(rng() % static_cast<std::uint64_t>(d.values));
    std::string below;
    for (int j = 0; j < d.parts; ++j) {
      std::string sub = "s" + std::to_string(j) + ":" +
                        std::to_string(u[static_cast<std::size_t>(sub_depends[static_cast<std::size_t>(j)])]);
      if (!made[sub]) {
        made[sub] = true;
        g.nodes.push_back({sub, {}, uniform(0.05, 1.0), bytes(), true});
      }
      std::string part = "p" + std::to_string(j) + ":";
      for (int p : depends[static_cast<std::size_t>(j)]) part += std::to_string(u[static_cast<std::size_t>(p)]) + ",";
      if (!made[part]) {
        made[part] = true;
        g.nodes.push_back({part, {sub}, uniform(0.1, 3.0), bytes(), true});
      }
      if (j == 0) {
        below = part;
        continue;
      }
      std::string join = "u" + std::to_string(j) + "(" + below + "|" + part + ")";
      if (!made[join]) {
        made[join] = true;
        g.nodes.push_back({join, {below, part}, uniform(0.01, 0.5), bytes(), true});
      }
      below = join;
    }
    g.samples.push_back({below});
  }
  return g;
}

// Reads a graph saved by `bench_cache_real_designs --graphs DIR`: lines
// "N key seconds bytes op child,child,..." ("-" for no children), one per
// subtree record of every valid sample, and "S rootkey" per sample.
inline SyntheticGraph ReadGraphFile(const std::string& path) {
  std::ifstream in(path);
  SyntheticGraph g;
  std::string tag;
  while (in >> tag) {
    if (tag == "S") {
      SampleTree t;
      in >> t.root;
      g.samples.push_back(t);
      continue;
    }
    SubtreeNode n;
    std::string op, children;
    in >> n.key >> n.seconds >> n.bytes >> op >> children;
    if (children != "-")
      for (std::size_t at = 0; at <= children.size();) {
        std::size_t comma = children.find(',', at);
        if (comma == std::string::npos) comma = children.size();
        n.children.push_back(children.substr(at, comma - at));
        at = comma + 1;
      }
    g.nodes.push_back(n);
    g.ops.push_back(op);
  }
  return g;
}

}  // namespace fabatlas::cache::testing
