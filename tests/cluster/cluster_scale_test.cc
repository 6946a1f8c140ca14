// Faults at scale (label cluster, slow): a >= 10^4-sample job on two
// workers, with >= 10 worker SIGKILLs mid-task and 2 coordinator kill -9s,
// publishes the same artifact, byte for byte, as the job run in this process;
// afterwards every blob the store references verifies, and no task, and no
// cache plan, ever asked for a blob the collector had removed (no
// blob_missing event; docs/protocol.md "Blob lifecycle"). The job has a
// cache plan, so the artifact's cache curves and entries, whose costs are
// floating-point sums, must come out bit for bit as in process
// (docs/cache.md "Determinism").
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <random>

#include "cluster_job.h"
#include "cluster_process.h"
#include "in_process_job.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"

using namespace fabatlas;
using namespace fabatlas::cluster_test;

namespace {

fs::path JobPath() { return SourceDir() / "tests/cluster/data/tube_scale.yaml"; }

// The artifact `fabatlas sample` writes for the job: the pipeline in this
// process (sampling on a thread pool, subtrees re-evaluated, the plan run
// here). What the cluster must publish.
// samples: the form's; tasks: the cluster's sample and ΔG tasks (an edge
// needs a ΔG task only between two valid samples, adaptive_sampler.cc).
std::string ReferenceArtifact(std::int64_t* samples, std::int64_t* tasks) {
  const fs::path dir = FreshDir("scale-reference");
  const pipeline::RunSummary run = RunInProcess(JobPath(), dir);
  EXPECT_TRUE(run.cache);
  const sampling::Form& form = run.sampling.form;
  *samples = run.sampling.statistics.samples;
  *tasks = *samples;
  for (const auto& [edge, dg] : form.geometry_changes)
    *tasks += form.samples[edge.first].outcome.valid && form.samples[edge.second].outcome.valid;
  return ReadText(dir / run.artifact_file);
}

}  // namespace

