// fabatlas/worker/worker.h — a cluster worker: pulls leases from the
// coordinator (WorkerService.Sync long polls), runs them on `slots` threads
// (one slot: on the thread that sends Sync, and while its tasks take under
// 100 ms it holds up to fifteen leases in advance and reports up to sixteen
// results per Sync, about 100 ms of work at most;
// with more, the slot thread that finishes the last running task sends the
// next Sync itself)
// with a DesignSampleEvaluator per job, reports results, and heartbeats its
// leases from a separate thread (docs/protocol.md).
//
// Jobs are fetched once per job bundle digest from BlobService and unpacked
// under cache_dir. Slow subtrees are uploaded as blobs at their key's second
// use on this worker; valid samples' root
// solids stay in memory and are uploaded only when another worker's ΔG task
// asks for one (a third thread long-polls ShareSolids), and ΔG tasks fetch
// the solids they lack from their holder (tasks.proto "Geometry blobs"). Reconnects with exponential backoff (200 ms
// doubling to 5 s) when the coordinator goes away, and keeps reporting its in-flight leases and unsent results, so a
// restarted coordinator accepts them.
#pragma once

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <string>

#include "fabatlas/protocol/channel.h"

namespace fabatlas::worker {

struct WorkerOptions {
  std::string coordinator;  // HOST:PORT
  protocol::ClientSecurity security;
  int slots = 1;  // tasks run at once
  // Threads the evaluations may keep busy in total (TBB/OpenVDB inside a
  // task included); 0 = slots, i.e. each slot evaluates on its own thread
  // only, so a worker with N slots uses at most N cores for evaluation.
  int threads = 0;
  std::filesystem::path cache_dir;  // job bundles; default: a temp dir
  std::string worker_id;            // default: host-pid-start time
  // Give up (InputError) when the coordinator has not answered once within
  // this time; after the first answer the worker retries forever.
  std::int64_t connect_timeout_ms = 30000;
  std::int64_t poll_ms = 5000;  // long-poll wait when idle
  // Plaintext HTTP "HOST:PORT" serving /metrics (Prometheus text: tasks run
  // and failed by kind, their durations, solid and subtree cache bytes,
  // resident memory) and /healthz (200 working, 503 stopping); empty = off.
  std::string metrics_listen;
  // Resident memory budget of the whole worker process, MiB (>= 256): half
  // of it holds geometry: the subtree cache (at most 1/8; subtrees whose
  // root took at least the job's cache.min_subtree_seconds; the same wait
  // for their key's second use to be uploaded, sharing the cache's memory,
  // at most 1/16 beyond it) and root solids
  // for ΔG and for sharing, older ones compressed (zstd, at most 5/16; a
  // solid is compressed only when it leaves the level sets) and the latest
  // as level sets (at least 1/16 of the budget, and whatever the subtree
  // cache and the compressed ones leave; least recently used first out; a
  // solid dropped everywhere is evaluated again); the other half is left to
  // the running evaluations, the allocator's slack and the process.
  // Measured peak resident set with 2 slots: docs/benchmarks.md.
  std::int64_t memory_mb = 1024;
};

struct WorkerSummary {
  std::int64_t tasks_run = 0;
  std::int64_t results_acknowledged = 0;
  std::int64_t blobs_uploaded = 0;       // solids and subtrees (tasks.proto "Geometry blobs")
  std::int64_t solids_downloaded = 0;    // ΔG inputs another worker evaluated
  std::int64_t samples_reevaluated = 0;  // ΔG inputs evaluated again (no holder, or it lost them)
  std::int64_t solids_shared = 0;        // root solids sent because another worker asked
};

// Runs until `stop` becomes true, then finishes the running tasks, reports
// them, returns the leases it had not started and returns. Throws InputError
// when the coordinator cannot be reached at first, refuses the token, or the
// options are invalid.
WorkerSummary RunWorker(const WorkerOptions& options, const std::atomic<bool>& stop);

}  // namespace fabatlas::worker
