// fabatlas/coordinator/coordinator.h — the cluster's coordinator: gRPC
// services for jobs, workers and blobs over a durable SQLite store
// (protocol in docs/protocol.md, operation in docs/operations.md).
//
// Sampling driver. Every running job has one driver thread that calls
// sampling::SampleDesignSpace with a remote executor: each batch of sampling
// tasks becomes durable task rows keyed by content (protocol/tasks.h); keys
// already finished in the store complete at once; the rest are leased to
// workers and the driver waits for their results. The sampler is a pure
// function of the results, so the form does not depend on the number of
// workers, their order or faults.
//
// Restart by replay. After a crash (kill -9) a new coordinator on the same
// state directory starts a driver for every job still running; the sampler
// runs again from the start and every stored result returns immediately, so
// no completed work is lost and the form is identical. Active leases get one
// lease period of grace so that workers that kept running can report.
//
// Scheduler. Leases last lease_ms and are extended by heartbeats; a sweeper
// expires stale leases every 100 ms and requeues their tasks after an
// exponential backoff (retry_backoff_ms, doubling, capped at 30 s); the
// quarantine_after-th expiry of one task quarantines it (an invalid sample
// with failure type "quarantined"). Results carry the lease attempt and are
// fenced when stale. Lease affinity (worker.proto, docs/protocol.md): a ΔG
// task prefers the workers that evaluated its samples, and with two or more
// connected workers each sample batch is cut into contiguous runs of point
// keys, one per worker; a worker takes its own preferred tasks first, then
// unclaimed ones, then steals, so no slot idles while work is queued.
//
// Threading: all public methods are thread-safe. Tasks without a job file
// (the cluster benchmarks' no-op tasks): run_tasks.h.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace fabatlas::coordinator {

// Exit status of fabatlas-coordinator when its state directory cannot be
// read or written at start (a ResourceError: an I/O error, a full disk), a
// reason that may pass: sysexits.h's EX_TEMPFAIL, which the systemd unit
// restarts, where it never restarts fabatlas::kExitBadInput (2: bad options,
// a state directory in use, a state.db that is not a job store).
inline constexpr int kExitStateUnavailable = 75;

struct CoordinatorOptions {
  // gRPC listen address; port 0 picks a free port (see Coordinator::port()).
  std::string listen = "127.0.0.1:7450";
  // Where the store (state.db), blobs/ and per-job files live. Required.
  std::filesystem::path state_dir;
  // Bearer token every call must carry; empty = none.
  std::string token;
  // TLS: server certificate chain and key (PEM files). Without them the
  // server speaks plaintext, which is refused unless `listen` is loopback or
  // allow_insecure_network is set (isolated test networks only).
  std::string tls_cert, tls_key;
  // When set, clients must present a certificate signed by this CA (PEM).
  std::string tls_client_ca;
  bool allow_insecure_network = false;
  // Plaintext HTTP on "HOST:PORT" serving /metrics (Prometheus text) and
  // /healthz (200 serving, 503 draining, for probes); empty = off.
  std::string metrics_listen;
  std::int64_t lease_ms = 30000;
  std::int64_t heartbeat_ms = 5000;
  std::int64_t retry_backoff_ms = 500;
  int quarantine_after = 3;
  // Most leases handed to one worker per Sync.
  int max_leases_per_sync = 256;
  // Lease affinity (see above). Off: every task is leased oldest first to
  // whoever asks (results are the same either way; only work moves).
  bool lease_affinity = true;
  // Longest long poll of an idle worker.
  std::int64_t max_poll_ms = 5000;
  // fsync the store's WAL on every commit (storage::JobStoreOptions): every
  // acknowledged result then survives a power loss too. Off by default: a
  // kill -9 of the coordinator loses nothing either way, and a power loss
  // can only make the last acknowledged tasks run again (same results).
  bool fsync_commits = false;
};

class Coordinator {
 public:
  explicit Coordinator(CoordinatorOptions options);
  ~Coordinator();  // Shutdown()
  Coordinator(const Coordinator&) = delete;
  Coordinator& operator=(const Coordinator&) = delete;

  // Opens the store, binds the server and resumes every running job. Throws
  // InputError for bad options (plaintext on a non-loopback address,
  // unreadable certificates, an address that cannot be bound) and
  // ResourceError for an unusable state directory.
  void Start();
  // The bound gRPC port.
  int port() const;
  // Graceful drain: hand out no more leases, report NOT_SERVING on the health
  // service, wait up to timeout_ms for the active leases to finish.
  void Drain(std::int64_t timeout_ms);
  // Stops the server and the driver threads (jobs stay running in the store
  // and resume on the next Start).
  void Shutdown();
  // Blocks until Shutdown() is called from another thread.
  void Wait();

  struct Impl;

 private:
  friend std::vector<std::string> RunTasks(Coordinator& coordinator, const std::string& job_id,
                                           const std::vector<std::string>& payloads,
                                           const std::vector<std::string>& keys);
  std::unique_ptr<Impl> impl_;
};

}  // namespace fabatlas::coordinator
