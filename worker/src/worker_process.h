// The worker process's state (see fabatlas/worker/worker.h), internal to
// fabatlas_worker. Its member functions live by responsibility:
//   lease_loop.cc      Sync long polls, slot threads, heartbeats, solid
//                       sharing's holder side, stopping (RunWorker);
//   task_execution.cc  one lease's task: the job's context (job_cache.h),
//                       sample / ΔG / swept-volume / cache-plan tasks, blobs;
//   worker_metrics.cc  /metrics and /healthz.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <httplib.h>

#include "fabatlas/directory_lock.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/log/metrics_text.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/sampling/sample_evaluator.h"
#include "fabatlas/v1/blob.grpc.pb.h"
#include "fabatlas/v1/worker.grpc.pb.h"
#include "fabatlas/worker/worker.h"
#include "job_cache.h"

namespace fabatlas::worker {

class Worker {
 public:
  Worker(WorkerOptions options, const std::atomic<bool>& stop);

  WorkerSummary Run();

 private:
  void Finish();

  // /metrics (Prometheus text) and /healthz (200 while working, 503 once
  // stopping) on WorkerOptions.metrics_listen, plaintext.
  void ServeMetrics();

  std::string MetricsPage();

  // Waits for `stop` (or the end), then cancels the calls under way: a long
  // poll or heartbeat to a coordinator that has gone (no answer, no reset)
  // would otherwise hold the worker for its whole deadline. Leases a
  // cancelled long poll was granted are returned by the next Sync (the
  // coordinator returns leases a worker does not list as in flight), and
  // the results it carried go out again on the next Sync (SyncLoop; a
  // stopping worker's calls get kStoppingCallMs): a drained worker reports
  // what it finished before it exits.
  void WatchStop();

  // A call to the coordinator, cancelled when the worker stops (WatchStop);
  // a call started while stopping gets a short deadline instead.
  class Call {
   public:
    Call(Worker& w, std::chrono::milliseconds timeout) : w_(w) {
      std::lock_guard lock(w_.mu_);
      if (w_.stop_) timeout = std::min(timeout, std::chrono::milliseconds(kStoppingCallMs));
      protocol::Prepare(ctx, w_.o_.security, timeout);
      w_.calls_.insert(&ctx);
    }
    ~Call() {
      std::lock_guard lock(w_.mu_);
      w_.calls_.erase(&ctx);
    }
    grpc::ClientContext ctx;

   private:
    Worker& w_;
  };
  static constexpr std::int64_t kStoppingCallMs = 3000;

  // The next Sync, built under mu_: finished results, in-flight leases and
  // free slots; a stopping worker returns the leases it has not started and,
  // once nothing runs, says it is leaving. A worker with nothing running
  // reports its results in the long poll itself (worker.proto Sync).
  v1::SyncRequest NextSyncRequest(bool* leaving);

  // Takes a Sync answer in, under mu_: new leases queued, revoked ones dropped.
  void TakeSyncResponse(v1::SyncResponse& resp);

  // Sends a Sync built by NextSyncRequest (mu_ not held). When it fails,
  // its results go back to done_ for the next Sync.
  grpc::Status CallSync(v1::SyncRequest& req, v1::SyncResponse* resp);

  // Ends a Sync: wakes the sync loop if it waits for one a slot thread made.
  void EndSync(std::unique_lock<std::mutex>& lock);

  // The sync loop's backoff between failed Syncs.
  struct SyncRetry {
    std::chrono::steady_clock::time_point started;                       // connect_timeout_ms counts from here
    std::optional<std::chrono::steady_clock::time_point> failing_since;  // the first failed Sync since the last answer
    std::int64_t backoff_ms = 200;
  };

  // Waits, under mu_, until the next Sync is due (when `patient`: for a
  // result or a while; always: for a slot thread's own Sync to end), then
  // marks a Sync under way and builds it (NextSyncRequest).
  v1::SyncRequest AwaitSyncTurn(bool patient, bool* leaving);

  // After a failed Sync (mu_ not held): throws when the coordinator refused
  // this worker or was not reached within connect_timeout_ms; false when a
  // stopping worker gives up on reporting; else sleeps the backoff and
  // doubles it (at most 5 s).
  bool BackOffAfterFailedSync(const grpc::Status& status, SyncRetry& retry);

  // A 1-slot worker runs the next lease on the sync loop's own thread, and
  // the short ones queued behind it; false when none was queued.
  bool RunLeasesHere();

  // Syncs with the coordinator until the worker leaves: reports results,
  // takes leases, reconnects with backoff.
  void SyncLoop();

  // Called by a slot thread after its task: when that was the worker's last
  // running task and no Sync is under way, this thread reports it itself in
  // the long poll and keeps the first lease that comes back (its loop takes
  // it from the queue), two thread hand-offs fewer than through the sync
  // loop. False when the sync loop is to report the result.
  bool ReportLastTask();

