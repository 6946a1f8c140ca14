// Adaptive sampling (Fab Forms Sec. 5.2) against designs with closed-form
// valid regions and exact ΔG (analytic_designs.h).
#include "fabatlas/sampling/adaptive_sampler.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "analytic_designs.h"
#include "fabatlas/error.h"
#include "fabatlas/sampling/form_json.h"

namespace fabatlas::sampling {
namespace {

using testing::CountingEvaluator;
using testing::EstimatedRegionIoU;

SamplingOptions Options(int depth, double threshold, std::int64_t budget = 1000000) {
  SamplingOptions o;
  o.max_depth = depth;
  o.dg_threshold = threshold;
  o.max_samples = budget;
  return o;
}

double EdgeChange(const Form& f, std::int64_t a, std::int64_t b) {
  return f.geometry_changes.at({std::min(a, b), std::max(a, b)});
}

// s(u_d) of a node, recomputed from the stored ΔG values (Fab Forms Fig. 7).
std::vector<double> ScoreVector(const Form& f, const FormNode& node, int d) {
  const auto ids = CornerSampleIds(f, node);
  std::vector<double> s;
  for (size_t c = 0; c < ids.size(); ++c)
    if (!((c >> d) & 1)) s.push_back(EdgeChange(f, ids[c], ids[c | (size_t{1} << d)]));
  std::sort(s.begin(), s.end(), std::greater<double>());
  return s;
}

TEST(SamplingAdaptive, HollowCylinder2DReachesIoU95) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(2);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(7, 0.5));
  const double iou = EstimatedRegionIoU(s.form, testing::HollowCylinder2D::TrulyValid);
  EXPECT_GE(iou, 0.95);
  // The valid region {t >= 0.5 + 0.01 R^2} is convex, so the all-valid leaves
  // lie inside it: valid volume <= 41.25 / 67.5 = 61.11 %, and within IoU of it.
  EXPECT_LE(s.statistics.valid_volume_percent, 100.0 * 41.25 / 67.5 + 1e-9);
  EXPECT_GE(s.statistics.valid_volume_percent, 0.95 * 100.0 * 41.25 / 67.5);
  EXPECT_EQ(s.statistics.failure_shares.at("min_thickness"), 1.0);
}

// Issue 3's acceptance figure on a 2-D sliver-shaped region (25.6 % valid):
// adaptive sampling reaches IoU 0.95 with at most a quarter of the samples of
// the coarsest uniform grid that does (bench/sampling has the full sweep).
TEST(SamplingAdaptive, BudgetCylinder2DBeatsUniformFourfold) {
  testing::BudgetCylinder2D ev;
  ThreadPoolExecutor ex(2);
  const auto truth = testing::BudgetCylinder2D::TrulyValid;
  const auto adaptive = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(9, 0.5));
  EXPECT_GE(EstimatedRegionIoU(adaptive.form, truth, 100000), 0.95);
  // A uniform grid with 4x the adaptive samples still falls short of 0.95.
  const int n = static_cast<int>(std::floor(std::sqrt(4.0 * adaptive.statistics.samples))) - 1;
  const auto uniform = SampleDesignSpace(DesignSpace(ev.Dimensions(), n), ev, ex, Options(0, 0.5));
  ASSERT_LE(uniform.statistics.samples, 4 * adaptive.statistics.samples);
  EXPECT_LT(EstimatedRegionIoU(uniform.form, truth, 100000), 0.95);
  EXPECT_GT(adaptive.statistics.failure_shares.at("over_budget"), 0.0);
  EXPECT_GT(adaptive.statistics.failure_shares.at("min_thickness"), 0.0);
}

TEST(SamplingAdaptive, HollowCylinder3DReachesIoU95) {
  testing::HollowCylinder3D ev;
  ThreadPoolExecutor ex(2);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(10, 0.5));
  EXPECT_GE(EstimatedRegionIoU(s.form, testing::HollowCylinder3D::TrulyValid, 100000), 0.95);
  // Both failure types occur; shares are over invalid samples.
  const auto& shares = s.statistics.failure_shares;
  ASSERT_EQ(shares.size(), 2u);
  EXPECT_GT(shares.at("min_thickness"), 0.0);
  EXPECT_GT(shares.at("tips_over"), 0.0);
  EXPECT_NEAR(shares.at("min_thickness") + shares.at("tips_over"), 1.0, 1e-12);
  EXPECT_EQ(s.statistics.samples - s.statistics.valid_samples,
            std::llround(0.0 + std::count_if(s.form.samples.begin(), s.form.samples.end(),
                                             [](const FormSample& x) { return !x.outcome.valid; })));
}

