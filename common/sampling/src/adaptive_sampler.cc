// Adaptive sampling, Fab Forms Sec. 5.2 (see adaptive_sampler.h for the rounds).
#include "fabatlas/sampling/adaptive_sampler.h"

#include <algorithm>
#include <functional>
#include <set>

#include "fabatlas/error.h"
#include "fabatlas/stopwatch.h"

namespace fabatlas::sampling {

namespace {

using Edge = std::pair<std::int64_t, std::int64_t>;

struct SplitCandidate {
  size_t frontier_index = 0;
  int dimension = -1;
  double max_dg = 0.0;
  std::vector<double> score;  // s(u_d) of the chosen direction, descending
};

class Sampler {
 public:
  Sampler(const DesignSpace& space, SampleEvaluator& evaluator, Executor& executor, const SamplingOptions& options)
      : space_(space), evaluator_(evaluator), executor_(executor), options_(options), n_(space.dimension_count()) {
    form_.dimensions = space.dimensions();
    form_.subdivisions = space.subdivisions();
  }

  SamplingSummary Run() {
    const Stopwatch wall_time;
    std::vector<LeafRef> frontier = Bootstrap();
    bool budget_exhausted = false;
    while (!frontier.empty()) {
      ComputeGeometryChanges(frontier);
      frontier = Refine(frontier, &budget_exhausted);
    }
    stats_.wall_seconds = wall_time.Seconds();
    stats_.sampling_logic_seconds = stats_.wall_seconds - executor_seconds_;
    FinishStatistics();
    return SamplingSummary{std::move(form_), std::move(stats_)};
  }

 private:
  PointKey Corner(const FormNode& node, size_t c) const {
    PointKey key(n_);
    for (int d = 0; d < n_; ++d) key[d] = (c >> d) & 1 ? node.hi[d] : node.lo[d];
    return key;
  }

  // Fab Forms Sec. 5: uniform bootstrap grid, one k-d tree per cell.
  std::vector<LeafRef> Bootstrap() {
    std::vector<int> cell(n_, 0);
    std::vector<PointKey> keys;
    std::vector<LeafRef> frontier;
    while (true) {
      FormTree tree;
      tree.cell = cell;
      FormNode root;
      root.lo.resize(n_);
      root.hi.resize(n_);
      for (int d = 0; d < n_; ++d) {
        root.lo[d] = space_.grid_key(d, cell[d]);
        root.hi[d] = space_.grid_key(d, cell[d] + 1);
      }
      for (size_t c = 0; c < (size_t{1} << n_); ++c) keys.push_back(Corner(root, c));
      tree.nodes.push_back(std::move(root));
      frontier.push_back({static_cast<int>(form_.trees.size()), 0});
      form_.trees.push_back(std::move(tree));
      int d = n_ - 1;  // last dimension fastest
      while (d >= 0 && ++cell[d] == space_.cell_count(d)) cell[d--] = 0;
      if (d < 0) break;
    }
    EvaluateSamples(std::move(keys));
    return frontier;
  }

  // Evaluates every key not yet sampled, as one batch; ids in key order.
  void EvaluateSamples(std::vector<PointKey> keys) {
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    std::vector<SampleTask> tasks;
    for (auto& k : keys)
      if (!form_.sample_ids.count(k)) tasks.push_back({SamplePoint{k, space_.point(k)}});
    if (tasks.empty()) return;
    std::vector<TaskTiming> timings;
    const Stopwatch executor_time;
    std::vector<SampleOutcome> outcomes = executor_.RunSampleTasks(tasks, evaluator_, &timings);
    executor_seconds_ += executor_time.Seconds();
    if (outcomes.size() != tasks.size()) throw std::runtime_error("executor returned a wrong number of sample results");
    for (size_t i = 0; i < tasks.size(); ++i) {
      const auto id = static_cast<std::int64_t>(form_.samples.size());
      form_.sample_ids.emplace(tasks[i].point.key, id);
      stats_.evaluator_cpu_seconds += outcomes[i].cpu_seconds;
      if (i < timings.size()) stats_.evaluator_wall_seconds += timings[i].wall_seconds;
      form_.samples.push_back(
          FormSample{std::move(tasks[i].point.key), std::move(tasks[i].point.u), std::move(outcomes[i])});
    }
  }

