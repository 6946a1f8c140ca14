// The cache optimisation of Fab Forms Sec. 6.2 as an integer program ("can be
// formulated as an integer linear program"), solved with GLPK's branch and
// cut. Formulation in exact_cache.h.
#include "fabatlas/cache/exact_cache.h"

#include <glpk.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>

#include "fabatlas/error.h"

namespace fabatlas::cache {

namespace {
using Id = std::int32_t;

struct Problem {
  glp_prob* lp = glp_create_prob();
  ~Problem() { glp_delete_prob(lp); }
};

// Rows are added one at a time with their coefficients (1-based for GLPK).
struct Row {
  std::vector<int> cols{0};
  std::vector<double> vals{0.0};
  void Add(int col, double v) {
    cols.push_back(col);
    vals.push_back(v);
  }
};

int AddRow(glp_prob* lp, Row& row, int type, double lo, double hi) {
  int r = glp_add_rows(lp, 1);
  glp_set_row_bnds(lp, r, type, lo, hi);
  glp_set_mat_row(lp, r, static_cast<int>(row.cols.size()) - 1, row.cols.data(), row.vals.data());
  return r;
}

// A sample root's sub-DAG, parents before children, with the GLPK column of
// each node's evaluation count k.
struct SampleDag {
  Id root;
  int weight;
  std::vector<Id> nodes;     // topological
  std::map<Id, int> column;  // node -> k column
};

// Each distinct root's sub-DAG (roots: root -> multiplicity), its nodes in
// topological order (columns not yet set).
std::vector<SampleDag> SampleDags(const DependencyGraph& g, const std::map<Id, int>& roots) {
  const std::size_t n = g.keys.size();
  std::vector<Id> topo_pos(n);
  for (std::size_t i = 0; i < n; ++i) topo_pos[static_cast<std::size_t>(g.topological_order[i])] = static_cast<Id>(i);
  std::vector<SampleDag> dags;
  std::vector<char> seen(n, 0);
  for (auto [r, w] : roots) {
    SampleDag d{r, w, {}, {}};
    std::vector<Id> stack{r};
    seen[static_cast<std::size_t>(r)] = 1;
    while (!stack.empty()) {
      Id v = stack.back();
      stack.pop_back();
      d.nodes.push_back(v);
      for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e) {
        Id c = g.child_ids[static_cast<std::size_t>(e)];
        if (!seen[static_cast<std::size_t>(c)]) {
          seen[static_cast<std::size_t>(c)] = 1;
          stack.push_back(c);
        }
      }
    }
    for (Id v : d.nodes) seen[static_cast<std::size_t>(v)] = 0;
    std::sort(d.nodes.begin(), d.nodes.end(), [&](Id a, Id b) {
      return topo_pos[static_cast<std::size_t>(a)] < topo_pos[static_cast<std::size_t>(b)];
    });
    dags.push_back(std::move(d));
  }
  return dags;
}

// Adds to lp a binary column h for each choosable node (stored, and taking
// more than o.min_seconds) below some root; returns node -> h column.
std::map<Id, int> AddCacheColumns(glp_prob* lp, const DependencyGraph& g, const ExactCacheOptions& o,
                                  const std::vector<SampleDag>& dags) {
  auto choosable = [&](Id x) {
    auto i = static_cast<std::size_t>(x);
    return g.stored[i] && g.seconds[i] > 0 && g.seconds[i] >= o.min_seconds;
  };
  std::map<Id, int> h_col;
  for (const SampleDag& d : dags)
    for (Id v : d.nodes)
      if (choosable(v) && !h_col.count(v)) h_col[v] = 0;
  for (auto& [v, col] : h_col) {
    col = glp_add_cols(lp, 1);
    glp_set_col_kind(lp, col, GLP_BV);
  }
  return h_col;
}

// Adds dag d's k columns (set in d.column) and rows to lp: each node's
// evaluations cover its parents' uses unless it is cached (h), and with the
// kWorst objective z >= T(root).
void AddSampleRows(glp_prob* lp, const DependencyGraph& g, const ExactCacheOptions& o, const std::map<Id, int>& h_col,
                   int z_col, double samples, SampleDag& d) {
  // Path counts from the root: the most evaluations X can need.
  std::map<Id, double> paths;
  paths[d.root] = 1;
  for (Id v : d.nodes) {
    int col = glp_add_cols(lp, 1);
    glp_set_col_bnds(lp, col, GLP_LO, 0.0, 0.0);
    d.column[v] = col;
    if (o.objective == ExactObjective::kMean)
      glp_set_obj_coef(lp, col, g.seconds[static_cast<std::size_t>(v)] * d.weight / samples);
    for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e)
      paths[g.child_ids[static_cast<std::size_t>(e)]] += paths[v];
  }
  // Parents' use of each node, with multiplicity.
  std::map<Id, std::map<Id, int>> uses;  // child -> parent -> count
  for (Id v : d.nodes)
    for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e)
      ++uses[g.child_ids[static_cast<std::size_t>(e)]][v];
  for (Id v : d.nodes) {
    Row row;
    row.Add(d.column[v], 1.0);
    auto h = h_col.find(v);
    if (h != h_col.end()) row.Add(h->second, v == d.root ? 1.0 : paths[v]);
    if (v == d.root) {
      AddRow(lp, row, GLP_LO, 1.0, 0.0);  // k_root + h_root >= 1
      continue;
    }
    for (auto [parent, count] : uses[v]) row.Add(d.column[parent], -static_cast<double>(count));
    AddRow(lp, row, GLP_LO, 0.0, 0.0);
  }
  if (o.objective == ExactObjective::kWorst) {
    Row row;
    row.Add(z_col, 1.0);
    for (Id v : d.nodes)
      if (g.seconds[static_cast<std::size_t>(v)] != 0) row.Add(d.column[v], -g.seconds[static_cast<std::size_t>(v)]);
    AddRow(lp, row, GLP_LO, 0.0, 0.0);  // z >= T(r)
  }
}

