// fabatlas/coordinator/job_eta.h — the predicted wall seconds until a job's
// artifact is published (JobStatus.eta_seconds), from its adaptive schedule
// and the rate at which the cluster does work now.
//
// The sampler runs rounds (sampling/adaptive_sampler.h): the bootstrap
// samples S_0; then per depth d the ΔG batch G_d of the frontier and, while
// d < max_depth and the sample budget lasts, the samples S_{d+1} of the
// frontier's splits; then the coordinator publishes (form outputs, artifact,
// blob collection). EstimateJobEta prices the work still to come in CPU
// seconds and divides it by the CPU seconds of work the cluster finished per
// wall second lately:
//  - tasks to come. Samples of the next round: S_{d+1} = g S_d, where g =
//    S_d / S_{d-1} is the growth of the last split round (it is
//    2 p sigma_d / sigma_{d-1}: p the fraction of frontier leaves that
//    split, each split leaving 2 leaves, sigma the new samples per split).
//    The bootstrap grid is no guide to splits, so until two split rounds
//    are seen g = Options::first_growth. Capped by max_samples (the budget
//    ends all refinement, adaptive_sampler.h step c) and by max_depth.
//    ΔG tasks of a round: G_d = h S_d, h = ΔG tasks per new sample of the
//    last round; from two split rounds on, h follows its trend (the ratio of
//    the last two, clamped to [1/1.25, 1.25]: h grows as the new samples
//    concentrate where the valid share is higher). Before the first split
//    round's ΔG batch, h = first_split_dg_per_sample_factor times the
//    bootstrap's.
//  - work per task of each kind, in CPU seconds: c_k + overhead, where c_k
//    is the evaluator CPU seconds per task (TaskResult.cpu_seconds) of the
//    last batch of kind k, blended with the running batch's own so far in
//    proportion to the share of it done (steady from round to round: 5.6 ms
//    per ΔG task of the coarse tube in every round), and overhead the CPU
//    each task costs beyond its evaluator (leases, results, the
//    coordinator's store). A kind not seen yet is priced as the other.
//  - the rate: CPU seconds of work (the same units) the workers reported
//    per wall second over the last rate_window_seconds (a sliding window;
//    since the job's driver started when that is shorter). The load of a
//    shared machine changes how much work a wall second does, for both kinds
//    alike; the window carries the latest rate to everything left, and
//    forgets a change of load after one window.
//  - publishing: publish_seconds_per_sample times the predicted samples;
//    while publishing, that minus the seconds spent so far (at least 0).
// ETA = (work of the running batch left + work of the batches to come) /
// rate + publishing. Pure function, no I/O, thread-compatible.
#pragma once

#include <vector>

namespace fabatlas::coordinator {

// One batch the sampler handed to the cluster.
struct EtaBatch {
  bool samples = true;  // SampleTasks (S_d) or GeometryChangeTasks (G_d)
  double tasks = 0;
  double cpu_seconds = 0;  // evaluator CPU seconds of its tasks once finished (replayed ones too); 0 = running
};

// Work the workers reported, cumulative since the job's driver started:
// evaluator CPU seconds and tasks of the results they delivered (not those
// replayed from the store, which cost nothing now).
struct EtaProgress {
  double seconds_ago = 0;  // how long before now this was the total
  double cpu_seconds = 0;
  double tasks = 0;
};

struct JobEtaInput {
  // Every batch so far in the order the sampler ran them (S_0, G_0, S_1,
  // G_1, ...; a round whose batch had no task has none). Unless publishing,
  // the last one is running.
  std::vector<EtaBatch> batches;
  double running_left = 0;   // tasks of the running batch not finished (queued + leased)
  EtaProgress running_done;  // work the workers reported for the running batch (seconds_ago unused)
  // The totals at points in time, oldest first: the first at the driver's
  // start (0, 0), one per delivery after it. Only the newest point at least
  // rate_window_seconds old and those after it matter.
  std::vector<EtaProgress> progress;
  // Seconds since sampling ended and publishing began; < 0 while sampling.
  double publishing_seconds = -1;
  int max_depth = 6;            // SamplingOptions
  double max_samples = 100000;  // SamplingOptions
  int dimensions = 1;
};

struct JobEtaOptions {
  // Growth S_{d+1} / S_d of the sample batches until two split rounds were
  // seen: every split leaf's two children split again, what the frontier
  // along a valid region's boundary does (measured on the coarse tube, 10k
  // job: S_2 / S_1 = 2.0; docs/benchmarks.md "Scale").
  double first_growth = 2.0;
  // h of the first split round over the bootstrap grid's h (measured: 2.43
  // on the 10k tube job, 2.71 on the 100k; the bootstrap grid's ΔG edges
  // join samples far from the boundary, half of them invalid).
  double first_split_dg_per_sample_factor = 2.5;
  // CPU seconds per task beyond its evaluator: the coordinator's lease,
  // result and store work and the worker's outside the evaluator (measured
  // on the coarse tube 10k job: 8.6 of its 69.4 CPU seconds were not the
  // evaluator's, over 37,354 tasks; docs/benchmarks.md "Scale").
  double overhead_cpu_seconds_per_task = 0.00025;
  // Length of the sliding window the rate is measured over, wall seconds.
  double rate_window_seconds = 60;
  // Wall seconds of publishing per sample (form outputs and maps, artifact,
  // outputs into the blob store) on 2 cores; measured on the coarse tube
  // jobs: 0.07 ms at 1k and 10k samples, 0.03 ms at 100k (driver start to
  // success less the sampling wall; docs/benchmarks.md "Scale"). Jobs with
  // a geometry cache add the cache plan, which this does not estimate.
  double publish_seconds_per_sample = 0.00007;
};

struct JobEta {
  bool known = false;            // false until a task's CPU and a rate are known
  double seconds = 0;            // running batch + batches to come + publishing
  double publish_seconds = 0;    // the publishing part of it
  double predicted_samples = 0;  // samples when sampling ends
  double work_cpu_seconds = 0;   // work left before publishing, CPU seconds
  double rate = 0;               // CPU seconds of work per wall second in the window
};

JobEta EstimateJobEta(const JobEtaInput& input, const JobEtaOptions& options = {});

}  // namespace fabatlas::coordinator
