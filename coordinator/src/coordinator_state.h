// The coordinator's state (Coordinator::Impl), internal to
// fabatlas_coordinator. Its member functions live by responsibility:
//   coordinator.cc      server start-up, drain and shutdown;
//   job_service.cc, worker_service.cc, blob_service.cc  the gRPC services;
//   scheduler.cc        workers seen, the lease sweeper, stalls, blob collection;
//   remote_executor.cc  task batches through the store to the workers
//                        (RunTasks, Deliver) and the pipeline's RemoteExecutor;
//   solid_sharing.cc    FetchSolid / ShareSolids;
//   job_driver.cc       one job's driver (pipeline::RunJob), its status;
//   metrics.cc          /metrics.
#pragma once

#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/service_type.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <unordered_map>
#include <vector>

#include "fabatlas/coordinator/coordinator.h"
#include "fabatlas/coordinator/job_eta.h"
#include "fabatlas/directory_lock.h"
#include "fabatlas/log/metrics_text.h"
#include "fabatlas/protocol/tasks.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/v1/job.pb.h"
#include "fabatlas/v1/tasks.pb.h"
#include "fabatlas/v1/worker.pb.h"

namespace fabatlas::coordinator {

inline std::int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The result a quarantined task finishes with (an invalid sample of failure
// type "quarantined" for sample tasks), as stored bytes.
inline std::string QuarantineBytes(int kind) {
  return protocol::QuarantineResult(static_cast<v1::TaskKind>(kind)).SerializeAsString();
}

// Thrown out of RunTasks to the driver: the coordinator stops, or the job
// was cancelled.
struct Stopping {};
struct JobCancelled {};

// The task kind of a result, named as protocol::TaskKindName names kinds.
inline std::string ResultKind(const v1::TaskResult& r) {
  switch (r.result_case()) {
    case v1::TaskResult::kSample:
      return "sample";
    case v1::TaskResult::kGeometryChange:
      return "geometry_change";
    case v1::TaskResult::kNoop:
      return "noop";
    case v1::TaskResult::kSweptVolume:
      return "swept_volume";
    case v1::TaskResult::kCachePlan:
      return "cache_plan";
    default:
      return "unknown";
  }
}

inline bool Terminal(storage::JobState s) {
  return s == storage::JobState::kSucceeded || s == storage::JobState::kFailed || s == storage::JobState::kCancelled;
}

struct Coordinator::Impl {
  explicit Impl(CoordinatorOptions o) : options(std::move(o)) {}

  CoordinatorOptions options;
  // Held from Start() until destruction, released after the store closes.
  std::unique_ptr<DirectoryLock> state_lock;
  std::unique_ptr<storage::JobStore> store;
  std::unique_ptr<storage::BlobStore> blobs;
  std::unique_ptr<grpc::Server> server;
  std::vector<std::unique_ptr<grpc::Service>> services;
  int port = 0;
  std::atomic<bool> stopping{false}, draining{false}, started{false};

  // Long polls wait for new work here.
  std::mutex work_mu;
  std::condition_variable work_cv;
  std::uint64_t work_epoch = 0;

  // Drivers wait for results here.
  struct Waiter {
    std::string job_id;
    std::map<std::string, std::string> results;
    std::map<std::string, std::string> workers;  // key -> worker that produced it ("" = from the store)
    std::size_t pending = 0;
  };
  // Connected workers for lease affinity: slots (free + in flight) and the
  // last Sync. A worker silent for a lease period, or leaving, loses its
  // task preferences (JobStore::ForgetAffinity).
  struct WorkerSeen {
    int slots = 0;
    std::int64_t last_ms = 0;
  };
  std::mutex workers_mu;
  std::map<std::string, WorkerSeen> workers_seen;
  std::mutex results_mu;
  std::condition_variable results_cv;
  std::unordered_multimap<std::string, Waiter*> waiting;
  std::set<std::string> cancelled_jobs;

  std::mutex drivers_mu;
  std::vector<std::thread> drivers;
  std::set<std::string> running_drivers;

  std::thread sweeper;
  std::unique_ptr<httplib::Server> metrics;
  std::thread metrics_thread;
  std::atomic<std::int64_t> last_retry_ms{0};
  std::atomic<std::int64_t> completed_total{0}, fenced_total{0}, duplicate_total{0};
  std::atomic<std::int64_t> task_failures_total{0}, state_write_failures_total{0};
  log::DurationHistogram task_seconds{"kind"};  // wall seconds of accepted results, by task kind

  // The state directory cannot be written (full disk, read-only or
  // removed): jobs stall until it can, losing nothing (workers keep their
  // results, drivers replay). Operators are told at once: an error log
  // line (then every 10 s while it lasts), the reason in every running
  // job's status, and fabatlas_state_stalled / _write_failures_total.
  std::atomic<bool> stalled{false};
  std::mutex stall_mu;
  std::string stall_reason;
  std::int64_t stall_since_ms = 0, stall_logged_ms = 0, stall_last_ms = 0;
  std::set<std::string> restart_drivers;  // jobs whose driver stopped on a state write; under drivers_mu

  void StateWriteFailed(const std::string& where, const std::string& error);
  // A write succeeded; the stall ends once no write failed for 5 s (on a
  // nearly full disk small writes succeed between failing large ones).
  void StateWriteSucceeded();
  // "" when writes succeed, else why running jobs are stalled.
  std::string StallText();

  // tasks/s per job: (time, tasks done) samples over the last 10 s.
  std::mutex rate_mu;
  std::map<std::string, std::deque<std::pair<std::int64_t, std::int64_t>>> rate_samples;

  std::mutex shutdown_mu;
  std::condition_variable shutdown_cv;
  bool shut_down = false;

  // Solid sharing (worker.proto FetchSolid / ShareSolids), in memory only: a
  // coordinator restart forgets it and workers evaluate a missing solid
  // again. shares: SolidKey -> what a holder shared: its bytes (kept until
  // one FetchSolid takes them) or an uploaded blob's digest (answered with
  // neither: it does not hold the solid); share_wanted: holder -> the
  // requests to pass on; share_polled: holder -> when its ShareSolids loop
  // was last seen (a holder not polling is not asked).
  struct Share {
    std::string digest{};
    std::string blob{};
    bool answered = false;
    std::int64_t asked_ms = 0;
  };
  std::mutex share_mu;
  std::condition_variable share_cv;
  std::map<std::string, Share> shares;
  std::map<std::string, std::vector<v1::SolidRef>> share_wanted;
  std::map<std::string, std::int64_t> share_polled;

  // The adaptive schedule of each running job as its driver last saw it, for
  // the ETA (JobStatus.eta_seconds, job_eta.h): the batches so far and, once
  // sampling is over, when publishing began; the
  // work the workers delivered (Deliver): its total, the total when the
  // running batch began, and the totals over the last rate window (oldest
  // first, the first before the window).
  struct Schedule {
    JobEtaInput input;
    std::chrono::steady_clock::time_point publish_started;
    EtaProgress work, work_at_batch_start;
    std::deque<std::pair<std::chrono::steady_clock::time_point, EtaProgress>> work_history;
  };
  std::mutex schedule_mu;
  std::map<std::string, Schedule> schedules;

  std::atomic<std::int64_t> blobs_collected_total{0}, blob_bytes_collected_total{0};
  std::mutex collect_mu;

  void SignalWork();

  struct Delivery {
    const std::string* key;
    const std::string* result;
    double cpu_seconds = -1;  // a worker's fresh result: its evaluator CPU (for the ETA's rate); -1 = from the store
  };
  // Hands results to the waiting drivers; wakes them only when one has all
  // its results (one wake-up per batch, not per task).
  void Deliver(const std::vector<Delivery>& results, const std::string& worker = "");
  void Deliver(const std::string& key, const std::string& result) { Deliver({{&key, &result}}); }

  // A worker showed it is alive, by a Sync (slots: free and in flight) or a
  // Heartbeat (slots = -1: it carries none, and refreshes only a worker a
  // Sync introduced): the workers table behind the `workers` metric and
  // workers_seen for lease affinity.
  void WorkerAlive(const std::string& id, int slots, std::int64_t now);

  // Workers that synced within the last lease period with at least one
  // slot, by id.
  std::vector<std::pair<std::string, int>> ConnectedWorkers();

  static std::string SolidKey(const v1::SolidRef& ref);

  // Blob garbage collection (docs/protocol.md "Blob lifecycle"): mark every
  // blob the store references (JobStore::ReferencedBlobs), sweep the rest
  // that are older than the oldest live lease (a worker uploads before it
  // reports, so a blob of a result not yet reported is newer than its
  // lease) and than 10 s (a client uploads a bundle just before it submits
  // it; a held blob named again is touched: BlobStore::Touch). Mark and
  // sweep are read-only on the store and idempotent on disk, so a kill -9
  // between any two steps loses nothing and the next pass finishes the work. Order matters: the cutoff is taken before
  // the references, so a lease that completes in between has its blobs marked.
  void CollectBlobs(const std::string& reason);

  // Runs the tasks (serialized payloads) through the workers; results in
  // order. preferred[i]: workers task i prefers (lease affinity; may be
  // empty). workers_out[i]: the worker whose result was accepted, or "" for
  // a result already in the store.
  std::vector<std::string> RunTasks(const std::string& job_id, const std::vector<std::string>& payloads,
                                    const std::vector<std::string>& keys, const std::vector<int>& kinds,
                                    const std::vector<std::vector<std::string>>& preferred = {},
                                    std::vector<std::string>* workers_out = nullptr);

  void Event(const std::string& job_id, const std::string& kind, const std::string& message);

  // The geometry cache plan of a job whose sampling finished, as one
  // TASK_KIND_CACHE_PLAN task (tasks.proto): the input goes into the blob
  // store, a worker leases the task, runs protocol::RunCachePlan and uploads
  // the report. Retried like any task; a replayed job finds the stored
  // result. Throws InputError when the task was quarantined.
  v1::CachePlanReport PlanCacheOnWorkers(const std::string& job_id, const std::string& evaluation_digest,
                                         int subdivisions, const v1::CachePlanInput& input);

  // Forgets the job's shared solids (its sampling is over).
  void ForgetShares(const std::string& bundle_digest);

  // worker.proto FetchSolid: the solid another worker holds (its bytes or
  // its blob's digest) into `resp`, or nothing (evaluate again).
  void FetchSolid(const v1::FetchSolidRequest& req, v1::FetchSolidResponse* resp, grpc::ServerContext* ctx);

  // worker.proto ShareSolids: records the holder's answers, then waits for
  // requests addressed to it.
  void ShareSolids(const v1::ShareSolidsRequest& req, v1::ShareSolidsResponse* resp, grpc::ServerContext* ctx);

  void Drive(const std::string& job_id);

  void ForgetSchedule(const std::string& job_id);

  void StartDriver(const std::string& job_id);

  v1::JobStatus StatusOf(const storage::JobRecord& job);

  std::string Metrics();

  // A store checkpoint, then the restart of the drivers a failed state
  // write stopped (Sweep, every second).
  void CheckpointAndRestartDrivers();

  // Expires the leases past their deadlines (none while state writes fail:
  // expiry_held remembers that, and the leases get a period of grace after)
  // and delivers the tasks that were quarantined.
  std::vector<storage::ExpiredLease> ExpireOverdueLeases(std::int64_t now, bool& expiry_held);

  // Forgets the workers silent for a lease period: their affinity, and the
  // solids asked of them (answered "not held").
  void ForgetSilentWorkers(std::int64_t now);

  // The sweeper thread, every 100 ms until stopping: the steps above, blob
  // collection every 10 s, and a wake-up of the drivers after retries.
  void Sweep();
};

}  // namespace fabatlas::coordinator