// 1 thread, 2 threads and shuffled completion on two threads give the same
// form byte for byte.
TEST(SamplingAdaptive, DeterministicWhateverThreadsAndCompletionOrder) {
  auto run = [](SampleEvaluator& ev, const std::vector<Dimension>& dims, Executor& ex, int depth) {
    return FormToJson(SampleDesignSpace(DesignSpace(dims, 5), ev, ex, Options(depth, 0.2)).form);
  };
  for (int design = 0; design < 2; ++design) {
    testing::HollowCylinder2D e2;
    testing::HollowCylinder3D e3;
    SampleEvaluator& ev = design == 0 ? static_cast<SampleEvaluator&>(e2) : e3;
    const auto dims = design == 0 ? e2.Dimensions() : e3.Dimensions();
    const int depth = design == 0 ? 7 : 4;
    ThreadPoolExecutor one(1), two(2);
    testing::ShuffledExecutor shuffled_a(7), shuffled_b(2024);
    const std::string reference = run(ev, dims, one, depth);
    EXPECT_GT(reference.size(), 10000u);
    EXPECT_EQ(run(ev, dims, two, depth), reference) << "design " << design;
    EXPECT_EQ(run(ev, dims, shuffled_a, depth), reference) << "design " << design;
    EXPECT_EQ(run(ev, dims, shuffled_b, depth), reference) << "design " << design;
  }
}

TEST(SamplingAdaptive, SharedVerticesAndEdgesEvaluatedOnce) {
  testing::HollowCylinder3D inner;
  CountingEvaluator ev(inner);
  ThreadPoolExecutor ex(2);
  const auto s = SampleDesignSpace(DesignSpace(inner.Dimensions(), 5), ev, ex, Options(5, 0.2));
  // A 6x6x6 bootstrap grid alone has 216 distinct vertices shared by 125 cells.
  EXPECT_GT(s.statistics.samples, 216);
  EXPECT_EQ(static_cast<std::int64_t>(ev.sample_calls_.size()), s.statistics.samples);
  for (const auto& [key, calls] : ev.sample_calls_) EXPECT_EQ(calls, 1);
  EXPECT_EQ(static_cast<std::int64_t>(ev.change_calls_.size()), s.statistics.geometry_change_calls);
  for (const auto& [edge, calls] : ev.change_calls_) EXPECT_EQ(calls, 1);
  EXPECT_EQ(ev.invalid_change_requests_, 0);  // evaluator only sees valid/valid pairs
}

// Fab Forms Sec. 5.2: invalid samples have empty volume.
TEST(SamplingAdaptive, GeometryChangeConventionsAndEveryLeafEdgeKept) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(1);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(6, 0.2));
  const Form& f = s.form;
  int mixed = 0, both_invalid = 0, both_valid = 0;
  for (const auto& [edge, dg] : f.geometry_changes) {
    const FormSample& a = f.samples[edge.first];
    const FormSample& b = f.samples[edge.second];
    if (!a.outcome.valid && !b.outcome.valid) {
      EXPECT_EQ(dg, 0.0);
      ++both_invalid;
    } else if (a.outcome.valid != b.outcome.valid) {
      EXPECT_EQ(dg, 1.0);
      ++mixed;
    } else {
      EXPECT_DOUBLE_EQ(dg, testing::HollowCylinderChange(a.u[0], a.u[1], 10, b.u[0], b.u[1], 10));
      ++both_valid;
    }
  }
  EXPECT_GT(mixed, 0);
  EXPECT_GT(both_invalid, 0);
  EXPECT_GT(both_valid, 0);
  for (const FormTree& t : f.trees)
    for (const FormNode& n : t.nodes)
      for (int d = 0; d < 2; ++d) EXPECT_EQ(ScoreVector(f, n, d).size(), 2u);  // throws if missing
}

