// The geometry cache plan task (see cache_plan.h).
#include "fabatlas/protocol/cache_plan.h"

#include <algorithm>
#include <limits>
#include <map>

#include "fabatlas/cache/cost_model.h"
#include "fabatlas/cache/dependency_graph.h"
#include "fabatlas/cache/exact_cache.h"
#include "fabatlas/error.h"

namespace fabatlas::protocol {

namespace {

constexpr std::uint64_t kNoBudget = std::numeric_limits<std::uint64_t>::max();

const char* ScoreName(cache::Score score) {
  switch (score) {
    case cache::Score::kTimesCount:
      return "times_count";
    case cache::Score::kPerByte:
      return "per_byte";
    case cache::Score::kSavedPerByte:
      return "saved_per_byte";
  }
  return "?";
}

void Fill(const cache::CacheCost& from, v1::CachePlanCost* to) {
  to->set_mean_seconds(from.mean_seconds);
  to->set_worst_seconds(from.worst_seconds);
  to->set_bytes(from.bytes);
  to->set_entries(from.entries);
}

}  // namespace

v1::CachePlanOptions CachePlanOptionsOf(const cache::CacheOptions& o) {
  v1::CachePlanOptions m;
  m.set_strategy(cache::StrategyName(o.strategy));
  m.set_score(ScoreName(o.score));
  m.set_budget_bytes(o.budget_bytes == kNoBudget ? 0 : o.budget_bytes);
  m.set_min_seconds(o.min_seconds);
  m.set_average_share(o.average_share);
  return m;
}

cache::CacheOptions CacheOptionsOf(const v1::CachePlanOptions& m) {
  cache::CacheOptions o;
  if (m.strategy() == "naive")
    o.strategy = cache::Strategy::kNaive;
  else if (m.strategy() == "opt_ave")
    o.strategy = cache::Strategy::kOptAve;
  else if (m.strategy() == "opt_max")
    o.strategy = cache::Strategy::kOptMax;
  else
    throw InputError("cache plan: strategy '" + m.strategy() + "' is not naive, opt_ave or opt_max");
  if (m.score() == "times_count")
    o.score = cache::Score::kTimesCount;
  else if (m.score() == "per_byte")
    o.score = cache::Score::kPerByte;
  else if (m.score() == "saved_per_byte")
    o.score = cache::Score::kSavedPerByte;
  else
    throw InputError("cache plan: score '" + m.score() + "' is not times_count, per_byte or saved_per_byte");
  o.budget_bytes = m.budget_bytes() == 0 ? kNoBudget : m.budget_bytes();
  o.min_seconds = m.min_seconds();
  o.average_share = m.average_share();
  o.record_curve = true;
  return o;
}

namespace {

// The input's dependency graph, one node per key, costed once (docs/cache.md
// "Determinism"): a key's records all carry the same op and children, so
// its model cost is a function of the key, and how many records a path
// reports (one per sample in process, one per key from the cluster's store,
// more after retries) must not change a bit of it. Merging k equal costs as
// a mean would: (t + t + t) / 3 is not always t. *op_of: each key's op.
cache::DependencyGraph GraphOf(const v1::CachePlanInput& input, std::map<std::string, std::string>* op_of) {
  struct Merged {
    const v1::CachePlanSubtree* first = nullptr;
    std::int64_t bytes = 0;
    bool stored = false;
  };
  std::map<std::string, Merged> by_key;
  for (const auto& s : input.subtrees()) {
    Merged& m = by_key[s.key()];
    if (m.first == nullptr)
      m.first = &s;
    else if (!std::equal(s.children().begin(), s.children().end(), m.first->children().begin(),
                         m.first->children().end()))
      throw InputError("cache graph: subtree " + s.key() + " is recorded with different children");
    m.bytes = std::max(m.bytes, s.bytes());
    m.stored = m.stored || s.stored();
  }
  std::vector<cache::SubtreeNode> nodes;
  nodes.reserve(by_key.size());
  for (const auto& [key, m] : by_key) {
    std::uint64_t in = 0;
    for (const auto& c : m.first->children())
      if (auto it = by_key.find(c); it != by_key.end()) in += static_cast<std::uint64_t>(it->second.bytes);
    const auto out = static_cast<std::uint64_t>(m.bytes);
    nodes.push_back({key,
                     {m.first->children().begin(), m.first->children().end()},
                     cache::ModelSubtreeSeconds(m.first->op(), out, in),
                     out,
                     m.stored});
    op_of->emplace(key, m.first->op());
  }
  std::vector<cache::SampleTree> samples;
  samples.reserve(static_cast<std::size_t>(input.sample_roots_size()));
  for (const auto& r : input.sample_roots()) samples.push_back({r});
  return cache::BuildDependencyGraph(nodes, samples);
}

// An entry per node in the chosen plan or the budget-free OPT-MAX plan.
void AddEntries(const cache::DependencyGraph& graph, const cache::CacheSet& opt, const cache::CacheSet& rfree,
                std::map<std::string, std::string>& op_of, v1::CachePlanReport* report) {
  for (std::int32_t id = 0; id < static_cast<std::int32_t>(graph.node_count()); ++id) {
    const bool in_opt = opt[id] != 0, in_rfree = rfree[id] != 0;
    if (!in_opt && !in_rfree) continue;
    v1::CachePlanEntry* e = report->add_entries();
    e->set_key(graph.keys[id]);
    e->set_op(op_of[graph.keys[id]]);
    for (std::int64_t c = graph.child_begin[id]; c < graph.child_begin[id + 1]; ++c)
      e->add_children(graph.keys[graph.child_ids[c]]);
    e->set_bytes(static_cast<std::int64_t>(graph.bytes[id]));
    e->set_cost_seconds(graph.seconds[id]);
    e->set_in_opt(in_opt);
    e->set_in_rfree(in_rfree);
  }
}

// Each strategy's cost curve under `options` (its own strategy replaced).
void AddCurves(const cache::DependencyGraph& graph, const cache::CacheOptions& options, v1::CachePlanReport* report) {
  for (auto strategy : {cache::Strategy::kNaive, cache::Strategy::kOptAve, cache::Strategy::kOptMax}) {
    cache::CacheOptions o = options;
    o.strategy = strategy;
    const cache::CachePlan p = cache::OptimizeCache(graph, o);
    v1::CachePlanCurve* curve = report->add_curves();
    curve->set_strategy(cache::StrategyName(strategy));
    for (const auto& point : p.curve) {
      v1::CachePlanCost* c = curve->add_points();
      c->set_mean_seconds(point.mean_seconds);
      c->set_worst_seconds(point.worst_seconds);
      c->set_bytes(point.bytes);
      c->set_entries(point.entries);
    }
  }
}

// The exact worst-case program (SolveExactCache) started from the chosen
// plan, within the input's variable and time limits, into *exact.
void SolveExact(const v1::CachePlanInput& input, const cache::DependencyGraph& graph,
                const cache::CacheOptions& options, const cache::CacheReport& plan, v1::CachePlanExact* exact) {
  if (input.options().exact_max_variables() <= 0) {
    exact->set_message("not attempted (exact_max_variables = 0)");
    return;
  }
  cache::ExactCacheOptions eo;
  eo.objective = cache::ExactObjective::kWorst;
  eo.budget_bytes = options.budget_bytes;
  eo.min_seconds = options.min_seconds;
  eo.time_limit_seconds =
      input.options().exact_time_limit_seconds() > 0 ? input.options().exact_time_limit_seconds() : 10.0;
  eo.max_variables = input.options().exact_max_variables();
  eo.start = plan.chosen.cache;
  const cache::ExactCacheSummary ex = cache::SolveExactCache(graph, eo);
  exact->set_solved(ex.solved);
  exact->set_optimal(ex.optimal);
  exact->set_variables(ex.variables);
  exact->set_message(ex.message);
  if (ex.solved) {
    exact->set_worst_seconds(ex.cost.worst_seconds);
    exact->set_bound_seconds(ex.bound);
    const double worst = plan.chosen.cost.worst_seconds;
    exact->set_gap(ex.cost.worst_seconds > 0 ? (worst - ex.cost.worst_seconds) / ex.cost.worst_seconds : 0.0);
  }
}

}  // namespace

v1::CachePlanReport RunCachePlan(const v1::CachePlanInput& input) {
  std::map<std::string, std::string> op_of;
  const cache::DependencyGraph graph = GraphOf(input, &op_of);

  const cache::CacheOptions options = CacheOptionsOf(input.options());
  const cache::CacheReport plan = cache::PlanCache(graph, options);
  cache::CacheOptions rfree_options = options;
  rfree_options.strategy = cache::Strategy::kOptMax;
  rfree_options.budget_bytes = kNoBudget;
  const cache::CachePlan rfree = cache::OptimizeCache(graph, rfree_options);

  v1::CachePlanReport report;
  report.set_nodes(graph.node_count());
  report.set_samples(graph.sample_count());
  Fill(plan.none, report.mutable_none());
  Fill(plan.top, report.mutable_top());
  Fill(plan.chosen.cost, report.mutable_opt());
  Fill(rfree.cost, report.mutable_rfree());
  AddEntries(graph, plan.chosen.cache, rfree.cache, op_of, &report);
  AddCurves(graph, options, &report);
  SolveExact(input, graph, options, plan, report.mutable_exact());
  return report;
}

}  // namespace fabatlas::protocol