TEST(ClusterScale, TenThousandSamplesUnderWorkerAndCoordinatorKillsPublishTheSameArtifact) {
  // The programs the test restarts are copies: a build relinking bin/
  // during the run must not swap binaries under a restarted coordinator.
  fs::path dir = FreshDir("scale_faults");
  fs::create_directories(dir / "bin");
  for (const char* program : {"fabatlas-coordinator", "fabatlas-worker"})
    fs::copy_file(BinDir() / program, dir / "bin" / program);
  ::setenv("FABATLAS_BIN_DIR", (dir / "bin").c_str(), 1);

  std::int64_t samples = 0, tasks = 0;
  const std::string reference = ReferenceArtifact(&samples, &tasks);
  ASSERT_GE(samples, 10000);

  const std::vector<std::string> fast = {"--lease-ms",         "1500", "--heartbeat-ms",     "300",
                                         "--retry-backoff-ms", "50",   "--quarantine-after", "1000"};
  CoordinatorProcess c = StartCoordinator(dir / "state", 0, fast);
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  const int port = c.port;
  int spawned = 0;
  auto spawn = [&] { return StartWorker(port, dir / ("w" + std::to_string(spawned++))); };
  std::vector<pid_t> workers = {spawn(), spawn()};
  const std::string id = Client(port).Submit(JobPath());
  std::mt19937 rng(13);
  int worker_kills = 0, coordinator_kills = 0;
  std::int64_t done_at_last_kill = 0;
  const auto started = std::chrono::steady_clock::now();
  v1::JobStatus s =
      WaitForJob([&] { return port; }, id, std::chrono::seconds(3300),
                 [&](const v1::JobStatus& st) {
                   if (st.tasks_done() <= done_at_last_kill) return;  // one fault per stretch of new progress
                   // Faults follow the job's progress in sample and ΔG tasks (known
                   // exactly from the reference run): the coordinator at 30 % and 70 %, a
                   // worker holding leases every 6 % up to 72 %.
                   const std::int64_t progress = st.tasks_done() * 100 / tasks;
                   const int coordinator_at[] = {30, 70};
                   if (coordinator_kills < 2 && progress >= coordinator_at[coordinator_kills]) {
                     KillAndReap(c.pid);
                     ++coordinator_kills;
                     c = StartCoordinator(dir / "state", port, fast);
                     ASSERT_EQ(c.port, port) << ReadText(dir / "state/coordinator.log");
                   } else if (worker_kills < 12 && st.tasks_leased() > 0 && progress >= 6 * (worker_kills + 1)) {
                     const std::size_t victim = rng() % workers.size();
                     KillAndReap(workers[victim]);
                     workers[victim] = spawn();
                     ++worker_kills;
                   } else {
                     return;
                   }
                   done_at_last_kill = st.tasks_done();
                 });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  std::printf(
      "cluster: %lld samples, %lld tasks, %d worker SIGKILLs, %d coordinator kill -9s, %lld lease expiries, "
      "%lld fenced results, %.1f s wall\n",
      static_cast<long long>(s.samples_done()), static_cast<long long>(s.tasks_total()), worker_kills,
      coordinator_kills, static_cast<long long>(s.lease_expiries()), static_cast<long long>(s.fenced_results()),
      seconds);
  ASSERT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  EXPECT_GE(worker_kills, 10);
  EXPECT_EQ(coordinator_kills, 2);
  EXPECT_GE(s.samples_done(), 10000);
  const std::string published = Client(port).Fetch(id)["tube_scale.fabatlas"];
  if (published != reference) {
    std::ofstream(dir / "published.fabatlas", std::ios::binary) << published;
    ADD_FAILURE() << "the artifact differs from the in-process one: " << (dir / "published.fabatlas").string();
  }
  for (pid_t p : workers) ::kill(p, SIGTERM);
  for (pid_t p : workers) EXPECT_EQ(WaitExit(p, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0) << ReadText(dir / "state/coordinator.log");

  storage::JobStore store(dir / "state/state.db");
  EXPECT_EQ(store.CheckConsistency(), std::vector<std::string>{});
  storage::BlobStore blobs(dir / "state/blobs");
  const std::vector<std::string> referenced = store.ReferencedBlobs();
  EXPECT_GE(referenced.size(), 3u);  // bundle, form.json, the artifact at least
  for (const auto& d : referenced) EXPECT_TRUE(blobs.Verify(d)) << d;
  // No blob a later task or the cache plan needed was collected: no read
  // of a missing blob, no subtree naming one, and no task that a worker
  // could not run (a missing input would fail it; a killed worker's task
  // only expires).
  int missing = 0, failed = 0;
  for (const std::string& job : {std::string(), id})
    for (const auto& e : store.Events(job)) {
      if (e.kind == "blob_missing") ++missing, ADD_FAILURE() << e.message;
      if (e.kind == "task_failed" || e.kind == "quarantined") ++failed, ADD_FAILURE() << e.message;
    }
  EXPECT_EQ(missing, 0);
  EXPECT_EQ(failed, 0);
  EXPECT_EQ(s.tasks_quarantined(), 0);
  // The job's geometry (a subtree blob for each key used twice on a worker,
  // min_subtree_seconds: 0) is referenced no more once published: the blob
  // store holds about what the store references, not the job's working set.
  // A key the store counts once has a blob only when a worker met it twice
  // while one of those attempts did not count: a sample run again after its
  // lease expired or its result was fenced. So such keys are at most the
  // re-run attempts times the subtrees of one sample.
  std::int64_t subtree_blobs = 0, once_with_blob = 0;
  for (const auto& row : store.Subtrees(id)) {
    subtree_blobs += !row.blob_digest.empty();
    once_with_blob += row.uses == 1 && !row.blob_digest.empty();
  }
  EXPECT_GT(subtree_blobs, 0);
  std::int64_t per_sample = 0;
  for (const auto& sample : store.SampleSubtreeKeys(id))
    per_sample = std::max<std::int64_t>(per_sample, static_cast<std::int64_t>(sample.subtree_keys.size()));
  EXPECT_LE(once_with_blob, (s.lease_expiries() + s.fenced_results()) * per_sample);
}
