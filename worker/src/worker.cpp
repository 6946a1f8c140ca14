// The worker loop (see worker.h).
#include "fabatlas/worker/worker.h"

#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <deque>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <thread>

#include <httplib.h>
#include <tbb/global_control.h>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/log/log.h"
#include "fabatlas/log/metrics_text.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/protocol/blob_transfer.h"
#include "fabatlas/protocol/cache_plan.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/protocol/tasks.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/sha256.h"
#include "fabatlas/v1/blob.grpc.pb.h"
#include "fabatlas/v1/worker.grpc.pb.h"

namespace fabatlas::worker {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string DefaultWorkerId() {
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                std::chrono::system_clock::now().time_since_epoch())
                .count();
  return std::string(host) + "-" + std::to_string(::getpid()) + "-" + std::to_string(ms);
}

// Root solids of valid samples as blob bytes (protocol/solid_blob.h, zstd:
// several times smaller than the level set), least recently used dropped
// first once `budget` bytes are held. ΔG tasks take their solids from here
// when the evaluator's own (uncompressed, smaller) memory dropped them, and
// solids are shared from here as they are. Thread-safe.
class SolidShelf {
 public:
  void SetBudget(std::size_t bytes) { budget_ = bytes; }
  void Put(const sampling::PointKey& key, std::string blob) {
    std::lock_guard lock(mu_);
    if (auto it = index_.find(key); it != index_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second);
      return;
    }
    bytes_ += blob.size();
    lru_.emplace_front(key, std::move(blob));
    index_[key] = lru_.begin();
    while (bytes_ > budget_ && lru_.size() > 1) {
      bytes_ -= lru_.back().second.size();
      index_.erase(lru_.back().first);
      lru_.pop_back();
    }
  }
  std::size_t bytes() {
    std::lock_guard lock(mu_);
    return bytes_;
  }
  std::optional<std::string> Get(const sampling::PointKey& key) {
    std::lock_guard lock(mu_);
    auto it = index_.find(key);
    if (it == index_.end()) return std::nullopt;
    lru_.splice(lru_.begin(), lru_, it->second);
    return it->second->second;
  }

 private:
  std::mutex mu_;
  std::size_t budget_ = 0, bytes_ = 0;
  std::list<std::pair<sampling::PointKey, std::string>> lru_;  // front = most recent
  std::map<sampling::PointKey, decltype(lru_)::iterator> index_;
};

struct JobContext {
  std::unique_ptr<precompute::DesignSampleEvaluator> evaluator;
  std::string error;  // set when the job could not be loaded
  double min_subtree_seconds = 0.1;  // job file cache.min_subtree_seconds
  std::mutex mu;
  // Subtree key -> seconds its root took when this worker last computed it
  // (cache hits report 0; tasks.proto SubtreeRecord.seconds wants this).
  std::map<std::string, double> last_seconds;
  // Subtree key -> blob digest, for the subtrees this worker uploaded.
  std::map<std::string, std::string> subtree_blobs;
  SolidShelf shelf;
};

class Worker {
 public:
  Worker(WorkerOptions options, const std::atomic<bool>& stop) : o_(std::move(options)), stop_(stop) {
    if (o_.coordinator.empty()) throw InputError("worker: --coordinator HOST:PORT is required");
    if (o_.slots < 1 || o_.slots > 1024) throw InputError("worker: --slots must be in 1..1024");
    if (o_.memory_mb < 256) throw InputError("worker: --memory-mb must be at least 256");
    if (o_.worker_id.empty()) o_.worker_id = DefaultWorkerId();
    if (o_.cache_dir.empty()) o_.cache_dir = fs::temp_directory_path() / ("fabatlas-worker-" + std::to_string(::getpid()));
    channel_ = protocol::MakeChannel(o_.coordinator, o_.security);
    stub_ = v1::WorkerService::NewStub(channel_);
    blob_stub_ = v1::BlobService::NewStub(channel_);
    if (const char* crash = std::getenv("FABATLAS_WORKER_CRASH_KEY_PREFIX")) crash_prefix_ = crash;
    crash_mid_cache_plan_ = std::getenv("FABATLAS_WORKER_CRASH_MID_CACHE_PLAN") != nullptr;
  }