  template <typename Ids>
  void Revoke(const Ids& ids) {
    for (const auto& id : ids) {
      in_flight_.erase(id);
      for (auto it = queue_.begin(); it != queue_.end(); ++it)
        if (it->lease_id() == id) {
          queue_.erase(it);
          break;
        }
    }
  }

  void HeartbeatLoop();

  // Solid sharing, the holder's side (worker.proto ShareSolids): a long poll
  // for the root solids other workers ask for; each is sent from this
  // worker's memory (inline, or uploaded when larger than a chunk), or
  // reported as not held, on the next call. On a
  // thread of its own, so a request is served while every slot is busy.
  void ShareLoop();

  void SlotLoop();

  // The front of the queue, counted as running (mu_ held, queue not empty).
  v1::Lease PopLease();

  // The next queued lease, counted as running; none while stopping.
  std::optional<v1::Lease> TakeLease();

  // Runs a lease taken from the queue and files its result for the next Sync.
  void RunLease(const v1::Lease& lease);

  std::shared_ptr<JobContext> ContextFor(const v1::Lease& lease);

  v1::CompletedTask Execute(const v1::Lease& lease);

  // Uploads a blob (resuming a partial upload); its digest, or "" when the
  // upload failed (the result then names no blob; tasks.proto "Geometry
  // blobs").
  std::string Upload(const std::string& bytes);

  // TASK_KIND_CACHE_PLAN (tasks.proto): the input blob, the plan
  // (protocol::RunCachePlan), the report uploaded before it is named.
  v1::TaskResult PlanCache(const v1::CachePlanTask& task);

  // EvaluateSample (Fab Forms Alg. 2, docs/references.md) and the sample's
  // subtree records (tasks.proto SampleResult). The root solid of a valid
  // sample stays in the evaluator's memory for ΔG, shared only on request
  // (ShareLoop).
  v1::TaskResult EvaluateSample(JobContext& ctx, const sampling::SamplePoint& point);

  // The root solid of a sample for ΔG: from this worker's memory, else the
  // blob named in the task (older coordinators), else shared by the worker
  // holding it (FetchSolid), else evaluated again (deterministic, so all
  // are the same level set).
  geometry::Solid SolidOf(JobContext& ctx, const v1::Lease& lease, const sampling::SamplePoint& point,
                          std::string digest, const std::string& holder);

  WorkerOptions o_;
  // The cache directory is this worker's alone while it runs (directory_lock.h).
  std::unique_ptr<DirectoryLock> cache_lock_;
  const std::atomic<bool>& stop_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::WorkerService::Stub> stub_;
  std::unique_ptr<v1::BlobService::Stub> blob_stub_;
  std::string crash_prefix_;
  bool crash_mid_cache_plan_ = false;

  std::mutex mu_;
  // One condition per waiter, so a hand-off wakes only the thread it is for
  // (each wake-up costs a context switch in the task's round trip):
  std::condition_variable queue_cv_;  // slot threads: leases queued, or exiting
  std::condition_variable done_cv_;   // the sync loop: a result to report
  std::condition_variable exit_cv_;   // the heartbeat thread: exiting
  std::deque<v1::Lease> queue_;
  std::set<std::string> in_flight_;
  std::vector<v1::CompletedTask> done_;
  int running_ = 0;
  bool exiting_ = false;
  bool connected_ = false;        // the coordinator has answered a Sync
  bool syncing_ = false;          // a Sync is under way (one at a time)
  bool sync_loop_waits_ = false;  // the sync loop waits for a slot thread's Sync
  // The last task took less than kShortTaskSeconds: a 1-slot worker then
  // takes up to kResultsPerSync - 1 leases in advance and runs them before
  // it reports, until the results it holds took kShortTaskSeconds together,
  // so one Sync (a round trip and a store commit) carries up to
  // kResultsPerSync results of a job of short tasks and none waits behind
  // more than about kShortTaskSeconds of work; a longer task ends this, so
  // no result or lease waits behind it.
  bool short_tasks_ = false;
  double held_seconds_ = 0;  // tasks of the results in done_ took this long together
  static constexpr double kShortTaskSeconds = 0.1;
  static constexpr int kResultsPerSync = 16;
  std::int64_t heartbeat_ms_ = 2000;
  std::vector<std::thread> slots_;
  std::thread heartbeat_, share_;
  std::thread stop_watch_;
  std::set<grpc::ClientContext*> calls_;                                  // calls under way (Call), under mu_
  std::map<std::string, std::int64_t> tasks_by_kind_, failures_by_kind_;  // under mu_
  log::DurationHistogram task_seconds_{"kind"};
  std::unique_ptr<httplib::Server> metrics_;
  std::thread metrics_thread_;
  std::mutex share_mu_;
  grpc::ClientContext* share_call_ = nullptr;  // the ShareSolids long poll under way

  std::mutex jobs_mu_;
  std::map<std::string, std::shared_ptr<JobContext>> jobs_;
  WorkerSummary summary_;
  std::atomic<std::int64_t> blobs_uploaded_{0}, solids_downloaded_{0}, samples_reevaluated_{0}, solids_shared_{0};
};

}  // namespace fabatlas::worker