// The starting solution o.start as a full column vector of lp (1-based): h
// from the start set, k the exact evaluation counts given it, z the largest
// T; empty when o.start is not given or exceeds the byte budget.
std::vector<double> StartingColumns(glp_prob* lp, const DependencyGraph& g, const ExactCacheOptions& o,
                                    const std::map<Id, int>& h_col, const std::vector<SampleDag>& dags, int z_col) {
  std::vector<double> start;
  if (o.start.size() != g.keys.size()) return start;
  const int cols = glp_get_num_cols(lp);
  start.assign(static_cast<std::size_t>(cols) + 1, 0.0);
  std::uint64_t bytes = 0;
  for (auto [v, col] : h_col)
    if (o.start[static_cast<std::size_t>(v)]) {
      start[static_cast<std::size_t>(col)] = 1;
      bytes += g.bytes[static_cast<std::size_t>(v)];
    }
  double z = 0;
  for (const SampleDag& d : dags) {
    std::map<Id, double> q;
    q[d.root] = 1;
    double t = 0;
    for (Id v : d.nodes) {
      bool cached = h_col.count(v) && o.start[static_cast<std::size_t>(v)];
      double k = cached ? 0.0 : q[v];
      start[static_cast<std::size_t>(d.column.at(v))] = k;
      t += g.seconds[static_cast<std::size_t>(v)] * k;
      for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e)
        q[g.child_ids[static_cast<std::size_t>(e)]] += k;
    }
    z = std::max(z, t);
  }
  if (z_col) start[static_cast<std::size_t>(z_col)] = z;
  if (bytes > o.budget_bytes) start.clear();  // not feasible: no start
  return start;
}

// GLPK's branch and cut on lp (GMI and MIR cuts, o.time_limit_seconds),
// offered `start` (when not empty) at its first heuristic call; returns
// glp_intopt's code.
int BranchAndCut(glp_prob* lp, const ExactCacheOptions& o, std::vector<double>& start) {
  struct Callback {
    std::vector<double>* start;
    bool given = false;
  } callback{&start};
  glp_iocp iocp;
  glp_init_iocp(&iocp);
  if (!start.empty()) {
    iocp.cb_info = &callback;
    iocp.cb_func = [](glp_tree* tree, void* info) {
      auto* c = static_cast<Callback*>(info);
      if (glp_ios_reason(tree) == GLP_IHEUR && !c->given) {
        c->given = true;
        glp_ios_heur_sol(tree, c->start->data());
      }
    };
  }
  iocp.msg_lev = GLP_MSG_OFF;
  iocp.tm_lim = static_cast<int>(std::min(o.time_limit_seconds * 1000.0, 2.0e9));
  iocp.gmi_cuts = GLP_ON;
  iocp.mir_cuts = GLP_ON;
  return glp_intopt(lp, &iocp);
}