  // ΔG on every edge of every frontier leaf (Fab Forms Eq. 2 and conventions).
  void ComputeGeometryChanges(const std::vector<LeafRef>& frontier) {
    std::set<Edge> needed;
    for (const LeafRef& ref : frontier) {
      const auto ids = CornerSampleIds(form_, form_.trees[ref.tree].nodes[ref.node]);
      for (int d = 0; d < n_; ++d)
        for (size_t c = 0; c < ids.size(); ++c) {
          if ((c >> d) & 1) continue;
          Edge e{std::min(ids[c], ids[c | (size_t{1} << d)]), std::max(ids[c], ids[c | (size_t{1} << d)])};
          if (form_.geometry_changes.count(e)) continue;
          const bool va = form_.samples[e.first].outcome.valid;
          const bool vb = form_.samples[e.second].outcome.valid;
          if (!va && !vb)
            form_.geometry_changes[e] = 0.0;
          else if (va != vb)
            form_.geometry_changes[e] = 1.0;
          else
            needed.insert(e);
        }
    }
    if (needed.empty()) return;
    std::vector<GeometryChangeTask> tasks;
    tasks.reserve(needed.size());
    for (const Edge& e : needed) {
      const FormSample& a = form_.samples[e.first];
      const FormSample& b = form_.samples[e.second];
      tasks.push_back({e.first, e.second, SamplePoint{a.key, a.u}, SamplePoint{b.key, b.u}});
    }
    std::vector<TaskTiming> timings;
    const Stopwatch executor_time;
    auto results = executor_.RunGeometryChangeTasks(tasks, evaluator_, &timings);
    executor_seconds_ += executor_time.Seconds();
    if (results.size() != tasks.size()) throw std::runtime_error("executor returned a wrong number of ΔG results");
    for (size_t i = 0; i < tasks.size(); ++i) {
      const double dg = std::clamp(results[i].geometry_change, 0.0, 1.0);
      form_.geometry_changes[{tasks[i].sample_a, tasks[i].sample_b}] = dg;
      stats_.evaluator_cpu_seconds += results[i].cpu_seconds;
      if (i < timings.size()) stats_.evaluator_wall_seconds += timings[i].wall_seconds;
      ++stats_.geometry_change_calls;
    }
  }

  // Split decisions for one frontier (all leaves at one depth); returns the
  // next frontier (the children, in tree order).
  std::vector<LeafRef> Refine(const std::vector<LeafRef>& frontier, bool* budget_exhausted) {
    std::vector<SplitCandidate> candidates;
    for (size_t f = 0; f < frontier.size(); ++f) {
      FormNode& node = form_.trees[frontier[f].tree].nodes[frontier[f].node];
      const auto ids = CornerSampleIds(form_, node);
      // s(u_d): ΔG of the 2^(n-1) edges along d, sorted descending.
      std::vector<std::vector<double>> s(n_);
      double max_dg = 0.0;
      for (int d = 0; d < n_; ++d) {
        for (size_t c = 0; c < ids.size(); ++c) {
          if ((c >> d) & 1) continue;
          const std::int64_t a = ids[c], b = ids[c | (size_t{1} << d)];
          const double dg = form_.geometry_changes.at({std::min(a, b), std::max(a, b)});
          s[d].push_back(dg);
          max_dg = std::max(max_dg, dg);
        }
        std::sort(s[d].begin(), s[d].end(), std::greater<double>());
      }
      if (max_dg < options_.dg_threshold) {
        node.stop = LeafStop::kThreshold;
        continue;
      }
      if (node.depth >= options_.max_depth) {
        node.stop = LeafStop::kMaxDepth;
        continue;
      }
      std::vector<int> order(n_);
      for (int d = 0; d < n_; ++d) order[d] = d;
      std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return s[a] > s[b]; });
      int chosen = -1;
      for (int d : order) {
        if (s[d][0] < options_.dg_threshold) break;  // nothing left worth splitting
        if (space_.can_split(d, node.lo[d], node.hi[d])) {
          chosen = d;
          break;
        }
      }
      if (chosen < 0) {
        node.stop = LeafStop::kUnsplittable;
        continue;
      }
      if (*budget_exhausted) {
        node.stop = LeafStop::kBudget;
        continue;
      }
      candidates.push_back({f, chosen, max_dg, s[chosen]});
    }

    // Budget: highest score first, the first split that does not fit ends refinement.
    std::vector<size_t> by_score(candidates.size());
    for (size_t i = 0; i < by_score.size(); ++i) by_score[i] = i;
    std::stable_sort(by_score.begin(), by_score.end(), [&](size_t a, size_t b) {
      if (candidates[a].max_dg != candidates[b].max_dg) return candidates[a].max_dg > candidates[b].max_dg;
      return candidates[a].score > candidates[b].score;
    });
    std::set<PointKey> pending;
    std::vector<bool> accepted(candidates.size(), false);
    for (size_t i : by_score) {
      const SplitCandidate& cand = candidates[i];
      FormNode& node = form_.trees[frontier[cand.frontier_index].tree].nodes[frontier[cand.frontier_index].node];
      if (*budget_exhausted) {
        node.stop = LeafStop::kBudget;
        continue;
      }
      const std::int64_t mid = space_.split_key(cand.dimension, node.lo[cand.dimension], node.hi[cand.dimension]);
      std::vector<PointKey> fresh;
      for (size_t c = 0; c < (size_t{1} << n_); ++c) {
        if ((c >> cand.dimension) & 1) continue;
        PointKey k = Corner(node, c);
        k[cand.dimension] = mid;
        if (!form_.sample_ids.count(k) && !pending.count(k)) fresh.push_back(std::move(k));
      }
      const auto total = static_cast<std::int64_t>(form_.samples.size() + pending.size() + fresh.size());
      if (total > options_.max_samples) {
        *budget_exhausted = true;
        node.stop = LeafStop::kBudget;
        continue;
      }
      for (auto& k : fresh) pending.insert(std::move(k));
      accepted[i] = true;
    }

