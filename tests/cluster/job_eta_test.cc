// EstimateJobEta (coordinator/job_eta.h) on schedules whose remaining wall
// time is known in closed form: rounds that grow geometrically, as the
// model assumes once it has seen them, so the estimate must equal the sum of
// the batches still to come; and the budget, the depth limit, the running
// batch's own rate, replayed batches and publishing.
#include <gtest/gtest.h>

#include "fabatlas/coordinator/job_eta.h"

namespace fabatlas::coordinator {
namespace {

constexpr double kTs = 0.01, kTg = 0.02;  // wall seconds per sample / ΔG task

// The true schedule: bootstrap S_0 = 1000 with h_0 = 1 ΔG task per sample;
// then S_1 = 400 and every later round twice the last (g = 2), with h = 2.5
// ΔG tasks per new sample; max_depth 3.
const double kS[] = {1000, 400, 800, 1600};
const double kG[] = {1000, 1000, 2000, 4000};

JobEtaInput Upto(int batches_done, bool running_samples_next) {
  JobEtaInput in;
  in.max_depth = 3;
  in.max_samples = 100000;
  in.dimensions = 3;
  int i = 0;
  for (int d = 0; d <= 3 && i < batches_done; ++d) {
    in.batches.push_back({true, kS[d], kS[d] * kTs});
    if (++i == batches_done) break;
    in.batches.push_back({false, kG[d], kG[d] * kTg});
    ++i;
  }
  // The next batch starts now (nothing of it done).
  const int d = batches_done / 2;
  if (running_samples_next) in.batches.push_back({true, kS[d], 0});
  else in.batches.push_back({false, kG[d], 0});
  in.running_left = in.batches.back().tasks;
  return in;
}

double Remaining(int from_batch) {
  double seconds = 0;
  for (int b = from_batch; b < 8; ++b) seconds += b % 2 == 0 ? kS[b / 2] * kTs : kG[b / 2] * kTg;
  return seconds;
}

TEST(JobEta, GeometricRoundsAreSummedExactlyOnceTheirRatesAreSeen) {
  JobEtaOptions options;  // first_growth 2, first split factor 2.5: this schedule's
  const double publish = options.publish_seconds_per_sample * (1000 + 400 + 800 + 1600);
  // From the start of S_1 (h of the first split round from the bootstrap's
  // times the factor), S_2, G_2, S_3 and G_3.
  for (int done : {2, 3, 4, 5, 6, 7}) {
    const JobEta eta = EstimateJobEta(Upto(done, done % 2 == 0), options);
    ASSERT_TRUE(eta.known);
    EXPECT_NEAR(eta.seconds, Remaining(done) + publish, 1e-9) << "batches done " << done;
    EXPECT_NEAR(eta.predicted_samples, 3800, 1e-9);
    EXPECT_NEAR(eta.publish_seconds, publish, 1e-12);
  }
}

TEST(JobEta, TheBudgetEndsRefinementAndTheDepthLimitEndsRounds) {
  // Budget: 2,900 samples leave S_3 = 700 of its 1,600 (and G_3 = 2.5 x 700).
  JobEtaInput in = Upto(4, true);
  in.max_samples = 2900;
  JobEtaOptions options;
  options.publish_seconds_per_sample = 0;
  EXPECT_NEAR(EstimateJobEta(in, options).seconds, 800 * kTs + 2000 * kTg + 700 * kTs + 1750 * kTg, 1e-9);
  EXPECT_NEAR(EstimateJobEta(in, options).predicted_samples, 2900, 1e-9);
  // max_depth 2: S_2 and its ΔG batch are the last.
  in.max_samples = 100000;
  in.max_depth = 2;
  EXPECT_NEAR(EstimateJobEta(in, options).seconds, 800 * kTs + 2000 * kTg, 1e-9);
}

TEST(JobEta, TheRunningBatchsOwnRateWeighsInByTheShareOfItDone) {
  JobEtaOptions options;
  options.publish_seconds_per_sample = 0;
  JobEtaInput in = Upto(7, false);  // G_3 running: 4,000 tasks, the last of the job
  // 1,000 done (a quarter) in 40 s: 0.04 s per task so far, after 0.02 on
  // G_2: 0.75 x 0.02 + 0.25 x 0.04 = 0.025 s per task for the 3,000 left.
  in.running_left = 3000;
  in.running_seconds = 40;
  EXPECT_NEAR(EstimateJobEta(in, options).seconds, 75, 1e-9);
  // Nothing done yet: G_2's rate.
  in.running_left = 4000;
  in.running_seconds = 5;
  EXPECT_NEAR(EstimateJobEta(in, options).seconds, 80, 1e-9);
  // The first ΔG batch, a quarter done in 2 s (no earlier ΔG rate): its own
  // 0.008 s per task for the 750 left and for the ΔG batch to come; then
  // S_1 = first_growth x 1,000 at S_0's 0.01 s per task, G_1 = 2.5 ΔG tasks
  // per new sample (first_split_dg_per_sample_factor x G_0 / S_0).
  JobEtaInput first = Upto(1, false);
  first.max_depth = 1;
  first.running_left = 750;
  first.running_seconds = 2;
  EXPECT_NEAR(EstimateJobEta(first, options).seconds, 750 * 0.008 + 2000 * 0.01 + 2.5 * 2000 * 0.008, 1e-9);
}

TEST(JobEta, TheLoadFactorOfTheRunningBatchPricesBothKinds) {
  // Evaluator CPU 0.004 s per sample task and 0.008 per ΔG task, run at 2.5
  // wall seconds per CPU second (kTs, kTg).
  JobEtaInput in = Upto(6, true);  // S_3 running: 1,600 sample tasks
  for (auto& b : in.batches)
    if (b.seconds > 0) b.cpu_seconds = b.tasks * (b.samples ? 0.004 : 0.008);
  JobEtaOptions options;
  options.publish_seconds_per_sample = 0;
  // Half of S_3 done in 16 s: 0.02 wall s per task, 5 per CPU second;
  // blended half and half with G_2's 2.5: 3.75. The 800 sample tasks left
  // at 0.004 x 3.75 and G_3 (2.5 x 1,600 ΔG tasks) at 0.008 x 3.75, where
  // each kind's own last wall time would price G_3 at G_2's 0.02.
  in.running_left = 800;
  in.running_seconds = 16;
  EXPECT_NEAR(EstimateJobEta(in, options).seconds, 800 * 0.004 * 3.75 + 4000 * 0.008 * 3.75, 1e-9);
  // Without CPU figures: each kind's own (S_3 blended to 0.015, G_2's 0.02).
  for (auto& b : in.batches) b.cpu_seconds = 0;
  EXPECT_NEAR(EstimateJobEta(in, options).seconds, 800 * 0.015 + 4000 * 0.02, 1e-9);
}

TEST(JobEta, ReplayedBatchesTeachNothingAndPublishingCountsDown) {
  JobEtaInput in = Upto(3, false);
  for (auto& b : in.batches) b.seconds = 0;  // all replayed from the store
  in.running_seconds = 0.01;
  in.running_left = in.batches.back().tasks;
  EXPECT_FALSE(EstimateJobEta(in).known);

  JobEtaInput done = Upto(8, false);
  done.batches.pop_back();
  JobEtaOptions options;
  options.publish_seconds_per_sample = 0.001;  // 3.8 s for 3,800 samples
  done.publishing_seconds = 1.3;
  const JobEta eta = EstimateJobEta(done, options);
  ASSERT_TRUE(eta.known);
  EXPECT_NEAR(eta.seconds, 2.5, 1e-9);
  done.publishing_seconds = 10;
  EXPECT_EQ(EstimateJobEta(done, options).seconds, 0);
}

}  // namespace
}  // namespace fabatlas::coordinator