// Fab Forms Sec. 5.2 on a case worked by hand: one bootstrap cell of the 2-D
// cylinder. Corners (R, t): (5, .5) and (20, .5) invalid, (5, 5) and (20, 5)
// valid. s(R) = [ΔG((5,5),(20,5)) = 1 (disjoint annuli), 0]; s(t) = [1, 1]
// -> split t at its midpoint 2.75, creating (5, 2.75) valid and (20, 2.75)
// invalid (t_min(20) = 4.5).
TEST(SamplingAdaptive, SplitChoiceWorkedByHand) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(1);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 1), ev, ex, Options(1, 0.1));
  const Form& f = s.form;
  ASSERT_EQ(f.trees.size(), 1u);
  const FormNode& root = f.trees[0].nodes[0];
  EXPECT_EQ(root.split_dimension, 1);
  EXPECT_DOUBLE_EQ(f.space().value(1, root.split_key), 2.75);
  EXPECT_EQ(ScoreVector(f, root, 0), (std::vector<double>{1.0, 0.0}));
  EXPECT_EQ(ScoreVector(f, root, 1), (std::vector<double>{1.0, 1.0}));
  ASSERT_EQ(s.statistics.samples, 6);
  const auto id_lo = f.sample_ids.at({0, root.split_key});
  const auto id_hi = f.sample_ids.at({std::int64_t{1} << kDyadicBits, root.split_key});
  EXPECT_TRUE(f.samples[id_lo].outcome.valid);
  EXPECT_FALSE(f.samples[id_hi].outcome.valid);
}

// Every split in a form follows the ranking rule and every stop its criterion.
void ExpectSplitsFollowRanking(const Form& f, const SamplingOptions& o) {
  const DesignSpace space = f.space();
  const int n = space.dimension_count();
  for (const FormTree& t : f.trees)
    for (const FormNode& node : t.nodes) {
      double max_dg = 0;
      std::vector<std::vector<double>> s(n);
      for (int d = 0; d < n; ++d) {
        s[d] = ScoreVector(f, node, d);
        max_dg = std::max(max_dg, s[d][0]);
      }
      if (node.split_dimension < 0) {
        if (node.stop == LeafStop::kThreshold) {
          EXPECT_LT(max_dg, o.dg_threshold);
        }
        if (node.stop == LeafStop::kMaxDepth) {
          EXPECT_EQ(node.depth, o.max_depth);
        }
        EXPECT_LE(node.depth, o.max_depth);
        continue;
      }
      EXPECT_GE(max_dg, o.dg_threshold);
      const int chosen = node.split_dimension;
      for (int d = 0; d < n; ++d) {
        if (d == chosen) continue;
        const bool ranked_higher = s[d] > s[chosen] || (s[d] == s[chosen] && d < chosen);
        // A higher-ranked direction must have been unusable.
        if (ranked_higher) {
          EXPECT_TRUE(!space.can_split(d, node.lo[d], node.hi[d]) || s[d][0] < o.dg_threshold);
        }
      }
    }
}

TEST(SamplingAdaptive, EverySplitFollowsLexicographicRanking) {
  testing::HollowCylinder3D ev;
  ThreadPoolExecutor ex(2);
  const auto o = Options(5, 0.15);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, o);
  ExpectSplitsFollowRanking(s.form, o);
}

// Enumerated dimension: material with 3 values gets 2 bootstrap cells of
// adjacent values and can never split; the sampler hands over to length.
// All-valid leaves need length < the smaller limit of the band's two
// materials: 0.31 for {pla, petg}, 0.57 for {petg, tpu}.
TEST(SamplingAdaptive, EnumeratedDimensionHandsOverToNextRanked) {
  testing::MaterialBar ev;
  ThreadPoolExecutor ex(2);
  const int depth = 8;
  const auto o = Options(depth, 0.1);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, o);
  const Form& f = s.form;
  ExpectSplitsFollowRanking(f, o);
  for (const FormSample& x : f.samples) {
    EXPECT_EQ(x.u[1], std::round(x.u[1]));
    EXPECT_GE(x.u[1], 0.0);
    EXPECT_LE(x.u[1], 2.0);
  }
  int handovers = 0;
  for (const FormTree& t : f.trees)
    for (const FormNode& node : t.nodes) {
      EXPECT_NE(node.split_dimension, 1);
      if (node.split_dimension == 0 && ScoreVector(f, node, 1) > ScoreVector(f, node, 0)) ++handovers;
    }
  EXPECT_GT(handovers, 0);
  EXPECT_GT(s.statistics.leaf_stops.at(LeafStop::kUnsplittable), 0);
  // Boundary leaves reach max depth: finest length step w = 0.2 / 2^depth.
  const double w = 0.2 / (1 << depth);
  const double expected = 100.0 * (std::floor(0.31 / w) * w + std::floor(0.57 / w) * w) / 2.0;
  EXPECT_NEAR(s.statistics.valid_volume_percent, expected, 1e-9);
}

