// Fab Forms Sec. 6.3 Alg. 1 (OPT-MAX) and the NAIVE and OPT-AVE strategies of
// Sec. 8 / Fig. 13.
//
// The greedy runs incrementally so that graphs of millions of subtrees plan in
// seconds. State per node: q(X), the number of times X is requested over all
// samples given H (n_H(X) = q(X) for X not in H). Adding X to H removes q(X)
// requests from each of X's children and, through the children not in H,
// further down: only X's H-free descendants are touched. Scores t·n_H only
// ever decrease as H grows, so the OPT-AVE choice comes from a lazy max-heap;
// T_H(r) only decreases too, so the worst sample comes from a lazy max-heap
// over root nodes whose entries are recomputed (a walk of one sample's
// H-free tree) when they reach the top.
#include "fabatlas/cache/optimize_cache.h"

#include <algorithm>
#include <map>
#include <queue>
#include <utility>

#include "fabatlas/error.h"

namespace fabatlas::cache {

const char* StrategyName(Strategy strategy) {
  switch (strategy) {
    case Strategy::kNaive:
      return "naive";
    case Strategy::kOptAve:
      return "opt_ave";
    case Strategy::kOptMax:
      return "opt_max";
  }
  return "?";
}

namespace {

using Id = std::int32_t;
using ScoreKind = Score;

struct Entry {
  double value;
  Id id;
  // Max-heap: larger value first, then lower id.
  bool operator<(const Entry& o) const { return value < o.value || (value == o.value && id > o.id); }
};

class Planner {
 public:
  Planner(const DependencyGraph& g, const CacheOptions& o) : g_(g), o_(o) {
    const std::size_t n = g.keys.size();
    if (g.seconds.size() != n || g.bytes.size() != n || g.stored.size() != n || g.child_begin.size() != n + 1 ||
        g.topological_order.size() != n)
      throw InputError("cache plan: malformed dependency graph");
    in_h_.assign(n, 0);
    q_.assign(n, 0.0);
    topo_pos_.assign(n, 0);
    stamp_.assign(n, 0);
    memo_stamp_.assign(n, 0);
    memo_.assign(n, 0.0);
    delta_.assign(n, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      topo_pos_[static_cast<std::size_t>(g.topological_order[i])] = static_cast<Id>(i);
    for (Id r : g.sample_roots) q_[static_cast<std::size_t>(r)] += 1;
    for (Id v : g.topological_order) {
      double qv = q_[static_cast<std::size_t>(v)];
      if (qv == 0) continue;
      for (std::int64_t e = g.child_begin[v]; e < g.child_begin[v + 1]; ++e) q_[Child(e)] += qv;
    }
    for (std::size_t i = 0; i < n; ++i) total_ += static_cast<long double>(g.seconds[i]) * q_[i];
    std::vector<char> is_root(n, 0);
    for (Id r : g.sample_roots) {
      if (is_root[static_cast<std::size_t>(r)]) continue;
      is_root[static_cast<std::size_t>(r)] = 1;
      roots_.push({RootTime(r), r});
    }
    for (std::size_t i = 0; i < n; ++i)
      if (Choosable(static_cast<Id>(i))) nodes_.push({Score(static_cast<Id>(i)), static_cast<Id>(i)});
  }

  CachePlan Run() {
    CachePlan plan;
    plan.strategy = o_.strategy;
    if (o_.record_curve) plan.curve.push_back(Point());
    if (o_.strategy == Strategy::kNaive) {
      std::vector<Entry> order;
      for (std::size_t i = 0; i < g_.keys.size(); ++i)
        if (Choosable(static_cast<Id>(i))) order.push_back({Score(static_cast<Id>(i)), static_cast<Id>(i)});
      std::sort(order.begin(), order.end(), [](const Entry& a, const Entry& b) { return b < a; });
      for (const Entry& e : order) {
        if (!Fits(e.id)) continue;
        Add(e.id, /*drop_redundant=*/false);
        ++plan.steps;
        if (o_.record_curve) plan.curve.push_back(Point());
      }
    } else {
      while (true) {
        Id x = -1;
        if (o_.strategy == Strategy::kOptMax) {
          x = WorstSampleChoice();
          // The worst sample's best node must be worth at least
          // average_share of the best node overall.
          if (x >= 0 && o_.average_share > 0) {
            Id y = AverageChoice();
            if (y >= 0) {
              nodes_.push({Score(y), y});
              if (Score(x) < o_.average_share * Score(y)) x = y;
            }
          }
        }
        if (x < 0) x = AverageChoice();
        if (x < 0) break;
        Add(x, /*drop_redundant=*/true);
        ++plan.steps;
        if (o_.record_curve) plan.curve.push_back(Point());
      }
    }
    plan.dropped = dropped_;
    plan.cache = in_h_;
    for (std::size_t i = 0; i < in_h_.size(); ++i)
      if (in_h_[i]) plan.chosen.push_back(static_cast<Id>(i));
    plan.cost = EvaluateCache(g_, plan.cache);
    return plan;
  }

 private:
  std::size_t Child(std::int64_t e) const {
    return static_cast<std::size_t>(g_.child_ids[static_cast<std::size_t>(e)]);
  }
  // What a strategy maximises (CacheOptions::score). Every variant only
  // decreases as H grows (q and the H-free subtree time both do), which the
  // lazy heap relies on.
  double Score(Id x) {
    auto i = static_cast<std::size_t>(x);
    switch (o_.score) {
      case ScoreKind::kTimesCount:
        return g_.seconds[i] * q_[i];
      case ScoreKind::kPerByte:
        return g_.seconds[i] * q_[i] / static_cast<double>(std::max<std::uint64_t>(g_.bytes[i], 1));
      case ScoreKind::kSavedPerByte:
        return SavedPerByte(x, RootTime(x));
    }
    return 0;
  }
  double SavedPerByte(Id x, double subtree_seconds) const {
    auto i = static_cast<std::size_t>(x);
    return subtree_seconds * q_[i] / static_cast<double>(std::max<std::uint64_t>(g_.bytes[i], 1));
  }
  bool Choosable(Id x) const {
    auto i = static_cast<std::size_t>(x);
    return !in_h_[i] && g_.stored[i] && g_.seconds[i] > 0 && g_.seconds[i] >= o_.min_seconds && q_[i] > 0;
  }
  bool Fits(Id x) const {
    std::uint64_t b = g_.bytes[static_cast<std::size_t>(x)];
    return bytes_ <= o_.budget_bytes && b <= o_.budget_bytes - bytes_;
  }

  CurvePoint Point() {
    CurvePoint p;
    p.bytes = bytes_;
    p.entries = entries_;
    p.mean_seconds = g_.sample_roots.empty() ? 0.0 : static_cast<double>(total_ / g_.sample_roots.size());
    if (p.mean_seconds < 0) p.mean_seconds = 0;
    std::vector<Id> tied;
    p.worst_seconds = WorstRoots(&tied);
    return p;
  }

  // T_H of a sample rooted at r: its H-free tree, children before parents.
  double RootTime(Id r) {
    if (in_h_[static_cast<std::size_t>(r)]) return 0.0;
    ++memo_epoch_;
    // Iterative post-order with memo (a subtree used twice is counted twice).
    stack_.clear();
    stack_.push_back({r, false});
    while (!stack_.empty()) {
      auto [v, expanded] = stack_.back();
      stack_.pop_back();
      auto vi = static_cast<std::size_t>(v);
      if (memo_stamp_[vi] == memo_epoch_ && !expanded) continue;
      if (!expanded) {
        stack_.push_back({v, true});
        for (std::int64_t e = g_.child_begin[v]; e < g_.child_begin[v + 1]; ++e) {
          std::size_t c = Child(e);
          if (!in_h_[c] && memo_stamp_[c] != memo_epoch_) stack_.push_back({static_cast<Id>(c), false});
        }
        continue;
      }
      if (memo_stamp_[vi] == memo_epoch_) continue;
      double sum = g_.seconds[vi];
      for (std::int64_t e = g_.child_begin[v]; e < g_.child_begin[v + 1]; ++e) {
        std::size_t c = Child(e);
        if (!in_h_[c]) sum += memo_[c];
      }
      memo_[vi] = sum;
      memo_stamp_[vi] = memo_epoch_;
    }
    return memo_[static_cast<std::size_t>(r)];
  }

  // The largest T_H over samples and every root node attaining it (none when
  // every sample previews in 0 s). Stored values are upper bounds: a popped
  // entry is recomputed and re-inserted when it was stale.
  double WorstRoots(std::vector<Id>* tied) {
    tied->clear();
    double worst = -1;
    while (!roots_.empty()) {
      Entry top = roots_.top();
      if (worst >= 0 && top.value < worst) break;
      roots_.pop();
      double t = RootTime(top.id);
      if (t <= 0) continue;  // T only decreases: this root stays at 0
      if (t < top.value) {
        roots_.push({t, top.id});
        continue;
      }
      if (worst < 0) worst = t;
      if (t == worst)
        tied->push_back(top.id);
      else
        roots_.push({t, top.id});
    }
    for (Id r : *tied) roots_.push({worst, r});
    return worst < 0 ? 0.0 : worst;
  }

  // Alg. 1: the descendant of the worst samples with the largest t·n_H.
  Id WorstSampleChoice() {
    std::vector<Id> tied;
    if (WorstRoots(&tied) <= 0) return -1;
    ++epoch_;
    Id best = -1;
    double best_score = 0;
    for (Id r : tied) {
      // One post-order pass gives C_H of every node below r (memo_), so the
      // saved-time scores need no walk of their own.
      RootTime(r);
      walk_.clear();
      if (stamp_[static_cast<std::size_t>(r)] != epoch_) {
        stamp_[static_cast<std::size_t>(r)] = epoch_;
        walk_.push_back(r);
      }
      while (!walk_.empty()) {
        Id v = walk_.back();
        walk_.pop_back();
        if (Choosable(v) && Fits(v)) {
          double s =
              o_.score == ScoreKind::kSavedPerByte ? SavedPerByte(v, memo_[static_cast<std::size_t>(v)]) : Score(v);
          if (s > best_score || (s == best_score && best >= 0 && v < best)) {
            best = v;
            best_score = s;
          }
        }
        for (std::int64_t e = g_.child_begin[v]; e < g_.child_begin[v + 1]; ++e) {
          std::size_t c = Child(e);
          if (in_h_[c] || stamp_[c] == epoch_) continue;
          stamp_[c] = epoch_;
          walk_.push_back(static_cast<Id>(c));
        }
      }
    }
    return best;
  }

  // OPT-AVE: the node with the largest t·n_H that fits.
  Id AverageChoice() {
    while (!nodes_.empty()) {
      Entry top = nodes_.top();
      nodes_.pop();
      if (!Choosable(top.id)) continue;
      double s = Score(top.id);
      if (s < top.value) {
        nodes_.push({s, top.id});
        continue;
      }
      if (!Fits(top.id)) {
        deferred_.emplace(g_.bytes[static_cast<std::size_t>(top.id)], top.id);
        continue;
      }
      return top.id;
    }
    return -1;
  }

  void Drop(Id v) {
    auto i = static_cast<std::size_t>(v);
    in_h_[i] = 0;
    bytes_ -= g_.bytes[i];
    --entries_;
    ++dropped_;
    // Bytes came free: what was set aside for not fitting may fit now.
    std::uint64_t room = o_.budget_bytes - bytes_;
    while (!deferred_.empty() && deferred_.begin()->first <= room) {
      Id d = deferred_.begin()->second;
      deferred_.erase(deferred_.begin());
      if (Choosable(d)) nodes_.push({Score(d), d});
    }
  }

  void Add(Id x, bool drop_redundant) {
    auto xi = static_cast<std::size_t>(x);
    in_h_[xi] = 1;
    bytes_ += g_.bytes[xi];
    ++entries_;
    total_ -= static_cast<long double>(g_.seconds[xi]) * q_[xi];
    if (q_[xi] == 0) return;
    // X's H-free descendants (nodes of H included as the ends).
    ++epoch_;
    below_.clear();
    walk_.clear();
    walk_.push_back(x);
    while (!walk_.empty()) {
      Id v = walk_.back();
      walk_.pop_back();
      for (std::int64_t e = g_.child_begin[v]; e < g_.child_begin[v + 1]; ++e) {
        std::size_t c = Child(e);
        if (stamp_[c] == epoch_) continue;
        stamp_[c] = epoch_;
        delta_[c] = 0;
        below_.push_back(static_cast<Id>(c));
        if (!in_h_[c]) walk_.push_back(static_cast<Id>(c));
      }
    }
    std::sort(below_.begin(), below_.end(), [&](Id a, Id b) {
      return topo_pos_[static_cast<std::size_t>(a)] < topo_pos_[static_cast<std::size_t>(b)];
    });
    for (std::int64_t e = g_.child_begin[x]; e < g_.child_begin[x + 1]; ++e) delta_[Child(e)] += q_[xi];
    for (Id v : below_) {
      auto vi = static_cast<std::size_t>(v);
      double d = delta_[vi];
      if (d == 0) continue;
      q_[vi] -= d;
      if (q_[vi] < 0) q_[vi] = 0;
      if (in_h_[vi]) {
        if (drop_redundant && q_[vi] == 0) Drop(v);
        continue;
      }
      total_ -= static_cast<long double>(g_.seconds[vi]) * d;
      for (std::int64_t e = g_.child_begin[v]; e < g_.child_begin[v + 1]; ++e) delta_[Child(e)] += d;
    }
  }

  const DependencyGraph& g_;
  const CacheOptions& o_;
  CacheSet in_h_;
  std::vector<double> q_;
  std::vector<Id> topo_pos_;
  std::vector<std::uint64_t> stamp_, memo_stamp_;  // walks; RootTime's memo
  std::uint64_t epoch_ = 0, memo_epoch_ = 0;
  std::vector<double> memo_, delta_;
  std::vector<std::pair<Id, bool>> stack_;
  std::vector<Id> walk_, below_;
  std::priority_queue<Entry> roots_, nodes_;
  std::multimap<std::uint64_t, Id> deferred_;
  long double total_ = 0;
  std::uint64_t bytes_ = 0;
  std::int64_t entries_ = 0, dropped_ = 0;
};

}  // namespace

CachePlan OptimizeCache(const DependencyGraph& graph, const CacheOptions& options) {
  return Planner(graph, options).Run();
}

CacheReport PlanCache(const DependencyGraph& graph, const CacheOptions& options) {
  CacheReport report;
  report.none = EvaluateCache(graph, CacheSet(graph.keys.size(), 0));
  report.top = EvaluateCache(graph, TopLevelCache(graph));
  CacheOptions rfree = options;
  rfree.strategy = Strategy::kOptMax;
  rfree.budget_bytes = std::numeric_limits<std::uint64_t>::max();
  rfree.record_curve = false;
  report.rfree = OptimizeCache(graph, rfree).cost;
  report.chosen = OptimizeCache(graph, options);
  return report;
}

}  // namespace fabatlas::cache