  WorkerSummary Run() {
    // Each slot thread takes part in its evaluation's TBB loops; TBB may add
    // max_allowed_parallelism - 1 helper threads, so this bounds the busy
    // threads at max(slots, threads).
    int threads = o_.threads > 0 ? o_.threads : o_.slots;
    tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism,
                                    static_cast<std::size_t>(std::max(1, threads - o_.slots + 1)));
    // A 1-slot worker runs its task on the sync loop's thread (SyncLoop);
    // more slots get a thread each.
    if (o_.slots > 1)
      for (int i = 0; i < o_.slots; ++i) slots_.emplace_back([this] { SlotLoop(); });
    heartbeat_ = std::thread([this] { HeartbeatLoop(); });
    stop_watch_ = std::thread([this] { WatchStop(); });
    ServeMetrics();
    share_ = std::thread([this] { ShareLoop(); });
    try {
      SyncLoop();
    } catch (...) {
      Finish();
      throw;
    }
    Finish();
    summary_.blobs_uploaded = blobs_uploaded_;
    summary_.solids_downloaded = solids_downloaded_;
    summary_.samples_reevaluated = samples_reevaluated_;
    summary_.solids_shared = solids_shared_;
    return summary_;
  }

 private:
  void Finish() {
    {
      std::lock_guard lock(mu_);
      exiting_ = true;
    }
    queue_cv_.notify_all();
    done_cv_.notify_all();
    exit_cv_.notify_all();
    for (auto& t : slots_) t.join();
    if (heartbeat_.joinable()) heartbeat_.join();
    if (stop_watch_.joinable()) stop_watch_.join();
    {
      std::lock_guard lock(share_mu_);
      if (share_call_) share_call_->TryCancel();
    }
    if (share_.joinable()) share_.join();
    if (metrics_) metrics_->stop();
    if (metrics_thread_.joinable()) metrics_thread_.join();
  }

  // /metrics (Prometheus text) and /healthz (200 while working, 503 once
  // stopping) on WorkerOptions.metrics_listen, plaintext.
  void ServeMetrics() {
    if (o_.metrics_listen.empty()) return;
    auto colon = o_.metrics_listen.rfind(':');
    if (colon == std::string::npos) throw InputError("worker: --metrics wants HOST:PORT, got " + o_.metrics_listen);
    metrics_ = std::make_unique<httplib::Server>();
    metrics_->Get("/healthz", [this](const httplib::Request&, httplib::Response& res) {
      res.status = stop_ ? 503 : 200;
      res.set_content(stop_ ? "stopping\n" : "working\n", "text/plain");
    });
    metrics_->Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(MetricsPage(), "text/plain; version=0.0.4");
    });
    if (!metrics_->bind_to_port(o_.metrics_listen.substr(0, colon), std::atoi(o_.metrics_listen.c_str() + colon + 1)))
      throw InputError("worker: cannot listen on " + o_.metrics_listen);
    metrics_thread_ = std::thread([this] { metrics_->listen_after_bind(); });
  }

  std::string MetricsPage() {
    log::MetricsText m;
    std::map<std::string, std::int64_t> run, failed;
    int running = 0;
    bool connected = false;
    {
      std::lock_guard lock(mu_);
      run = tasks_by_kind_;
      failed = failures_by_kind_;
      running = running_;
      connected = connected_;
    }
    for (const auto& [kind, n] : run)
      m.Counter("fabatlas_worker_tasks_total", "Tasks this worker ran, by kind.", static_cast<double>(n), {{"kind", kind}});
    for (const auto& [kind, n] : failed)
      m.Counter("fabatlas_worker_task_failures_total", "Tasks this worker could not run, by kind.",
                static_cast<double>(n), {{"kind", kind}});
    task_seconds_.Write(m, "fabatlas_worker_task_duration_seconds", "Wall time of the tasks this worker ran, by kind.");
    std::size_t level_sets = 0, compressed = 0, subtrees = 0;
    {
      std::lock_guard lock(jobs_mu_);
      for (const auto& [digest, ctx] : jobs_) {
        if (!ctx) continue;
        compressed += ctx->shelf.bytes();
        if (ctx->evaluator) {
          level_sets += ctx->evaluator->solid_bytes();
          subtrees += ctx->evaluator->subtree_bytes();
        }
      }
    }
    m.Gauge("fabatlas_worker_solid_cache_bytes", "Root solids held for ΔG tasks, as level sets and compressed.",
            static_cast<double>(level_sets), {{"form", "level_set"}});
    m.Gauge("fabatlas_worker_solid_cache_bytes", "", static_cast<double>(compressed), {{"form", "compressed"}});
    m.Gauge("fabatlas_worker_subtree_cache_bytes", "Subtree cache of the design evaluators.", static_cast<double>(subtrees));
    m.Gauge("fabatlas_worker_memory_budget_bytes", "The resident budget (--memory-mb).",
            static_cast<double>(static_cast<std::int64_t>(o_.memory_mb) << 20));
    m.Gauge("process_resident_memory_bytes", "Resident memory of the worker.", static_cast<double>(log::ResidentMemoryBytes()));
    m.Gauge("fabatlas_worker_slots", "Tasks this worker runs at once (--slots).", o_.slots);
    m.Gauge("fabatlas_worker_running_tasks", "Tasks running now.", running);
    m.Gauge("fabatlas_worker_connected", "1 once the coordinator has answered.", connected ? 1 : 0);
    return m.text();
  }

  // Waits for `stop` (or the end), then cancels the calls under way: a long
  // poll or heartbeat to a coordinator that has gone (no answer, no reset)
  // would otherwise hold the worker for its whole deadline. Leases a
  // cancelled long poll was granted are returned by the next Sync (the
  // coordinator returns leases a worker does not list as in flight).
  void WatchStop() {
    std::unique_lock lock(mu_);
    while (!stop_ && !exiting_) exit_cv_.wait_for(lock, std::chrono::milliseconds(50));
    if (!stop_) return;
    log::Info("worker_stopping", {{"worker", o_.worker_id}, {"running", running_}, {"queued", queue_.size()}});
    for (grpc::ClientContext* call : calls_) call->TryCancel();
    lock.unlock();
    done_cv_.notify_all();
    queue_cv_.notify_all();
  }

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
  v1::SyncRequest NextSyncRequest(bool* leaving) {
    v1::SyncRequest req;
    *leaving = false;
    if (stop_) {
      // The coordinator requeues leases missing from in_flight at once.
      for (const auto& l : queue_) in_flight_.erase(l.lease_id());
      queue_.clear();
      *leaving = running_ == 0;
    }
    req.set_worker_id(o_.worker_id);
    int busy = static_cast<int>(queue_.size()) + running_;
    req.set_free_slots(stop_ ? 0 : std::max(0, o_.slots - busy));
    for (const auto& id : in_flight_) req.add_in_flight_lease_ids(id);
    for (auto& c : done_) *req.add_completed() = std::move(c);
    done_.clear();
    req.set_leaving(*leaving);
    bool idle = in_flight_.empty() && !stop_;
    req.set_max_wait_ms(idle ? static_cast<int>(o_.poll_ms) : 0);
    return req;
  }

  // Takes a Sync answer in, under mu_: new leases queued, revoked ones dropped.
  void TakeSyncResponse(v1::SyncResponse& resp) {
    summary_.results_acknowledged += resp.acknowledged_lease_ids_size();
    if (resp.heartbeat_interval_ms() > 0) heartbeat_ms_ = resp.heartbeat_interval_ms();
    Revoke(resp.revoked_lease_ids());
    for (auto& lease : *resp.mutable_leases()) {
      in_flight_.insert(lease.lease_id());
      queue_.push_back(std::move(lease));
    }
  }

  // Sends a Sync built by NextSyncRequest (mu_ not held). When it fails,
  // its results go back to done_ for the next Sync.
  grpc::Status CallSync(v1::SyncRequest& req, v1::SyncResponse* resp) {
    Call call(*this, std::chrono::milliseconds(req.max_wait_ms() + 15000));
    grpc::Status status = stub_->Sync(&call.ctx, req, resp);
    if (!status.ok()) {
      std::lock_guard lock(mu_);
      for (auto& c : *req.mutable_completed()) done_.push_back(std::move(c));
    }
    return status;
  }

  // Ends a Sync: wakes the sync loop if it waits for one a slot thread made.
  void EndSync(std::unique_lock<std::mutex>& lock) {
    syncing_ = false;
    bool wake = sync_loop_waits_;
    lock.unlock();
    if (wake) done_cv_.notify_one();
  }

  void SyncLoop() {
    auto started = Clock::now();
    std::int64_t backoff_ms = 200;
    bool patient = false;  // wait for a result (or a while) before the next Sync
    while (true) {
      v1::SyncRequest req;
      bool leaving = false;
      {
        std::unique_lock lock(mu_);
        while (true) {
          // Nothing new: wait for a result (or briefly for free slots to be
          // worth asking for more work again). Also right after new leases
          // filled every slot: asking again at once could only extend
          // leases, which the heartbeat thread does.
          if (patient && !slots_.empty() && !in_flight_.empty()) {
            bool full = static_cast<int>(queue_.size()) + running_ >= o_.slots;
            // (Nothing left running: a slot thread reported the last task
            // and its long poll brought nothing; poll again now.)
            done_cv_.wait_for(lock, std::chrono::milliseconds(full ? 1000 : 200),
                              [&] { return !done_.empty() || stop_ || syncing_ || in_flight_.empty(); });
          }
          if (stop_ && running_ > 0)
            done_cv_.wait_for(lock, std::chrono::milliseconds(200), [&] { return !done_.empty(); });
          if (!syncing_) break;
          // A slot thread is reporting the worker's last task and waits for
          // work itself (ReportLastTask); after it, wait for results again.
          sync_loop_waits_ = true;
          done_cv_.wait(lock, [&] { return !syncing_; });
          sync_loop_waits_ = false;
          patient = true;
        }
        syncing_ = true;
        req = NextSyncRequest(&leaving);
      }
      v1::SyncResponse resp;
      grpc::Status status = CallSync(req, &resp);
      if (!status.ok()) {
        {
          std::unique_lock lock(mu_);
          EndSync(lock);
        }
        if (status.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
            status.error_code() == grpc::StatusCode::PERMISSION_DENIED)
          throw InputError("coordinator " + o_.coordinator + " refused this worker: " + status.error_message());
        auto waited = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - started).count();
        if (!connected_ && waited > o_.connect_timeout_ms)
          throw InputError("cannot reach coordinator " + o_.coordinator + ": " + status.error_message());
        if (stop_ && waited > o_.connect_timeout_ms) return;  // leaving and nobody listens
        if (stop_ && status.error_code() != grpc::StatusCode::CANCELLED) {
          // Stopping and the coordinator does not answer: what is left (its
          // unreported results, unstarted leases) is recomputed after the
          // leases expire, so waiting for a coordinator that may never come
          // back gains nothing (systemd and Kubernetes would SIGKILL).
          std::lock_guard lock(mu_);
          log::Warn("worker_leaving_unreported", {{"worker", o_.worker_id}, {"coordinator", o_.coordinator},
                                                  {"error", status.error_message()}, {"results", done_.size()},
                                                  {"leases", in_flight_.size()}});
          return;
        }
        if (!stop_)
          log::Warn("worker_reconnecting", {{"worker", o_.worker_id}, {"coordinator", o_.coordinator},
                                            {"error", status.error_message()}, {"backoff_ms", backoff_ms}});
        std::this_thread::sleep_for(std::chrono::milliseconds(stop_ ? 200 : backoff_ms));
        backoff_ms = std::min<std::int64_t>(backoff_ms * 2, 5000);
        patient = false;
        continue;
      }
      const bool reconnected = backoff_ms > 200;  // a Sync failed before this one
      backoff_ms = 200;
      {
        std::unique_lock lock(mu_);
        if (!connected_) started = Clock::now();
        if (!connected_ || reconnected)
          log::Info("worker_connected", {{"worker", o_.worker_id}, {"coordinator", o_.coordinator}, {"slots", o_.slots}});
        connected_ = true;
        TakeSyncResponse(resp);
        patient = resp.leases_size() == 0 || static_cast<int>(queue_.size()) + running_ >= o_.slots;
        EndSync(lock);
      }
      if (leaving) return;
      if (slots_.empty()) {
        // One slot: run the task here. Nothing is due to the coordinator
        // while it runs (the heartbeat thread keeps its lease), and the
        // result goes out on the next Sync from this thread: two thread
        // hand-offs fewer per task than through a slot thread.
        if (std::optional<v1::Lease> lease = TakeLease()) {
          RunLease(*lease);
          patient = false;
          continue;
        }
      } else if (resp.leases_size() > 0) {
        queue_cv_.notify_all();
      }
    }
  }

  // Called by a slot thread after its task: when that was the worker's last
  // running task and no Sync is under way, this thread reports it itself in
  // the long poll and keeps the first lease that comes back (its loop takes
  // it from the queue), two thread hand-offs fewer than through the sync
  // loop. False when the sync loop is to report the result.
  bool ReportLastTask() {
    std::unique_lock lock(mu_);
    if (syncing_ || stop_ || exiting_ || !connected_ || !in_flight_.empty() || !queue_.empty()) return false;
    syncing_ = true;
    bool leaving = false;
    v1::SyncRequest req = NextSyncRequest(&leaving);
    lock.unlock();
    v1::SyncResponse resp;
    grpc::Status status = CallSync(req, &resp);
    lock.lock();
    if (!status.ok()) {
      // The sync loop retries, with its backoff.
      EndSync(lock);
      done_cv_.notify_one();
      return true;
    }
    TakeSyncResponse(resp);
    const bool others = queue_.size() > 1;
    const bool idle = queue_.empty();
    EndSync(lock);
    if (others) queue_cv_.notify_all();
    if (idle) done_cv_.notify_one();  // nothing came: the sync loop long-polls again
    return true;
  }

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

  void HeartbeatLoop() {
    while (true) {
      v1::HeartbeatRequest req;
      {
        std::unique_lock lock(mu_);
        exit_cv_.wait_for(lock, std::chrono::milliseconds(heartbeat_ms_), [&] { return exiting_; });
        if (exiting_) return;
        if (in_flight_.empty()) continue;
        req.set_worker_id(o_.worker_id);
        for (const auto& id : in_flight_) req.add_lease_ids(id);
      }
      Call call(*this, std::chrono::milliseconds(5000));
      v1::HeartbeatResponse resp;
      if (stub_->Heartbeat(&call.ctx, req, &resp).ok()) {
        std::lock_guard lock(mu_);
        // Leases still queued are dropped; a running one finishes and its
        // result is fenced or acknowledged as a duplicate.
        for (const auto& id : resp.revoked_lease_ids())
          for (auto it = queue_.begin(); it != queue_.end(); ++it)
            if (it->lease_id() == id) {
              in_flight_.erase(id);
              queue_.erase(it);
              break;
            }
      }
    }
  }

  // Solid sharing, the holder's side (worker.proto ShareSolids): a long poll
  // for the root solids other workers ask for; each is uploaded from this
  // worker's memory (or reported as not held) on the next call. On a
  // thread of its own, so a request is served while every slot is busy.
  void ShareLoop() {
    std::vector<v1::SharedSolid> answers;
    std::int64_t backoff_ms = 200;
    while (true) {
      {
        std::lock_guard lock(mu_);
        if (exiting_) return;
      }
      v1::ShareSolidsRequest req;
      req.set_worker_id(o_.worker_id);
      req.set_max_wait_ms(static_cast<int>(std::min<std::int64_t>(o_.poll_ms, 10000)));
      for (auto& a : answers) *req.add_shared() = std::move(a);
      answers.clear();
      v1::ShareSolidsResponse resp;
      grpc::ClientContext ctx;
      protocol::Prepare(ctx, o_.security, std::chrono::milliseconds(req.max_wait_ms() + 15000));
      {
        std::lock_guard lock(share_mu_);
        share_call_ = &ctx;
      }
      {
        std::lock_guard lock(mu_);
        if (exiting_) ctx.TryCancel();
      }
      grpc::Status status = stub_->ShareSolids(&ctx, req, &resp);
      {
        std::lock_guard lock(share_mu_);
        share_call_ = nullptr;
      }
      if (!status.ok()) {
        if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED) return;  // an older coordinator
        for (auto& a : *req.mutable_shared()) answers.push_back(std::move(a));
        std::unique_lock lock(mu_);
        exit_cv_.wait_for(lock, std::chrono::milliseconds(backoff_ms), [&] { return exiting_; });
        backoff_ms = std::min<std::int64_t>(backoff_ms * 2, 5000);
        continue;
      }
      backoff_ms = 200;
      for (const auto& ref : resp.wanted()) {
        v1::SharedSolid answer;
        *answer.mutable_solid() = ref;
        std::shared_ptr<JobContext> job;
        {
          std::lock_guard lock(jobs_mu_);
          if (auto it = jobs_.find(ref.job_bundle_digest()); it != jobs_.end()) job = it->second;
        }
        if (job)
          if (auto blob = job->shelf.Get(sampling::PointKey(ref.point_key().begin(), ref.point_key().end()))) {
            answer.set_digest(Upload(*blob));
            if (!answer.digest().empty()) ++solids_shared_;
          }
        answers.push_back(std::move(answer));
      }
    }
  }

  void SlotLoop() {
    while (true) {
      v1::Lease lease;
      {
        std::unique_lock lock(mu_);
        queue_cv_.wait(lock, [&] { return exiting_ || (!queue_.empty() && !stop_); });
        if (exiting_) return;
        lease = PopLease();
      }
      RunLease(lease);
      if (!ReportLastTask()) done_cv_.notify_one();  // only the sync loop waits for results
    }
  }

  // The front of the queue, counted as running (mu_ held, queue not empty).
  v1::Lease PopLease() {
    v1::Lease lease = std::move(queue_.front());
    queue_.pop_front();
    ++running_;
    return lease;
  }

  // The next queued lease, counted as running; none while stopping.
  std::optional<v1::Lease> TakeLease() {
    std::lock_guard lock(mu_);
    if (queue_.empty() || stop_) return std::nullopt;
    return PopLease();
  }

  // Runs a lease taken from the queue and files its result for the next Sync.
  void RunLease(const v1::Lease& lease) {
    auto started = Clock::now();
    v1::CompletedTask done = Execute(lease);
    const std::string kind = protocol::TaskKindName(lease.payload().kind());
    task_seconds_.Observe(kind, std::chrono::duration<double>(Clock::now() - started).count());
    if (!done.error().empty())
      log::Warn("task_failed", {{"task", lease.task_key()}, {"job", lease.job_id()}, {"attempt", lease.attempt()},
                                {"reason", done.error()}});
    std::lock_guard lock(mu_);
    ++tasks_by_kind_[kind];
    if (!done.error().empty()) ++failures_by_kind_[kind];
    --running_;
    ++summary_.tasks_run;
    in_flight_.erase(lease.lease_id());
    done_.push_back(std::move(done));
  }

  std::shared_ptr<JobContext> ContextFor(const v1::Lease& lease) {
    std::lock_guard lock(jobs_mu_);
    auto& ctx = jobs_[lease.job_bundle_digest()];
    if (ctx && ctx->evaluator) return ctx;
    ctx = std::make_shared<JobContext>();
    try {
      grpc::ClientContext call;
      protocol::Prepare(call, o_.security, std::chrono::seconds(120));
      v1::ReadRequest req;
      req.set_digest(lease.job_bundle_digest());
      auto reader = blob_stub_->Read(&call, req);
      std::string bytes;
      v1::ReadChunk chunk;
      while (reader->Read(&chunk)) bytes += chunk.data();
      grpc::Status s = reader->Finish();
      if (!s.ok()) throw InputError("cannot fetch job bundle: " + s.error_message());
      if (Sha256Hex(bytes) != lease.job_bundle_digest()) throw InputError("job bundle digest mismatch");
      v1::JobBundle bundle;
      if (!bundle.ParseFromString(bytes)) throw InputError("job bundle does not parse");
      auto files = protocol::Materialize(bundle, o_.cache_dir / lease.job_bundle_digest().substr(0, 16));
      ctx->min_subtree_seconds =
          sampling::ParseJobFile(bundle.job_file(), files.job_file.string()).cache_min_subtree_seconds;
      precompute::DesignEvaluatorOptions options;
      // The resident budget (WorkerOptions.memory_mb): 1/16 for the latest
      // root solids as level sets, 5/16 for root solids compressed (the
      // shelf), 1/8 for the subtree cache, the other half for the running
      // evaluations, the allocator's slack and the process itself.
      const std::size_t budget = static_cast<std::size_t>(o_.memory_mb) << 20;
      options.solid_memory_bytes = budget / 16;
      options.subtree_memory_bytes = budget / 8;
      ctx->shelf.SetBudget(budget / 16 * 5);
      JobContext* job = ctx.get();
      options.on_subtree_computed = [this, job](const std::string& key, const geometry::Solid& solid,
                                                double seconds) {
        {
          std::lock_guard lock(job->mu);
          job->last_seconds[key] = seconds;
          if (seconds < job->min_subtree_seconds || job->subtree_blobs.count(key)) return;
        }
        std::string digest = Upload(protocol::SolidBlobOf(solid));
        if (digest.empty()) return;
        std::lock_guard lock(job->mu);
        job->subtree_blobs.emplace(key, digest);
      };
      ctx->evaluator = std::make_unique<precompute::DesignSampleEvaluator>(design::LoadDesign(files.design_file),
                                                                           std::move(options));
    } catch (const std::exception& e) {
      ctx->error = e.what();
      auto failed = ctx;
      ctx.reset();  // try again on the next lease
      return failed;
    }
    return ctx;
  }

  v1::CompletedTask Execute(const v1::Lease& lease) {
    v1::CompletedTask done;
    done.set_lease_id(lease.lease_id());
    done.set_task_key(lease.task_key());
    done.set_attempt(lease.attempt());
    if (!crash_prefix_.empty() && lease.task_key().rfind(crash_prefix_, 0) == 0) std::raise(SIGKILL);
    const v1::TaskPayload& p = lease.payload();
    auto wall0 = Clock::now();
    double cpu0 = ThreadCpuSeconds();
    v1::TaskResult result;
    if (p.kind() == v1::TASK_KIND_NOOP) {
      result.set_noop(true);
    } else if (p.kind() == v1::TASK_KIND_CACHE_PLAN) {
      try {
        result = PlanCache(p.cache_plan());  // needs no design: the job is not loaded
      } catch (const std::exception& e) {
        done.set_error(e.what());
        return done;
      }
    } else {
      auto ctx = ContextFor(lease);
      if (!ctx->evaluator) {
        done.set_error(ctx->error.empty() ? "job not loaded" : ctx->error);
        return done;
      }
      try {
        if (p.kind() == v1::TASK_KIND_SAMPLE) {
          result = EvaluateSample(*ctx, protocol::PointOf(p.point_a()));
        } else if (p.kind() == v1::TASK_KIND_GEOMETRY_CHANGE) {
          geometry::Solid a =
              SolidOf(*ctx, lease, protocol::PointOf(p.point_a()), p.solid_digest_a(), p.solid_holder_a());
          geometry::Solid b =
              SolidOf(*ctx, lease, protocol::PointOf(p.point_b()), p.solid_digest_b(), p.solid_holder_b());
          result.set_geometry_change(geometry::DeltaG(a, b));
        } else if (p.kind() == v1::TASK_KIND_SWEPT_VOLUME) {
          const design::Design& d = ctx->evaluator->design();
          const design::SweptVolumeResult s = design::ComputeSweptVolume(
              d, precompute::DesignPointOf(d, protocol::PointOf(p.point_a()).u), p.swept().node_path());
          auto* out = result.mutable_swept_volume();
          out->set_volume(s.volume);
          out->set_triangles(s.triangles);
          out->set_time_steps(s.time_steps);
          out->set_active_voxels(s.active_voxels);
          out->set_surface_sha256(s.surface_sha256);
          // The cutter itself, for the coordinator to publish (tasks.proto).
          out->set_surface_blob(Upload(s.surface_bytes));
        } else {
          done.set_error("unknown task kind " + std::to_string(p.kind()));
          return done;
        }
      } catch (const std::exception& e) {
        done.set_error(e.what());
        return done;
      }
    }
    result.set_cpu_seconds(ThreadCpuSeconds() - cpu0);
    result.set_wall_seconds(std::chrono::duration<double>(Clock::now() - wall0).count());
    *done.mutable_result() = std::move(result);
    return done;
  }

  // Uploads a blob (resuming a partial upload); its digest, or "" when the
  // upload failed (the result then names no blob; tasks.proto "Geometry
  // blobs").
  std::string Upload(const std::string& bytes) {
    std::string digest;
    grpc::Status s = protocol::UploadBlob(*blob_stub_, o_.security, bytes, std::chrono::seconds(30), &digest);
    if (!s.ok()) return "";
    ++blobs_uploaded_;
    return digest;
  }

  // TASK_KIND_CACHE_PLAN (tasks.proto): the input blob, the plan
  // (protocol::RunCachePlan), the report uploaded before it is named.
  v1::TaskResult PlanCache(const v1::CachePlanTask& task) {
    std::string bytes;
    grpc::Status s = protocol::DownloadBlob(*blob_stub_, o_.security, task.input_digest(), std::chrono::seconds(300), &bytes);
    if (!s.ok()) throw InputError("cache plan input " + task.input_digest() + ": " + s.error_message());
    v1::CachePlanInput input;
    if (!input.ParseFromString(bytes)) throw InputError("cache plan input " + task.input_digest() + " does not parse");
    bytes.clear();
    const v1::CachePlanReport report = protocol::RunCachePlan(input);
    // Fault injection for the cluster tests: die with the plan computed but
    // not reported.
    if (crash_mid_cache_plan_) std::raise(SIGKILL);
    const std::string digest = Upload(report.SerializeAsString());
    if (digest.empty()) throw InputError("cache plan report upload failed");
    v1::TaskResult result;
    result.mutable_cache_plan()->set_report_digest(digest);
    result.mutable_cache_plan()->set_opt_entries(report.opt().entries());
    result.mutable_cache_plan()->set_rfree_entries(report.rfree().entries());
    return result;
  }

  // EvaluateSample (seed 001 Alg. 2) and the sample's subtree records
  // (tasks.proto SampleResult). The root solid of a valid sample stays in
  // the evaluator's memory for ΔG, shared only on request (ShareLoop).
  v1::TaskResult EvaluateSample(JobContext& ctx, const sampling::SamplePoint& point) {
    design::SampleResult r = ctx.evaluator->Evaluate(point);
    sampling::SampleOutcome outcome;
    outcome.valid = r.valid;
    outcome.failure_type = r.failure;
    outcome.properties = r.properties;
    v1::TaskResult result = protocol::SampleResultOf(outcome);
    v1::SampleResult* sample = result.mutable_sample();
    if (r.valid) ctx.shelf.Put(point.key, protocol::SolidBlobOf(r.solid));
    std::lock_guard lock(ctx.mu);
    for (const design::SubtreeRecord& rec : r.subtrees) {
      v1::SubtreeRecord* out = sample->add_subtrees();
      out->set_key(rec.key);
      out->set_topology(rec.topology);
      out->set_op(rec.op);
      double seconds = rec.seconds;
      if (rec.from_cache) {
        auto it = ctx.last_seconds.find(rec.key);
        if (it != ctx.last_seconds.end()) seconds = it->second;
      }
      out->set_seconds(seconds);
      out->set_from_cache(rec.from_cache);
      out->set_bytes(static_cast<std::int64_t>(rec.bytes));
      for (const auto& child : rec.children) out->add_children(child);
      if (auto it = ctx.subtree_blobs.find(rec.key); it != ctx.subtree_blobs.end()) out->set_blob_digest(it->second);
    }
    return result;
  }

  // The root solid of a sample for ΔG: from this worker's memory, else the
  // blob named in the task (older coordinators), else shared by the worker
  // holding it (FetchSolid), else evaluated again (deterministic, so all
  // are the same level set).
  geometry::Solid SolidOf(JobContext& ctx, const v1::Lease& lease, const sampling::SamplePoint& point,
                          std::string digest, const std::string& holder) {
    if (auto solid = ctx.evaluator->RememberedSolid(point.key)) return *solid;
    if (auto blob = ctx.shelf.Get(point.key)) {
      geometry::Solid solid = protocol::SolidOfBlob(*blob);
      ctx.evaluator->Remember(point.key, solid);
      return solid;
    }
    if (digest.empty() && !holder.empty() && holder != o_.worker_id) {
      v1::FetchSolidRequest req;
      req.set_worker_id(o_.worker_id);
      req.mutable_solid()->set_job_bundle_digest(lease.job_bundle_digest());
      for (auto k : point.key) req.mutable_solid()->add_point_key(k);
      req.set_holder_worker_id(holder);
      req.set_max_wait_ms(5000);
      v1::FetchSolidResponse resp;
      grpc::ClientContext call;
      protocol::Prepare(call, o_.security, std::chrono::milliseconds(20000));
      if (stub_->FetchSolid(&call, req, &resp).ok()) digest = resp.digest();
    }
    if (!digest.empty()) {
      std::string bytes;
      if (protocol::DownloadBlob(*blob_stub_, o_.security, digest, std::chrono::seconds(60), &bytes).ok()) {
        try {
          geometry::Solid solid = protocol::SolidOfBlob(bytes);
          ctx.evaluator->Remember(point.key, solid);
          ctx.shelf.Put(point.key, std::move(bytes));
          ++solids_downloaded_;
          return solid;
        } catch (const InputError&) {
        }
      }
    }
    ++samples_reevaluated_;
    return ctx.evaluator->SolidOf(point);
  }

  WorkerOptions o_;
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
  bool connected_ = false;         // the coordinator has answered a Sync
  bool syncing_ = false;           // a Sync is under way (one at a time)
  bool sync_loop_waits_ = false;   // the sync loop waits for a slot thread's Sync
  std::int64_t heartbeat_ms_ = 2000;
  std::vector<std::thread> slots_;
  std::thread heartbeat_, share_;
  std::thread stop_watch_;
  std::set<grpc::ClientContext*> calls_;  // calls under way (Call), under mu_
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

}  // namespace

WorkerSummary RunWorker(const WorkerOptions& options, const std::atomic<bool>& stop) {
  Worker worker(options, stop);
  return worker.Run();
}

}  // namespace fabatlas::worker