// Drops from *cache the chosen nodes no sample reaches any more (they cost
// bytes, save nothing).
void DropUnreached(const DependencyGraph& g, CacheSet* cache) {
  const std::size_t n = g.keys.size();
  std::vector<double> q(n, 0.0);
  for (Id r : g.sample_roots) q[static_cast<std::size_t>(r)] += 1;
  for (Id v : g.topological_order) {
    if ((*cache)[static_cast<std::size_t>(v)] || q[static_cast<std::size_t>(v)] == 0) continue;
    for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e)
      q[static_cast<std::size_t>(g.child_ids[static_cast<std::size_t>(e)])] += q[static_cast<std::size_t>(v)];
  }
  for (std::size_t i = 0; i < n; ++i)
    if ((*cache)[i] && q[i] == 0) (*cache)[i] = 0;
}
}  // namespace

ExactCacheSummary SolveExactCache(const DependencyGraph& g, const ExactCacheOptions& o) {
  ExactCacheSummary out;
  const std::size_t n = g.keys.size();
  out.cache.assign(n, 0);
  // Distinct sample roots with their multiplicity.
  std::map<Id, int> roots;
  for (Id r : g.sample_roots) ++roots[r];
  if (roots.empty()) {
    out.solved = out.optimal = true;
    out.cost = EvaluateCache(g, out.cache);
    return out;
  }
  // Each root's sub-DAG, parents before children.
  std::vector<SampleDag> dags = SampleDags(g, roots);
  std::int64_t k_columns = 0;
  for (const SampleDag& d : dags) k_columns += static_cast<std::int64_t>(d.nodes.size());
  out.variables = k_columns;
  if (k_columns > o.max_variables) {
    out.message = "program too large: " + std::to_string(k_columns) + " evaluation variables > max_variables " +
                  std::to_string(o.max_variables);
    return out;
  }

  glp_term_out(GLP_OFF);
  Problem p;
  glp_prob* lp = p.lp;
  glp_set_obj_dir(lp, GLP_MIN);
  const std::map<Id, int> h_col = AddCacheColumns(lp, g, o, dags);
  int z_col = 0;
  if (o.objective == ExactObjective::kWorst) {
    z_col = glp_add_cols(lp, 1);
    glp_set_col_bnds(lp, z_col, GLP_LO, 0.0, 0.0);
    glp_set_obj_coef(lp, z_col, 1.0);
  }
  const double samples = static_cast<double>(g.sample_roots.size());
  for (SampleDag& d : dags) AddSampleRows(lp, g, o, h_col, z_col, samples, d);
  if (o.budget_bytes != std::numeric_limits<std::uint64_t>::max() && !h_col.empty()) {
    Row row;
    // In MiB, so the budget row is on the scale of the others.
    const double mib = 1.0 / 1048576.0;
    for (auto [v, col] : h_col) row.Add(col, static_cast<double>(g.bytes[static_cast<std::size_t>(v)]) * mib);
    AddRow(lp, row, GLP_UP, 0.0, static_cast<double>(o.budget_bytes) * mib);
  }

  glp_scale_prob(lp, GLP_SF_AUTO);
  glp_smcp smcp;
  glp_init_smcp(&smcp);
  smcp.msg_lev = GLP_MSG_OFF;
  if (glp_simplex(lp, &smcp) != 0 || glp_get_status(lp) != GLP_OPT) {
    out.message = "LP relaxation not solved";
    return out;
  }
  const double lp_bound = glp_get_obj_val(lp);
  std::vector<double> start = StartingColumns(lp, g, o, h_col, dags, z_col);
  int rc = BranchAndCut(lp, o, start);
  int status = glp_mip_status(lp);
  if (status != GLP_OPT && status != GLP_FEAS) {
    out.message = rc == GLP_ETMLIM ? "time limit before any integer solution" : "no integer solution";
    out.bound = lp_bound;
    return out;
  }
  out.solved = true;
  out.optimal = status == GLP_OPT;
  out.objective = glp_mip_obj_val(lp);
  out.bound = out.optimal ? out.objective : lp_bound;
  if (!out.optimal) out.message = "time limit: best solution found, not proven optimal";
  for (auto [v, col] : h_col)
    if (glp_mip_col_val(lp, col) > 0.5) out.cache[static_cast<std::size_t>(v)] = 1;
  DropUnreached(g, &out.cache);
  out.cost = EvaluateCache(g, out.cache);
  return out;
}

}  // namespace fabatlas::cache