    // Apply the accepted splits in tree order (node indices deterministic).
    std::vector<LeafRef> next;
    for (size_t i = 0; i < candidates.size(); ++i) {
      if (!accepted[i]) continue;
      const SplitCandidate& cand = candidates[i];
      const LeafRef ref = frontier[cand.frontier_index];
      FormTree& tree = form_.trees[ref.tree];
      const int d = cand.dimension;
      FormNode lo_child = tree.nodes[ref.node], hi_child = tree.nodes[ref.node];
      const std::int64_t mid = space_.split_key(d, lo_child.lo[d], lo_child.hi[d]);
      lo_child.hi[d] = mid;
      hi_child.lo[d] = mid;
      lo_child.depth = hi_child.depth = tree.nodes[ref.node].depth + 1;
      const int lo_index = static_cast<int>(tree.nodes.size());
      tree.nodes.push_back(std::move(lo_child));
      tree.nodes.push_back(std::move(hi_child));
      FormNode& parent = tree.nodes[ref.node];
      parent.split_dimension = d;
      parent.split_key = mid;
      parent.children[0] = lo_index;
      parent.children[1] = lo_index + 1;
      next.push_back({ref.tree, lo_index});
      next.push_back({ref.tree, lo_index + 1});
    }
    EvaluateSamples(std::vector<PointKey>(pending.begin(), pending.end()));
    return next;
  }

  void FinishStatistics() {
    stats_.samples = static_cast<std::int64_t>(form_.samples.size());
    stats_.geometry_changes = static_cast<std::int64_t>(form_.geometry_changes.size());
    std::int64_t invalid = 0;
    for (const FormSample& s : form_.samples) {
      if (s.outcome.valid) {
        ++stats_.valid_samples;
        continue;
      }
      ++invalid;
      stats_.failure_shares[s.outcome.failure_type] += 1.0;
    }
    for (auto& [type, share] : stats_.failure_shares) share /= static_cast<double>(invalid);
    for (const FormTree& t : form_.trees)
      for (const FormNode& node : t.nodes)
        if (node.split_dimension < 0) {
          ++stats_.leaves;
          ++stats_.leaf_stops[node.stop];
        }
    stats_.valid_volume_percent = ValidVolumePercent(form_);
  }

  const DesignSpace& space_;
  SampleEvaluator& evaluator_;
  Executor& executor_;
  SamplingOptions options_;
  int n_;
  Form form_;
  SamplingStatistics stats_;
  double executor_seconds_ = 0.0;
};

}  // namespace

double ValidVolumePercent(const Form& form) {
  const DesignSpace space = form.space();
  const int n = space.dimension_count();
  double total = 1.0;
  for (int d = 0; d < n; ++d) total *= space.length(d, space.key_lo(d), space.key_hi(d));
  double valid = 0.0;
  for (const FormTree& t : form.trees)
    for (const FormNode& node : t.nodes) {
      if (node.split_dimension >= 0 || !IsAllValidLeaf(form, node)) continue;
      double v = 1.0;
      for (int d = 0; d < n; ++d) v *= space.length(d, node.lo[d], node.hi[d]);
      valid += v;
    }
  return 100.0 * valid / total;
}

SamplingSummary SampleDesignSpace(const DesignSpace& space, SampleEvaluator& evaluator, Executor& executor,
                                  const SamplingOptions& options) {
  if (options.max_depth < 0 || options.max_depth > 4 * kDyadicBits)
    throw InputError("sampling: max_depth must be in [0, " + std::to_string(4 * kDyadicBits) + "], got " +
                     std::to_string(options.max_depth));
  if (!(options.dg_threshold >= 0.0 && options.dg_threshold <= 1.0))
    throw InputError("sampling: dg_threshold must be in [0, 1], got " + std::to_string(options.dg_threshold));
  if (options.max_samples < 1)
    throw InputError("sampling: max_samples must be >= 1, got " + std::to_string(options.max_samples));
  return Sampler(space, evaluator, executor, options).Run();
}

}  // namespace fabatlas::sampling
