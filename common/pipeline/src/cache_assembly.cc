// The geometry cache of an artifact (see cache_assembly.h).
#include "fabatlas/pipeline/cache_assembly.h"

#include <cstdio>
#include <limits>

#include "fabatlas/geometry/solid.h"
#include "fabatlas/protocol/cache_plan.h"
#include "fabatlas/artifact/glb.h"

namespace fabatlas::pipeline {

v1::CachePlanInput CachePlanInputOf(const CacheAssembly& a) {
  v1::CachePlanInput input;
  for (const auto& s : a.subtrees) {
    v1::CachePlanSubtree* out = input.add_subtrees();
    out->set_key(s.key);
    out->set_op(s.op);
    for (const auto& c : s.children) out->add_children(c);
    out->set_bytes(s.bytes);
    out->set_stored(s.stored);
  }
  for (const auto& r : a.sample_roots) input.add_sample_roots(r);
  *input.mutable_options() = protocol::CachePlanOptionsOf(a.options);
  input.mutable_options()->set_exact_max_variables(a.exact_max_variables);
  input.mutable_options()->set_exact_time_limit_seconds(a.exact_time_limit_seconds);
  return input;
}

CacheAssemblySummary AddCache(artifact::Artifact& artifact, const CacheAssembly& a, const v1::CachePlanReport& report) {
  CacheAssemblySummary summary;
  summary.exact = report.exact();
  const cache::CacheOptions& options = a.options;
  artifact::CacheSummary& m = artifact.manifest.cache;
  m.strategy = cache::StrategyName(options.strategy);
  m.budget_bytes = options.budget_bytes == std::numeric_limits<std::uint64_t>::max()
                       ? 0
                       : static_cast<std::int64_t>(options.budget_bytes);
  m.threshold_seconds = options.min_seconds;
  m.cost_model = "cache::ModelSubtreeSeconds (docs/cache.md)";
  m.top_entries = report.top().entries();
  m.top_bytes = static_cast<std::int64_t>(report.top().bytes());
  m.opt_entries = report.opt().entries();
  m.opt_bytes = static_cast<std::int64_t>(report.opt().bytes());
  m.rfree_entries = report.rfree().entries();
  m.rfree_bytes = static_cast<std::int64_t>(report.rfree().bytes());

  artifact.cache_curves.clear();
  for (const auto& curve : report.curves())
    for (int step = 0; step < curve.points_size(); ++step) {
      const auto& p = curve.points(step);
      artifact.cache_curves.push_back({curve.strategy(), static_cast<std::int64_t>(step), p.entries(),
                                       static_cast<std::int64_t>(p.bytes()), p.mean_seconds(), p.worst_seconds()});
    }

  artifact.cache.clear();
  artifact.cache_geometry = nullptr;
  // The geometry of an entry: the subtree's grid and its zero iso-surface.
  auto fill = [grid_of = a.grid_of](artifact::CacheEntry& e) {
    try {
      e.grid = grid_of ? grid_of(e.key) : std::string();
    } catch (const std::exception&) {
      e.grid.clear();
    }
    if (e.grid.empty()) return false;
    {
      const geometry::Solid solid = geometry::Solid::Deserialize(e.grid);
      e.glb = artifact::SolidPreviewGlb(solid.ToMesh(), solid.boundary() != nullptr);
    }
    return true;
  };
  if (a.stream_geometry) artifact.cache_geometry = fill;
  for (const auto& r : report.entries()) {
    if (!r.in_opt() && !a.store_rfree) continue;  // H_rfree beyond H_opt: sizes in the manifest only
    artifact::CacheEntry e;
    e.key = r.key();
    e.op = r.op();
    e.children.assign(r.children().begin(), r.children().end());
    e.bytes = r.bytes();
    e.cost_seconds = r.cost_seconds();
    e.in_opt = r.in_opt();
    e.in_rfree = r.in_rfree();
    if (!a.stream_geometry && !fill(e)) {
      ++summary.missing;
      continue;
    }
    artifact.cache.push_back(std::move(e));
    ++summary.entries;
  }
  return summary;
}

CacheAssemblySummary AddCache(artifact::Artifact& artifact, const CacheAssembly& assembly) {
  return AddCache(artifact, assembly, protocol::RunCachePlan(CachePlanInputOf(assembly)));
}

std::string ExactText(const v1::CachePlanExact& exact) {
  if (!exact.solved()) return "exact optimum: " + exact.message();
  char text[160];
  std::snprintf(text, sizeof text, "exact worst case %.6g s (%s, %lld variables), H_opt gap %.2f %%",
                exact.worst_seconds(), exact.optimal() ? "optimal" : "time limit",
                static_cast<long long>(exact.variables()), 100.0 * exact.gap());
  return text;
}

}  // namespace fabatlas::pipeline
