// Starting points (Fab Forms Sec. 7.4) on a small sampled form with two
// separate valid regions.
#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "fabatlas/cache/starting_points.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"

namespace fabatlas::cache {
namespace {

using namespace fabatlas::sampling;

// Valid for x < 0.3 or x > 0.7 on [0,1]^2; ΔG between valid samples grows
// with the distance (half the L1 distance, so it stays in [0, 1]).
class TwoBands : public SampleEvaluator {
 public:
  SampleOutcome EvaluateSample(const SamplePoint& p) override {
    SampleOutcome o;
    o.valid = p.u[0] < 0.3 || p.u[0] > 0.7;
    if (!o.valid) o.failure_type = "gap";
    return o;
  }
  double GeometryChange(const SamplePoint& a, const SamplePoint& b) override {
    return 0.5 * (std::abs(a.u[0] - b.u[0]) + std::abs(a.u[1] - b.u[1]));
  }
};

Form TwoBandForm() {
  DesignSpace space({{"x", DimensionKind::kReal, 0.0, 1.0, {}}, {"y", DimensionKind::kReal, 0.0, 1.0, {}}}, 5);
  TwoBands evaluator;
  ThreadPoolExecutor executor(1);
  SamplingOptions o;
  o.max_depth = 0;  // the 6 x 6 bootstrap grid only
  return SampleDesignSpace(space, evaluator, executor, o).form;
}

TEST(StartingPoints, OnePerComponentAtTheCentreOfEachBand) {
  Form form = TwoBandForm();
  ASSERT_EQ(form.samples.size(), 36u);
  std::vector<StartingPoint> points = ChooseStartingPoints(form, {.count = 2, .seed = 1});
  ASSERT_EQ(points.size(), 2u);
  std::set<int> components;
  for (const StartingPoint& p : points) {
    components.insert(p.component);
    EXPECT_EQ(p.segment_size, 12);  // a band is 2 x 6 grid samples
    // Sum of L1 distances over a 2 x 6 grid is least in the middle rows.
    EXPECT_TRUE(std::abs(p.u[1] - 0.4) < 1e-9 || std::abs(p.u[1] - 0.6) < 1e-9) << p.u[1];
    EXPECT_TRUE(p.u[0] < 0.3 || p.u[0] > 0.7);
  }
  EXPECT_EQ(components.size(), 2u);
}

TEST(StartingPoints, AskingForOneStillSeedsEveryComponent) {
  Form form = TwoBandForm();
  EXPECT_EQ(ChooseStartingPoints(form, {.count = 1, .seed = 3}).size(), 2u);
}

TEST(StartingPoints, FarthestPointSegmentsSplitABandAndAreDeterministic) {
  Form form = TwoBandForm();
  auto a = ChooseStartingPoints(form, {.count = 4, .seed = 9});
  auto b = ChooseStartingPoints(form, {.count = 4, .seed = 9});
  ASSERT_EQ(a.size(), 4u);
  std::int64_t total = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].sample_id, b[i].sample_id);
    total += a[i].segment_size;
  }
  EXPECT_EQ(total, 24);  // every valid sample in exactly one segment
  // Both bands are split in two: the third and fourth seeds are the samples
  // farthest from the first two, at the far ends of the bands.
  std::set<std::int64_t> ids;
  for (const auto& p : a) ids.insert(p.sample_id);
  EXPECT_EQ(ids.size(), 4u);
}

TEST(StartingPoints, LargeSegmentsUseTheDescentAndStayInTheBand) {
  Form form = TwoBandForm();
  auto points = ChooseStartingPoints(form, {.count = 2, .seed = 1, .max_exact_centroid = 4});
  ASSERT_EQ(points.size(), 2u);
  for (const auto& p : points) EXPECT_TRUE(std::abs(p.u[1] - 0.4) < 1e-9 || std::abs(p.u[1] - 0.6) < 1e-9) << p.u[1];
}

TEST(StartingPoints, NoValidSampleNoStartingPoint) {
  Form form;
  EXPECT_TRUE(ChooseStartingPoints(form).empty());
}

}  // namespace
}  // namespace fabatlas::cache
