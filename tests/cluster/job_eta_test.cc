// EstimateJobEta (coordinator/job_eta.h) on schedules whose remaining wall
// time is known in closed form: rounds that grow geometrically, as the
// model assumes once it has seen them, run by a machine whose rate of work
// is given, so the estimate must equal the work of the batches still to
// come over that rate; and the budget, the depth limit, the running batch's
// own CPU, a change of load inside the sliding window, replayed batches and
// publishing.
#include <gtest/gtest.h>

#include <cmath>

#include "fabatlas/coordinator/job_eta.h"

namespace fabatlas::coordinator {
namespace {

// Evaluator CPU seconds per sample / ΔG task, and the overhead per task.
constexpr double kCs = 0.004, kCg = 0.008, kO = 0.001;
constexpr double kWs = kCs + kO, kWg = kCg + kO;  // work per task, CPU seconds

// The true schedule: bootstrap S_0 = 1000 with h_0 = 1 ΔG task per sample;
// then S_1 = 400 and every later round twice the last (g = 2), with h = 2.5
// ΔG tasks per new sample; max_depth 3.
const double kS[] = {1000, 400, 800, 1600};
const double kG[] = {1000, 1000, 2000, 4000};

JobEtaOptions Options() {
  JobEtaOptions o;  // first_growth 2, first split factor 2.5: this schedule's
  o.overhead_cpu_seconds_per_task = kO;
  o.rate_window_seconds = 60;
  o.publish_seconds_per_sample = 0;
  return o;
}

// The workers' reports over the last `seconds`: one a second, ΔG tasks
// only, at `before` tasks per second until `change_ago` seconds ago and
// `after` since.
std::vector<EtaProgress> History(double seconds, double before, double after, double change_ago) {
  std::vector<EtaProgress> h;
  double tasks = 0;
  for (int ago = static_cast<int>(seconds); ago >= 0; --ago) {
    h.push_back({static_cast<double>(ago), kCg * tasks, tasks});
    tasks += ago > change_ago ? before : after;
  }
  return h;
}

// A machine that has done 100 ΔG tasks a second for 200 s: 0.9 CPU
// seconds of work per wall second.
constexpr double kRate = 100 * kWg;

JobEtaInput Upto(int batches_done, bool running_samples_next) {
  JobEtaInput in;
  in.max_depth = 3;
  in.max_samples = 100000;
  in.dimensions = 3;
  int i = 0;
  for (int d = 0; d <= 3 && i < batches_done; ++d) {
    in.batches.push_back({true, kS[d], kS[d] * kCs});
    if (++i == batches_done) break;
    in.batches.push_back({false, kG[d], kG[d] * kCg});
    ++i;
  }
  // The next batch starts now (nothing of it done).
  const int d = batches_done / 2;
  if (running_samples_next)
    in.batches.push_back({true, kS[d], 0});
  else
    in.batches.push_back({false, kG[d], 0});
  in.running_left = in.batches.back().tasks;
  in.progress = History(200, 100, 100, 0);
  return in;
}

// CPU seconds of work from batch `from_batch` (S_0 = 0, G_0 = 1, ...) on.
double Remaining(int from_batch) {
  double work = 0;
  for (int b = from_batch; b < 8; ++b) work += b % 2 == 0 ? kS[b / 2] * kWs : kG[b / 2] * kWg;
  return work;
}

TEST(JobEta, GeometricRoundsAreSummedExactlyOnceTheirRatesAreSeen) {
  JobEtaOptions options = Options();
  options.publish_seconds_per_sample = 0.001;
  const double publish = 0.001 * (1000 + 400 + 800 + 1600);
  // From the start of S_1 (h of the first split round from the bootstrap's
  // times the factor), S_2, G_2, S_3 and G_3.
  for (int done : {2, 3, 4, 5, 6, 7}) {
    const JobEta eta = EstimateJobEta(Upto(done, done % 2 == 0), options);
    ASSERT_TRUE(eta.known);
    EXPECT_NEAR(eta.rate, kRate, 1e-12);
    EXPECT_NEAR(eta.work_cpu_seconds, Remaining(done), 1e-9) << "batches done " << done;
    EXPECT_NEAR(eta.seconds, Remaining(done) / kRate + publish, 1e-9) << "batches done " << done;
    EXPECT_NEAR(eta.predicted_samples, 3800, 1e-9);
    EXPECT_NEAR(eta.publish_seconds, publish, 1e-12);
  }
}

TEST(JobEta, TheBudgetEndsRefinementAndTheDepthLimitEndsRounds) {
  // Budget: 2,900 samples leave S_3 = 700 of its 1,600 (and G_3 = 2.5 x 700).
  JobEtaInput in = Upto(4, true);
  in.max_samples = 2900;
  EXPECT_NEAR(EstimateJobEta(in, Options()).seconds, (800 * kWs + 2000 * kWg + 700 * kWs + 1750 * kWg) / kRate, 1e-9);
  EXPECT_NEAR(EstimateJobEta(in, Options()).predicted_samples, 2900, 1e-9);
  // max_depth 2: S_2 and its ΔG batch are the last.
  in.max_samples = 100000;
  in.max_depth = 2;
  EXPECT_NEAR(EstimateJobEta(in, Options()).seconds, (800 * kWs + 2000 * kWg) / kRate, 1e-9);
}

TEST(JobEta, TheRunningBatchsOwnCpuWeighsInByTheShareOfItDone) {
  JobEtaInput in = Upto(7, false);  // G_3 running: 4,000 tasks, the last of the job
  // 1,000 done (a quarter) at 0.016 CPU s each, after 0.008 on G_2:
  // 0.75 x 0.008 + 0.25 x 0.016 = 0.010 CPU s, + 0.001 overhead, for the
  // 3,000 left.
  in.running_left = 3000;
  in.running_done = {0, 16, 1000};
  EXPECT_NEAR(EstimateJobEta(in, Options()).seconds, 3000 * 0.011 / kRate, 1e-9);
  // Nothing done yet: G_2's CPU per task.
  in.running_left = 4000;
  in.running_done = {};
  EXPECT_NEAR(EstimateJobEta(in, Options()).seconds, 4000 * kWg / kRate, 1e-9);
  // The first ΔG batch, a quarter done at 0.012 CPU s per task (no earlier
  // ΔG batch): its own CPU for the 750 left and for the ΔG batches to come;
  // then S_1 = first_growth x 1,000 at S_0's CPU, G_1 = 2.5 ΔG tasks per
  // new sample (first_split_dg_per_sample_factor x G_0 / S_0).
  JobEtaInput first = Upto(1, false);
  first.max_depth = 1;
  first.running_left = 750;
  first.running_done = {0, 3, 250};
  EXPECT_NEAR(EstimateJobEta(first, Options()).seconds, (750 * 0.013 + 2000 * kWs + 2.5 * 2000 * 0.013) / kRate, 1e-9);
  // Before any ΔG result, ΔG tasks are priced as sample tasks.
  JobEtaInput bootstrap = Upto(0, true);
  bootstrap.max_depth = 0;
  bootstrap.running_left = 600;
  bootstrap.running_done = {0, 1.6, 400};
  // Its ΔG batch: one edge per dimension and sample until one is seen.
  EXPECT_NEAR(EstimateJobEta(bootstrap, Options()).seconds, (600 * kWs + 3 * 1000 * kWs) / kRate, 1e-9);
}

TEST(JobEta, AChangeOfLoadScalesAllKindsAlikeWithinOneWindow) {
  // S_3 running; the machine did 200 ΔG tasks a second (1.8 CPU s of work
  // per wall second) until a CPU hog started 30 s ago, 50 (0.45) since:
  // the last 60 s did 30 x 200 + 30 x 50 tasks, 67.5 CPU s, 1.125 a second.
  JobEtaInput in = Upto(6, true);
  in.progress = History(200, 200, 50, 30);
  const double work = 1600 * kWs + 4000 * kWg;
  JobEta eta = EstimateJobEta(in, Options());
  EXPECT_NEAR(eta.rate, 67.5 / 60, 1e-12);
  EXPECT_NEAR(eta.seconds, work / 1.125, 1e-9);
  // 90 s after the change, the window holds only the new rate.
  in.progress = History(200, 200, 50, 90);
  EXPECT_NEAR(EstimateJobEta(in, Options()).seconds, work / 0.45, 1e-9);
  // A driver 20 s old: the rate since it started (the window is not full).
  in.progress = History(20, 100, 100, 0);
  EXPECT_NEAR(EstimateJobEta(in, Options()).rate, 2000 * kWg / 20, 1e-12);
  // Nothing delivered for the last 40 s: the window's rate falls with it.
  in.progress = History(200, 100, 100, 0);
  for (auto& p : in.progress)
    if (p.seconds_ago < 40) p = {p.seconds_ago, in.progress[160].cpu_seconds, in.progress[160].tasks};
  EXPECT_NEAR(EstimateJobEta(in, Options()).rate, 20 * 100 * kWg / 60, 1e-12);
}

TEST(JobEta, WithoutReportsOrCpuTheEtaIsUnknownAndPublishingCountsDown) {
  // All replayed from the store: no work delivered, no rate.
  JobEtaInput in = Upto(3, false);
  in.progress = {{5, 0, 0}};
  EXPECT_FALSE(EstimateJobEta(in, Options()).known);
  in.progress.clear();
  EXPECT_FALSE(EstimateJobEta(in, Options()).known);
  // The bootstrap's first tasks still running: no task's CPU known.
  JobEtaInput start = Upto(0, true);
  EXPECT_FALSE(EstimateJobEta(start, Options()).known);

  JobEtaInput done = Upto(8, false);
  done.batches.pop_back();
  JobEtaOptions options = Options();
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
