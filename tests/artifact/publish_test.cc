// The cache part of the artifact (pipeline/cache_assembly.h AddCache): a design
// with two decoupled pieces, like Fab Forms' chess set (Fig. 8), whose
// samples share the pieces' subtrees. Real level sets, real plan, real file.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>

#include "fabatlas/cache/cost_model.h"
#include "fabatlas/pipeline/artifact_of.h"
#include "fabatlas/pipeline/cache_assembly.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/precompute/preview_times.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/sha256.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/artifact/glb.h"
#include "fabatlas/testing/paths.h"

namespace fabatlas::pipeline {
namespace {

namespace fs = std::filesystem;

// 3 x 3 samples: piece A_i (a sphere of radius 3 + i), piece B_j (a box of
// edge 4 + j), root_ij = union(A_i, B_j translated). Every A_i and B_j is
// shared by three samples; every root is used once.
struct ChessLike {
  std::map<std::string, std::string> grids;
  CacheAssembly assembly;
  std::vector<std::string> pieces, roots;
  std::map<std::string, double> sphere_radius;  // key -> radius of the A pieces

  ChessLike() {
    geometry::GridSpec g;
    g.voxel_size = 0.5;
    std::vector<geometry::Solid> a, b;
    std::vector<std::string> ka, kb;
    for (int i = 0; i < 3; ++i) {
      a.push_back(geometry::Sphere(g, 3.0 + i));
      ka.push_back(Add(a.back(), "sphere", {}));
      sphere_radius[ka.back()] = 3.0 + i;
      b.push_back(geometry::Translate(geometry::Box(g, {4.0 + i, 4.0 + i, 4.0 + i}), {12, 0, 0}));
      kb.push_back(Add(b.back(), "box", {}));
    }
    pieces = ka;
    pieces.insert(pieces.end(), kb.begin(), kb.end());
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        // Each sample reports its whole post-order list, as workers do.
        assembly.subtrees.push_back(Record(ka[i], a[i], "sphere", {}));
        assembly.subtrees.push_back(Record(kb[j], b[j], "box", {}));
        roots.push_back(Add(geometry::Union(a[i], b[j]), "union", {ka[i], kb[j]}));
        assembly.sample_roots.push_back(roots.back());
      }
    assembly.options.strategy = cache::Strategy::kOptMax;
    assembly.options.min_seconds = 0.0;
    assembly.grid_of = [this](const std::string& key) { return grids.at(key); };
  }

  CacheSubtree Record(const std::string& key, const geometry::Solid& s, const std::string& op,
                      std::vector<std::string> children) {
    return {key, op, std::move(children), static_cast<std::int64_t>(s.MemoryBytes()), true};
  }
  std::string Add(const geometry::Solid& s, const std::string& op, std::vector<std::string> children) {
    std::string grid = s.Serialize();
    std::string key = Sha256Hex(op + grid);
    grids[key] = grid;
    if (op == "union") assembly.subtrees.push_back(Record(key, s, op, std::move(children)));
    return key;
  }
};

TEST(PublishCache, ChessLikeDesignPlansHoptHrfreeHtopAndTheFileHoldsTheCache) {
  ChessLike chess;
  artifact::Artifact art =
      artifact::ReadArtifact(testing::SourceDir() / "tests/data/artifact_v1/tube_wall_2d.fabatlas");
  const CacheAssemblySummary summary = AddCache(art, chess.assembly);
  const auto& m = art.manifest.cache;
  EXPECT_EQ(m.strategy, "opt_max");
  EXPECT_EQ(summary.missing, 0);
  // H_TOP: the 9 roots. H_rfree: OPT-MAX to the end. With threshold 0 every
  // root is eligible, and a root always has a sample evaluating it until it
  // is cached, so OPT-MAX run to the end caches all 9 and every piece below
  // becomes redundant: H_rfree = H_TOP (Fab Forms' shoe case).
  std::int64_t root_bytes = 0;
  for (const auto& r : chess.assembly.subtrees)
    if (r.op == "union") root_bytes += r.bytes;
  EXPECT_EQ(m.top_entries, 9);
  EXPECT_EQ(m.top_bytes, root_bytes);
  EXPECT_EQ(m.rfree_entries, 9);
  EXPECT_EQ(m.rfree_bytes, root_bytes);
  EXPECT_EQ(m.opt_entries, m.rfree_entries);  // no budget: the chosen cache is H_rfree
  // With a threshold above every union's model cost and below a sphere's
  // (6.56 ms, docs/cache.md), the roots are never cached, so H_rfree is
  // exactly the pieces whose model cost reaches the threshold, the three
  // spheres (boxes cost 1.89 ms), each shared by three samples (Fab Forms'
  // chess and vase rows: H_rfree well below H_TOP).
  double union_seconds = 0;
  for (const auto& r : chess.assembly.subtrees)
    if (r.op == "union") {
      std::uint64_t input = 0;
      for (const auto& p : chess.assembly.subtrees)
        if (p.key == r.children[0] || p.key == r.children[1]) input += static_cast<std::uint64_t>(p.bytes) / 3;
      union_seconds = std::max(union_seconds, cache::ModelSubtreeSeconds("union", r.bytes, input));
    }
  const double sphere_seconds = cache::ModelSubtreeSeconds("sphere", 0, 0);
  ASSERT_LT(union_seconds, sphere_seconds);
  ASSERT_LT(cache::ModelSubtreeSeconds("box", 0, 0), union_seconds);
  {
    ChessLike spheres_only;
    spheres_only.assembly.options.min_seconds = (union_seconds + sphere_seconds) / 2;
    artifact::Artifact p = art;
    AddCache(p, spheres_only.assembly);
    std::int64_t sphere_bytes = 0;
    for (const auto& r : chess.assembly.subtrees)
      if (r.op == "sphere") sphere_bytes += r.bytes;
    EXPECT_EQ(p.manifest.cache.top_entries, 9);
    EXPECT_EQ(p.manifest.cache.rfree_entries, 3);
    EXPECT_EQ(p.manifest.cache.rfree_bytes, sphere_bytes / 3);
    std::set<std::string> keys, spheres;
    for (const auto& e : p.cache) keys.insert(e.key);
    for (const auto& [key, radius] : chess.sphere_radius) spheres.insert(key);
    EXPECT_EQ(keys, spheres);
  }
  // Curves: three strategies, each from the empty cache, mean never above worst.
  std::set<std::string> strategies;
  for (const auto& p : art.cache_curves) {
    strategies.insert(p.strategy);
    EXPECT_LE(p.mean_seconds, p.worst_seconds + 1e-12);
    if (p.step == 0) {
      EXPECT_EQ(p.entries, 0);
    }
  }
  EXPECT_EQ(strategies, (std::set<std::string>{"naive", "opt_ave", "opt_max"}));

  const fs::path path = testing::FreshTempDir("publish") / "chess.fabatlas";
  artifact::WriteArtifact(art, path);
  const artifact::Artifact back = artifact::ReadArtifact(path);
  ASSERT_EQ(back.cache.size(), static_cast<std::size_t>(summary.entries));
  for (const auto& e : back.cache) {
    EXPECT_EQ(e.grid, chess.grids.at(e.key));
    // The glTF mesh is the level set's surface: for a sphere piece, every
    // vertex lies within a voxel of the radius.
    const mesh::TriangleMesh mesh = artifact::GlbToMesh(e.glb);
    EXPECT_GT(mesh.triangles.size(), 100u);
    auto it = chess.sphere_radius.find(e.key);
    if (it == chess.sphere_radius.end()) continue;
    for (const auto& v : mesh.vertices)
      EXPECT_NEAR(std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]), it->second, 0.5);
  }
  // A budget below H_rfree chooses less, and only entries that fit.
  ChessLike tight;
  tight.assembly.options.budget_bytes = static_cast<std::uint64_t>(m.rfree_bytes / 2);
  artifact::Artifact small = art;
  AddCache(small, tight.assembly);
  EXPECT_LE(small.manifest.cache.opt_bytes, m.rfree_bytes / 2);
  EXPECT_EQ(small.manifest.cache.rfree_bytes, m.rfree_bytes);
  std::int64_t opt_bytes = 0;
  for (const auto& e : small.cache)
    if (e.in_opt) opt_bytes += e.bytes;
  EXPECT_EQ(opt_bytes, small.manifest.cache.opt_bytes);
}

