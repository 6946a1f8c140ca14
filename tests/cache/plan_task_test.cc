// The cache plan task (protocol::RunCachePlan, docs/cache.md "Determinism")
// reports the same bits whatever order its records arrive in and however
// many times each key is recorded: `fabatlas sample` sends one record per
// sample that evaluated a subtree, the cluster's store one per key (more
// after retries), and the artifact must not tell them apart.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "fabatlas/error.h"
#include "fabatlas/protocol/cache_plan.h"
#include "fabatlas/protocol/canonical_bytes.h"
#include "synthetic_graphs.h"

namespace fabatlas::protocol {
namespace {

v1::CachePlanSubtree Record(const cache::SubtreeNode& n) {
  v1::CachePlanSubtree r;
  r.set_key(n.key);
  // Real operations, so that the model costs (a + b·bytes) are not round.
  r.set_op(n.children.empty() ? "cylinder" : n.children.size() == 1 ? "translate" : "union");
  for (const auto& c : n.children) r.add_children(c);
  r.set_bytes(static_cast<std::int64_t>(n.bytes));
  r.set_stored(true);
  return r;
}

v1::CachePlanInput Input(const cache::testing::SyntheticGraph& g) {
  v1::CachePlanInput input;
  for (const auto& r : g.samples) input.add_sample_roots(r.root);
  cache::CacheOptions o;
  o.budget_bytes = 2'000'000'000;  // a few entries of 1-100 MB: the curves take many steps
  *input.mutable_options() = CachePlanOptionsOf(o);
  input.mutable_options()->set_exact_max_variables(0);  // time-limited, never in an artifact
  return input;
}

TEST(PlanTask, SameBitsForShuffledAndRepeatedRecords) {
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    cache::testing::SyntheticDesign d;
    d.seed = seed;
    d.samples = 200;
    d.parts = 4;
    const auto g = cache::testing::MakeSyntheticGraph(d);
    // Once per key, in key order: what the cluster's store sends.
    v1::CachePlanInput once = Input(g);
    std::vector<v1::CachePlanSubtree> records;
    for (const auto& n : g.nodes) records.push_back(Record(n));
    std::sort(records.begin(), records.end(), [](const auto& a, const auto& b) { return a.key() < b.key(); });
    for (const auto& r : records) *once.add_subtrees() = r;
    const std::string expected = CanonicalBytes(RunCachePlan(once));

    // Each key 1-7 times, shuffled: samples reporting in process, retries.
    std::mt19937_64 rng(seed);
    for (int trial = 0; trial < 3; ++trial) {
      std::vector<v1::CachePlanSubtree> repeated;
      for (const auto& r : records) {
        const int copies = 1 + static_cast<int>(rng() % 7);
        for (int i = 0; i < copies; ++i) repeated.push_back(r);
      }
      std::shuffle(repeated.begin(), repeated.end(), rng);
      v1::CachePlanInput input = Input(g);
      for (const auto& r : repeated) *input.add_subtrees() = r;
      EXPECT_TRUE(CanonicalBytes(RunCachePlan(input)) == expected)
          << "the report differs: seed " << seed << " trial " << trial;
    }
  }
}

// A key recorded with different children is an error, not a silent merge.
TEST(PlanTask, KeyWithDifferentChildrenIsAnInputError) {
  cache::testing::SyntheticDesign d;
  const auto g = cache::testing::MakeSyntheticGraph(d);
  v1::CachePlanInput input = Input(g);
  for (const auto& n : g.nodes) *input.add_subtrees() = Record(n);
  for (const auto& n : g.nodes)
    if (!n.children.empty()) {
      v1::CachePlanSubtree r = Record(n);
      r.add_children(n.children.front());
      *input.add_subtrees() = r;
      break;
    }
  EXPECT_THROW(RunCachePlan(input), InputError);
}

}  // namespace
}  // namespace fabatlas::protocol
