#include "fabatlas/assembly/precheck.h"

#include <algorithm>
#include <limits>
#include <map>
#include <queue>

namespace fabatlas::assembly {

bool PolygonInequalityFeasible(const std::vector<CycleLink>& links, double slack) {
  double sum_hi = 0;
  for (const auto& l : links) sum_hi += l.max_span_mm;
  for (const auto& l : links)
    if (l.min_span_mm > sum_hi - l.max_span_mm + slack) return false;
  return true;
}

namespace {

// Sampled connector positions of a primitive over its parameter box.
std::vector<Eigen::Vector3d> SamplePositions(const Primitive& p, int n) {
  const auto specs = p.Params();
  std::vector<std::vector<double>> axes;
  for (const auto& s : specs) {
    std::vector<double> v;
    const int m = s.kind == ParamKind::kUnbounded ? 2 * n : n;
    for (int i = 0; i < m; ++i)
      v.push_back(s.kind == ParamKind::kUnbounded ? s.min + (s.max - s.min) * i / m
                                                  : s.min + (s.max - s.min) * i / std::max(1, m - 1));
    axes.push_back(v);
  }
  std::vector<Eigen::Vector3d> out;
  std::vector<double> s(specs.size());
  std::vector<size_t> idx(specs.size(), 0);
  while (true) {
    for (size_t i = 0; i < specs.size(); ++i) s[i] = axes[i][idx[i]];
    out.push_back(ConnectorFrame(p, s).translation());
    size_t k = 0;
    while (k < idx.size() && ++idx[k] == axes[k].size()) idx[k++] = 0;
    if (k == idx.size()) break;
  }
  return out;
}

void Span(const Primitive& a, const Primitive& b, int n, double& lo, double& hi) {
  const auto pa = SamplePositions(a, n), pb = SamplePositions(b, n);
  lo = std::numeric_limits<double>::max();
  hi = 0;
  for (const auto& x : pa)
    for (const auto& y : pb) {
      const double d = (x - y).norm();
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  if (&a == &b) lo = 0;  // two connections on the same primitive may touch
}

// Records a failed check of connection c: sum->ok false, and an issue naming
// the connection's place and connectors.
void AddIssue(const Program& prog, PrecheckFailure f, const Connection& c, const std::string& what,
              PrecheckSummary* sum) {
  sum->ok = false;
  sum->issues.push_back({f, c.where + ": connect " + prog.instances[c.part_a].name + "." + c.primitive_a + " - " +
                                prog.instances[c.part_b].name + "." + c.primitive_b + ": " + what});
}

// 4.3.1: connectivity table and closed primitives.
void CheckConnectable(const Program& prog, PrecheckSummary* sum) {
  for (const auto& c : prog.connections) {
    const Primitive& a = prog.PrimitiveA(c);
    const Primitive& b = prog.PrimitiveB(c);
    if (!CanConnect(a.type, b.type))
      AddIssue(prog, PrecheckFailure::kNotConnectable, c,
               std::string(ToString(a.type)) + " cannot connect to " + ToString(b.type) + " (FabHacks Table 1)", sum);
    else if (a.closed && b.closed)
      AddIssue(prog, PrecheckFailure::kBothClosed, c,
               "both primitives are closed; there is no motion path to connect them", sum);
  }
}

// 4.1 critical dimensions: each primitive's available critical dimension
// must hold everything connected to it.
void CheckCriticalDimensions(const Program& prog, PrecheckSummary* sum) {
  std::map<std::pair<int, std::string>, double> used;
  for (const auto& c : prog.connections) {
    const Primitive& a = prog.PrimitiveA(c);
    const Primitive& b = prog.PrimitiveB(c);
    const bool is_a_hoop = a.type == PrimitiveType::kHook || a.type == PrimitiveType::kRing;
    const bool is_b_hoop = b.type == PrimitiveType::kHook || b.type == PrimitiveType::kRing;
    auto consume = [&](int inst, const Primitive& host, const Primitive& guest, bool host_is_hoop) {
      if (host.type == PrimitiveType::kHemisphere || host.type == PrimitiveType::kSurface) return;
      double& u = used[{inst, host.name}];
      // A hoop holding a hoop: wire diameters share the inner radius.
      u += host_is_hoop && guest.type != PrimitiveType::kRod && guest.type != PrimitiveType::kTube
               ? guest.OccupiedSize(host.type) / 2
               : guest.OccupiedSize(host.type);
      if (u > host.CriticalDimension() + 1e-9)
        AddIssue(prog, PrecheckFailure::kCriticalDimension, c,
                 "critical dimension of " + prog.instances[inst].name + "." + host.name + " exhausted (needs " +
                     std::to_string(u) + " mm, has " + std::to_string(host.CriticalDimension()) + " mm)",
                 sum);
    };
    consume(c.part_a, a, b, is_a_hoop);
    consume(c.part_b, b, a, is_b_hoop);
  }
}

// Breadth-first spanning tree of the parts from the environment (part 0):
// each part's tree connection (-1 for the environment, -2 when not reached)
// and depth, and which connections are tree edges.
struct SpanningTree {
  std::vector<int> parent_edge, depth;
  std::vector<bool> tree_edge;
};

SpanningTree BuildSpanningTree(const Program& prog) {
  const int n = static_cast<int>(prog.instances.size());
  std::vector<std::vector<int>> adj(n);
  for (int i = 0; i < static_cast<int>(prog.connections.size()); ++i) {
    adj[prog.connections[i].part_a].push_back(i);
    adj[prog.connections[i].part_b].push_back(i);
  }
  SpanningTree t{std::vector<int>(n, -2), std::vector<int>(n, 0), std::vector<bool>(prog.connections.size(), false)};
  t.parent_edge[0] = -1;
  std::queue<int> q;
  q.push(0);
  while (!q.empty()) {
    const int u = q.front();
    q.pop();
    for (int e : adj[u]) {
      const auto& c = prog.connections[e];
      const int v = c.part_a == u ? c.part_b : c.part_a;
      if (t.parent_edge[v] != -2) continue;
      t.parent_edge[v] = e;
      t.depth[v] = t.depth[u] + 1;
      t.tree_edge[e] = true;
      q.push(v);
    }
  }
  return t;
}

// The rigid links of the cycle that non-tree connection e closes: its edges
// in order (e from a to b, then b up to the lowest common ancestor, then
// down to a), each part between consecutive edges one link with its span
// range (mm) between the two connectors.
std::vector<CycleLink> CycleLinks(const Program& prog, const SpanningTree& tree, int e, const PrecheckOptions& opt) {
  auto other = [&](int edge, int part) {
    return prog.connections[edge].part_a == part ? prog.connections[edge].part_b : prog.connections[edge].part_a;
  };
  auto prim_at = [&](int edge, int part) -> const Primitive& {
    const auto& con = prog.connections[edge];
    return con.part_a == part ? prog.PrimitiveA(con) : prog.PrimitiveB(con);
  };
  const auto& c = prog.connections[e];
  // Cycle edges: path a -> lca, path b -> lca, plus e.
  std::vector<int> pa, pb;
  int u = c.part_a, v = c.part_b;
  while (u != v) {
    if (tree.depth[u] >= tree.depth[v]) {
      pa.push_back(tree.parent_edge[u]);
      u = other(tree.parent_edge[u], u);
    } else {
      pb.push_back(tree.parent_edge[v]);
      v = other(tree.parent_edge[v], v);
    }
  }
  // Ordered edge loop: e (a->b), then b up to lca, then lca down to a.
  std::vector<int> loop{e};
  loop.insert(loop.end(), pb.begin(), pb.end());
  loop.insert(loop.end(), pa.rbegin(), pa.rend());
  // Walk the loop; each part between consecutive edges is one rigid link.
  std::vector<CycleLink> links;
  int cur = c.part_b;
  for (size_t k = 0; k < loop.size(); ++k) {
    const int in = loop[k], out = loop[(k + 1) % loop.size()];
    CycleLink link;
    link.part = prog.instances[cur].name;
    Span(prim_at(in, cur), prim_at(out, cur), opt.samples_per_param, link.min_span_mm, link.max_span_mm);
    links.push_back(link);
    cur = other(out, cur);
  }
  return links;
}

}  // namespace

PrecheckSummary Precheck(const Program& prog, const PrecheckOptions& opt) {
  PrecheckSummary sum;
  CheckConnectable(prog, &sum);
  CheckCriticalDimensions(prog, &sum);
  // Spanning tree from the environment; every non-tree connection closes a cycle.
  const SpanningTree tree = BuildSpanningTree(prog);
  for (int v = 0; v < static_cast<int>(prog.instances.size()); ++v)
    if (tree.parent_edge[v] == -2) {
      sum.ok = false;
      sum.issues.push_back({PrecheckFailure::kDisconnected,
                            prog.file + ": part '" + prog.instances[v].name + "' is not connected to the environment"});
    }
  for (int e = 0; e < static_cast<int>(prog.connections.size()); ++e) {
    if (tree.tree_edge[e]) continue;
    const auto& c = prog.connections[e];
    if (tree.parent_edge[c.part_a] == -2 || tree.parent_edge[c.part_b] == -2) continue;
    std::vector<CycleLink> links = CycleLinks(prog, tree, e, opt);
    sum.cycles.push_back(links);
    if (!PolygonInequalityFeasible(links, opt.cycle_slack_mm)) {
      std::string detail;
      for (const auto& l : links)
        detail += " " + l.part + "[" + std::to_string(static_cast<int>(l.min_span_mm)) + "," +
                  std::to_string(static_cast<int>(l.max_span_mm)) + "]";
      AddIssue(prog, PrecheckFailure::kCycleCannotClose, c,
               "cycle cannot close: polygon inequality violated, link spans (mm):" + detail, &sum);
    }
  }
  return sum;
}

}  // namespace fabatlas::assembly
