// The geometry cache plan as a worker task (tasks.proto TASK_KIND_CACHE_PLAN,
// issue 5): real coordinator and worker processes on loopback. The plan task
// is leased to a worker, which is SIGKILLed with the plan computed but not
// reported; the lease expires, a second worker completes the task, and the
// published artifact is byte-identical to the in-process `fabatlas sample`
// one (which runs the same protocol::RunCachePlan here).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "cluster_job.h"
#include "cluster_process.h"
#include "in_process_job.h"
#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/design/design.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/v1/tasks.pb.h"

using namespace fabatlas;
using namespace fabatlas::cluster_test;

namespace {

fs::path JobPath() { return SourceDir() / "tests/cluster/data/tube_cache.yaml"; }

// The artifact `fabatlas sample` writes for the job: the pipeline in this
// process (sampling on a thread pool, subtrees re-evaluated, the plan run
// here).
std::string InProcessArtifact(const fs::path& dir) {
  const pipeline::RunSummary run = RunInProcess(JobPath(), dir);
  EXPECT_TRUE(run.cache);
  return ReadText(dir / run.artifact_file);
}

struct LeaseRow {
  std::string worker, state;
};

// Leases of one task, in attempt order (storage/src/schema.cc).
std::vector<LeaseRow> LeasesOf(const fs::path& db_path, const std::string& task_key) {
  std::vector<LeaseRow> rows;
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open_v2(db_path.string().c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* st = nullptr;
  EXPECT_EQ(sqlite3_prepare_v2(db, "SELECT worker_id, state FROM leases WHERE task_key = ? ORDER BY attempt", -1, &st,
                               nullptr),
            SQLITE_OK);
  sqlite3_bind_text(st, 1, task_key.c_str(), -1, SQLITE_TRANSIENT);
  while (sqlite3_step(st) == SQLITE_ROW)
    rows.push_back({reinterpret_cast<const char*>(sqlite3_column_text(st, 0)),
                    reinterpret_cast<const char*>(sqlite3_column_text(st, 1))});
  sqlite3_finalize(st);
  sqlite3_close(db);
  return rows;
}

}  // namespace

TEST(ClusterCachePlan, PlanTaskSurvivesAWorkerKilledMidPlanAndPublishesTheSameBytes) {
  const fs::path dir = FreshDir("cache_plan");
  const std::string reference = InProcessArtifact(dir / "reference");
  ASSERT_FALSE(reference.empty());

  // Fast failure detection: a lost lease expires after 1.5 s.
  CoordinatorProcess c =
      StartCoordinator(dir / "state", 0, {"--lease-ms", "1500", "--heartbeat-ms", "300", "--retry-backoff-ms", "50"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  // The only worker while sampling runs; it kills itself (SIGKILL) once it
  // has computed a cache plan, before reporting it.
  ::setenv("FABATLAS_WORKER_CRASH_MID_CACHE_PLAN", "1", 1);
  const pid_t crasher = StartWorker(c.port, dir / "crasher", {"--id", "crasher"});
  ::unsetenv("FABATLAS_WORKER_CRASH_MID_CACHE_PLAN");
  const std::string id = Client(c.port).Submit(JobPath());
  EXPECT_EQ(WaitExit(crasher, std::chrono::seconds(240)), 128 + SIGKILL) << ReadText(dir / "crasher/worker.log");
  EXPECT_EQ(Client(c.port).Status(id).state(), v1::JOB_STATE_RUNNING) << "the job waits for its plan";

  const pid_t planner = StartWorker(c.port, dir / "planner", {"--id", "planner"});
  v1::JobStatus s;
  for (int i = 0; i < 1200; ++i) {
    s = Client(c.port).Status(id);
    if (s.state() >= v1::JOB_STATE_SUCCEEDED) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  auto outputs = Client(c.port).Fetch(id);
  EXPECT_TRUE(outputs["tube_wall_2d.fabatlas"] == reference) << "the artifact differs from the in-process one";
  ::kill(planner, SIGTERM);
  EXPECT_EQ(WaitExit(planner, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);

  // The task table: one plan task, leased to the crasher (expired), then
  // completed by the planner; its report names the artifact's cache.
  storage::JobStore store(dir / "state/state.db");
  EXPECT_EQ(store.CheckConsistency(), std::vector<std::string>{});
  std::vector<storage::TaskRecord> plans;
  for (const auto& t : store.Tasks(id))
    if (t.kind == v1::TASK_KIND_CACHE_PLAN) plans.push_back(t);
  ASSERT_EQ(plans.size(), 1u);
  EXPECT_EQ(plans[0].state, storage::TaskState::kDone);
  EXPECT_EQ(plans[0].completions, 1);
  EXPECT_GE(plans[0].expiries, 1);
  const auto leases = LeasesOf(dir / "state/state.db", plans[0].key);
  ASSERT_GE(leases.size(), 2u);
  EXPECT_EQ(leases.front().worker, "crasher");
  EXPECT_EQ(leases.front().state, "expired");
  EXPECT_EQ(leases.back().worker, "planner");
  EXPECT_EQ(leases.back().state, "completed");
  v1::TaskResult result;
  ASSERT_TRUE(result.ParseFromString(plans[0].result));
  EXPECT_EQ(result.cache_plan().report_digest().size(), 64u);
  const artifact::Artifact artifact = artifact::ReadArtifact(dir / "reference" / "tube_wall_2d.fabatlas");
  EXPECT_EQ(result.cache_plan().opt_entries(), artifact.manifest.cache.opt_entries);
  EXPECT_EQ(result.cache_plan().rfree_entries(), artifact.manifest.cache.rfree_entries);
  EXPECT_GT(artifact.manifest.cache.opt_entries, 0);

  // Events: the coordinator dispatched the plan and used its result.
  bool dispatched = false, used = false;
  for (const auto& e : store.Events(id)) {
    dispatched = dispatched || e.kind == "cache_plan";
    used = used || (e.kind == "cache" && e.message.find("exact") != std::string::npos);
  }
  EXPECT_TRUE(dispatched);
  EXPECT_TRUE(used);
}