// Integer dimension: blocks in [0, 10] with 2 bootstrap cells [0,5], [5,10];
// valid iff blocks <= 6; x never matters (ΔG 0 along x), so no x split.
TEST(SamplingAdaptive, IntegerDimensionSplitsOnlyAtWholeValues) {
  testing::BlockStack ev;
  ThreadPoolExecutor ex(1);
  const auto o = Options(10, 0.1);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 2), ev, ex, o);
  ExpectSplitsFollowRanking(s.form, o);
  for (const FormSample& x : s.form.samples) EXPECT_EQ(x.u[1], std::round(x.u[1]));
  for (const FormTree& t : s.form.trees)
    for (const FormNode& node : t.nodes) EXPECT_NE(node.split_dimension, 0);
  // All-valid leaves cover blocks in [0, 6]: 6 of 10 value steps.
  EXPECT_DOUBLE_EQ(s.statistics.valid_volume_percent, 60.0);
  EXPECT_GT(s.statistics.leaf_stops.at(LeafStop::kUnsplittable), 0);
  EXPECT_EQ(s.statistics.failure_shares.at("too_tall"), 1.0);
}

TEST(SamplingAdaptive, StopsAtMaxDepth) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(1);
  const auto flat = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(0, 0.1));
  EXPECT_EQ(flat.statistics.samples, 36);  // 6 x 6 bootstrap vertices
  EXPECT_EQ(flat.statistics.leaves, 25);
  const auto o = Options(3, 0.1);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, o);
  ExpectSplitsFollowRanking(s.form, o);
  EXPECT_GT(s.statistics.leaf_stops.at(LeafStop::kMaxDepth), 0);
}

TEST(SamplingAdaptive, StopsAtThreshold) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(1);
  const auto o = Options(12, 0.3);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, o);
  ExpectSplitsFollowRanking(s.form, o);
  EXPECT_GT(s.statistics.leaf_stops.at(LeafStop::kThreshold), 0);
  // Threshold 1 splits only cells with an edge of ΔG = 1: a valid/invalid
  // pair or two valid cylinders that do not overlap at all; every cell that
  // straddles the boundary is split until max depth.
  const auto o1 = Options(6, 1.0);
  const auto b = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, o1);
  ExpectSplitsFollowRanking(b.form, o1);
  for (const FormTree& t : b.form.trees)
    for (const FormNode& node : t.nodes) {
      int valid = 0;
      for (auto id : CornerSampleIds(b.form, node)) valid += b.form.samples[id].outcome.valid;
      if (valid > 0 && valid < 4) {
        EXPECT_TRUE(node.split_dimension >= 0 || node.depth == 6);
      }
    }
  EXPECT_LT(b.statistics.samples, s.statistics.samples);
}

TEST(SamplingAdaptive, StopsAtSampleBudget) {
  testing::HollowCylinder2D ev;
  ThreadPoolExecutor ex(2);
  for (std::int64_t budget : {37, 120, 500}) {
    const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(12, 0.1, budget));
    EXPECT_LE(s.statistics.samples, budget);
    EXPECT_GT(s.statistics.samples, budget - 2);  // a 2-D split adds at most 2 samples
    EXPECT_GT(s.statistics.leaf_stops.at(LeafStop::kBudget), 0);
  }
  // The bootstrap grid is always complete.
  const auto tiny = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(12, 0.1, 1));
  EXPECT_EQ(tiny.statistics.samples, 36);
}