TEST(PublishCache, StartingPointsAreValidSamplesOfTheForm) {
  artifact::Artifact art =
      artifact::ReadArtifact(testing::SourceDir() / "tests/data/artifact_v1/tube_wall_2d.fabatlas");
  AddStartingPoints(art);
  ASSERT_FALSE(art.starting_points.empty());
  for (const auto& p : art.starting_points) {
    ASSERT_GE(p.sample_id, 0);
    EXPECT_TRUE(art.form.samples[p.sample_id].outcome.valid);
    EXPECT_EQ(p.u, art.form.samples[p.sample_id].u);
  }
}

}  // namespace
}  // namespace fabatlas::pipeline

namespace fabatlas::pipeline {
namespace {

// A preview through a cache holding a sample's root looks it up before its
// children (EvaluateOptions::lookup_before_children): one record, the same
// key and geometry as the full evaluation, and nothing evaluated below it.
TEST(PreviewCache, CachedRootSkipsItsChildren) {
  const design::Design d = design::LoadDesign(testing::SourceDir() / "configs/designs/tube_wall_2d.yaml");
  const design::Point u = precompute::DesignPointOf(d, {15.0, 6.0});
  design::InMemorySubtreeCache full_cache;
  design::EvaluateOptions full;
  full.cache = &full_cache;
  full.run_checks = false;
  const design::SampleResult first = design::EvaluateSample(d, u, full);
  ASSERT_TRUE(first.valid) << first.failure_reason;
  ASSERT_EQ(first.subtrees.size(), 3u);  // two cylinders and their difference

  precompute::FrozenSubtreeCache roots;
  roots.Add(first.subtrees.back().key, first.solid);
  design::EvaluateOptions preview = full;
  preview.cache = &roots;
  preview.lookup_before_children = true;
  const design::SampleResult second = design::EvaluateSample(d, u, preview);
  ASSERT_EQ(second.subtrees.size(), 1u);
  EXPECT_TRUE(second.subtrees[0].from_cache);
  EXPECT_EQ(second.subtrees[0].key, first.subtrees.back().key);
  EXPECT_EQ(second.subtrees[0].children, first.subtrees.back().children);
  EXPECT_EQ(second.solid.Serialize(), first.solid.Serialize());

  // Without the root, a cached child is used and the other child evaluated.
  precompute::FrozenSubtreeCache child;
  child.Add(first.subtrees[0].key,
            geometry::Solid::Deserialize(full_cache.Find(first.subtrees[0].key)->solid.Serialize()));
  preview.cache = &child;
  const design::SampleResult third = design::EvaluateSample(d, u, preview);
  ASSERT_EQ(third.subtrees.size(), 3u);
  EXPECT_TRUE(third.subtrees[0].from_cache);
  EXPECT_FALSE(third.subtrees[1].from_cache);
  EXPECT_EQ(third.solid.Serialize(), first.solid.Serialize());
}

}  // namespace
}  // namespace fabatlas::pipeline
