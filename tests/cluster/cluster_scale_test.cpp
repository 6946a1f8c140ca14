// Faults at scale (label cluster, slow): a >= 10^4-sample job on two
// workers, with >= 10 worker SIGKILLs mid-task and 2 coordinator kill -9s,
// publishes the same artifact, byte for byte, as the job run in this process;
// afterwards every blob the store references verifies, and no task ever asked
// for a blob the collector had removed (no blob_missing event;
// docs/protocol.md "Blob lifecycle").
#include <gtest/gtest.h>

#include <random>

#include "cluster_job.h"
#include "cluster_process.h"
#include "fabatlas/coordinator/publish.h"
#include "fabatlas/design/design.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/storage/artifact.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"

using namespace fabatlas;
using namespace fabatlas::cluster_test;

namespace {

fs::path JobPath() { return SourceDir() / "tests/cluster/data/tube_scale.yaml"; }

// The artifact of the job computed in this process (thread pool): what the
// cluster must publish.
std::string ReferenceArtifact(std::int64_t* samples) {
  sampling::JobFile job = sampling::ReadJobFile(JobPath().string());
  design::Design design = design::LoadDesign(job.design_path);
  sampling::DesignSpace space = precompute::DesignSpaceOf(design, job.subdivisions);
  precompute::DesignSampleEvaluator evaluator(design);
  sampling::ThreadPoolExecutor executor(2);
  sampling::SamplingSummary summary = sampling::SampleDesignSpace(space, evaluator, executor, job.sampling);
  *samples = summary.statistics.samples;
  storage::Artifact artifact =
      coordinator::ArtifactOf(protocol::MakeJobBundle(JobPath()), design.name, job, summary.form);
  fs::path dir = FreshDir("scale-reference");
  storage::WriteArtifact(artifact, dir / "tube_scale.fabatlas");
  return ReadText(dir / "tube_scale.fabatlas");
}

}  // namespace

TEST(ClusterScale, TenThousandSamplesUnderWorkerAndCoordinatorKillsPublishTheSameArtifact) {
  std::int64_t samples = 0;
  const std::string reference = ReferenceArtifact(&samples);
  ASSERT_GE(samples, 10000);

  fs::path dir = FreshDir("scale_faults");
  const std::vector<std::string> fast = {"--lease-ms", "1500", "--heartbeat-ms", "300", "--retry-backoff-ms", "50",
                                         "--quarantine-after", "1000"};
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
  v1::JobStatus s = WaitForJob([&] { return port; }, id, std::chrono::seconds(1500), [&](const v1::JobStatus& st) {
    if (st.tasks_done() <= done_at_last_kill) return;  // one fault per stretch of new progress
    // Faults spread over the job: the coordinator at about 1/3 and 2/3 of
    // the samples, a worker holding leases every ~4 % in between.
    const std::int64_t progress = st.samples_done() * 100 / samples;
    if (coordinator_kills < 2 && progress >= 33 * (coordinator_kills + 1)) {
      KillAndReap(c.pid);
      ++coordinator_kills;
      c = StartCoordinator(dir / "state", port, fast);
      ASSERT_EQ(c.port, port) << ReadText(dir / "state/coordinator.log");
    } else if (worker_kills < 12 && st.tasks_leased() > 0 && progress >= 4 * (worker_kills + 1)) {
      const std::size_t victim = rng() % workers.size();
      KillAndReap(workers[victim]);
      workers[victim] = spawn();
      ++worker_kills;
    } else {
      return;
    }
    done_at_last_kill = st.tasks_done();
  });
  ASSERT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  EXPECT_GE(worker_kills, 10);
  EXPECT_EQ(coordinator_kills, 2);
  EXPECT_GE(s.samples_done(), 10000);
  EXPECT_TRUE(Client(port).Fetch(id)["tube_scale.fabatlas"] == reference) << "the artifact differs";
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
  int missing = 0;
  for (const auto& e : store.Events(""))
    if (e.kind == "blob_missing") ++missing, ADD_FAILURE() << e.message;
  for (const auto& e : store.Events(id))
    if (e.kind == "blob_missing") ++missing, ADD_FAILURE() << e.message;
  EXPECT_EQ(missing, 0);
  // The job's geometry (thousands of subtree blobs, min_subtree_seconds: 0)
  // is referenced no more once published: the blob store holds about what
  // the store references, not the job's working set.
  std::int64_t subtree_blobs = 0;
  for (const auto& row : store.Subtrees(id)) subtree_blobs += !row.blob_digest.empty();
  EXPECT_GT(subtree_blobs, 1000);
}