// Half-plane x + y <= 1.3 on the unit square: true valid fraction 75.5 %; the
// region is convex, so the conservative estimate approaches it from below.
TEST(SamplingAdaptive, ValidVolumeOfKnownFraction) {
  testing::HalfPlane ev;
  ThreadPoolExecutor ex(2);
  const auto s = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(12, 0.5));
  EXPECT_LE(s.statistics.valid_volume_percent, 75.5 + 1e-9);
  EXPECT_GE(s.statistics.valid_volume_percent, 74.5);
  const auto coarse = SampleDesignSpace(DesignSpace(ev.Dimensions(), 5), ev, ex, Options(0, 0.5));
  // 5x5 grid: cells whose far corner has x + y = (i+j+2) 0.2 <= 1.3, i.e.
  // i + j <= 4: 15 cells of 25.
  EXPECT_NEAR(coarse.statistics.valid_volume_percent, 60.0, 1e-9);
}

// Six dimensions (the most sampling::DesignSpace allows): 2^6 corners per leaf. Valid iff
// |u| <= 0.8 on [0,1]^6 (1/64 of the 6-ball, volume
// pi^3/6 0.8^6 / 64 = 2.1167 %); geometry a ball of radius 1 + |u|, nested,
// so ΔG = 1 - (r_small / r_big)^3. The ball is convex: estimate <= 2.1167 %.
class SixBall : public SampleEvaluator {
 public:
  static double Norm(const std::vector<double>& u) {
    double s = 0;
    for (double x : u) s += x * x;
    return std::sqrt(s);
  }
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = Norm(p.u) <= 0.8;
    if (!o.valid) o.failure_type = "outside";
    return o;
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    const double ra = 1 + Norm(a.u), rb = 1 + Norm(b.u);
    return 1.0 - std::pow(std::min(ra, rb) / std::max(ra, rb), 3);
  }
};

TEST(SamplingAdaptive, SixDimensions) {
  std::vector<Dimension> dims;
  for (int d = 0; d < 6; ++d) dims.push_back({"u" + std::to_string(d), DimensionKind::kReal, 0.0, 1.0, {}});
  SixBall ev;
  CountingEvaluator counting(ev);
  ThreadPoolExecutor ex(2);
  const auto o = Options(6, 0.5);
  const auto s = SampleDesignSpace(DesignSpace(dims, 2), counting, ex, o);
  EXPECT_GT(s.statistics.samples, 729);  // 3^6 bootstrap vertices, then refinement
  EXPECT_EQ(static_cast<std::int64_t>(counting.sample_calls_.size()), s.statistics.samples);
  ExpectSplitsFollowRanking(s.form, o);
  const double exact = 100.0 * std::pow(std::numbers::pi, 3) / 6.0 * std::pow(0.8, 6) / 64.0;
  EXPECT_NEAR(exact, 2.1167, 1e-4);
  EXPECT_LE(s.statistics.valid_volume_percent, exact);
  // The estimate exactly, by counting lattice cells: the bootstrap grid has
  // side 1/2 and max_depth 6 splits every dimension once more, so leaves
  // with mixed corners (ΔG = 1 > 0.5 on a valid-invalid edge, always split)
  // end as cubes of side 1/4, and all-valid leaves are unions of such cubes
  // inside the ball. A cube [i, i+1]^6 / 4 lies inside it when its far
  // corner does: sum (i_k + 1)^2 / 16 <= 0.64, i.e. sum (i_k + 1)^2 <= 10.24,
  // true for i = 0 and for the six cubes with one i_k = 1 (sum 9), false for
  // anything more (12). So 7 cubes of (1/4)^6: 7 / 4096 = 0.1709 % of the
  // space, whatever the order of the splits.
  EXPECT_NEAR(s.statistics.valid_volume_percent, 100.0 * 7 / 4096, 1e-9);
}

TEST(SamplingAdaptive, RejectsBadOptions) {
  testing::HalfPlane ev;
  ThreadPoolExecutor ex(1);
  const DesignSpace space(ev.Dimensions(), 5);
  EXPECT_THROW(SampleDesignSpace(space, ev, ex, Options(-1, 0.1)), InputError);
  EXPECT_THROW(SampleDesignSpace(space, ev, ex, Options(3, 1.5)), InputError);
  EXPECT_THROW(SampleDesignSpace(space, ev, ex, Options(3, 0.1, 0)), InputError);
}

}  // namespace
}  // namespace fabatlas::sampling
