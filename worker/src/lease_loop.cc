// The worker's lease loop (see worker_process.h): Sync long polls, slot
// threads, heartbeats, the holder's side of solid sharing, and stopping.
#include <unistd.h>

#include <cstdlib>

#include <tbb/global_control.h>

#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/protocol/tasks.h"
#include "worker_process.h"

namespace fabatlas::worker {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

std::string DefaultWorkerId() {
  char host[256] = {0};
  gethostname(host, sizeof host - 1);
  auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
                .count();
  return std::string(host) + "-" + std::to_string(::getpid()) + "-" + std::to_string(ms);
}

}  // namespace

Worker::Worker(WorkerOptions options, const std::atomic<bool>& stop) : o_(std::move(options)), stop_(stop) {
  if (o_.coordinator.empty()) throw InputError("worker: --coordinator HOST:PORT is required");
  if (o_.slots < 1 || o_.slots > 1024) throw InputError("worker: --slots must be in 1..1024");
  if (o_.memory_mb < 256) throw InputError("worker: --memory-mb must be at least 256");
  if (o_.worker_id.empty()) o_.worker_id = DefaultWorkerId();
  if (o_.cache_dir.empty())
    o_.cache_dir = fs::temp_directory_path() / ("fabatlas-worker-" + std::to_string(::getpid()));
  cache_lock_ = std::make_unique<DirectoryLock>(o_.cache_dir, "worker cache directory");
  channel_ = protocol::MakeChannel(o_.coordinator, o_.security);
  stub_ = v1::WorkerService::NewStub(channel_);
  blob_stub_ = v1::BlobService::NewStub(channel_);
  if (const char* crash = std::getenv("FABATLAS_WORKER_CRASH_KEY_PREFIX")) crash_prefix_ = crash;
  crash_mid_cache_plan_ = std::getenv("FABATLAS_WORKER_CRASH_MID_CACHE_PLAN") != nullptr;
}

WorkerSummary Worker::Run() {
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

void Worker::Finish() {
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

void Worker::WatchStop() {
  std::unique_lock lock(mu_);
  while (!stop_ && !exiting_) exit_cv_.wait_for(lock, std::chrono::milliseconds(50));
  if (!stop_) return;
  log::Info("worker_stopping", {{"worker", o_.worker_id}, {"running", running_}, {"queued", queue_.size()}});
  for (grpc::ClientContext* call : calls_) call->TryCancel();
  lock.unlock();
  done_cv_.notify_all();
  queue_cv_.notify_all();
}

v1::SyncRequest Worker::NextSyncRequest(bool* leaving) {
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
  // A 1-slot worker running short tasks asks for leases beyond the one it
  // can run, and runs them before it reports (SyncLoop): one Sync per up to
  // kResultsPerSync tasks.
  const int wanted = o_.slots + (slots_.empty() && short_tasks_ ? kResultsPerSync - 1 : 0);
  req.set_free_slots(stop_ ? 0 : std::max(0, wanted - busy));
  // Leases beyond the slots are taken in advance: never another worker's
  // preferred tasks (worker.proto, lease affinity).
  req.set_idle_slots(stop_ ? 0 : std::max(0, o_.slots - busy));
  for (const auto& id : in_flight_) req.add_in_flight_lease_ids(id);
  for (auto& c : done_) *req.add_completed() = std::move(c);
  done_.clear();
  held_seconds_ = 0;
  req.set_leaving(*leaving);
  bool idle = in_flight_.empty() && !stop_;
  req.set_max_wait_ms(idle ? static_cast<int>(o_.poll_ms) : 0);
  return req;
}

void Worker::TakeSyncResponse(v1::SyncResponse& resp) {
  summary_.results_acknowledged += resp.acknowledged_lease_ids_size();
  // Which results the coordinator stored (the power-loss test's witness of
  // what was acknowledged before a cut, docs/testing.md).
  if (resp.acknowledged_lease_ids_size() > 0 && log::Enabled(log::Level::kDebug)) {
    std::string ids;
    for (const auto& id : resp.acknowledged_lease_ids()) ids += (ids.empty() ? "" : ",") + id;
    log::Debug("results_acknowledged", {{"worker", o_.worker_id}, {"leases", ids}});
  }
  if (resp.heartbeat_interval_ms() > 0) heartbeat_ms_ = resp.heartbeat_interval_ms();
  Revoke(resp.revoked_lease_ids());
  for (auto& lease : *resp.mutable_leases()) {
    in_flight_.insert(lease.lease_id());
    queue_.push_back(std::move(lease));
  }
}

grpc::Status Worker::CallSync(v1::SyncRequest& req, v1::SyncResponse* resp) {
  Call call(*this, std::chrono::milliseconds(req.max_wait_ms() + 15000));
  grpc::Status status = stub_->Sync(&call.ctx, req, resp);
  if (!status.ok()) {
    std::lock_guard lock(mu_);
    for (auto& c : *req.mutable_completed()) done_.push_back(std::move(c));
  }
  return status;
}

void Worker::EndSync(std::unique_lock<std::mutex>& lock) {
  syncing_ = false;
  bool wake = sync_loop_waits_;
  lock.unlock();
  if (wake) done_cv_.notify_one();
}

v1::SyncRequest Worker::AwaitSyncTurn(bool patient, bool* leaving) {
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
    if (stop_ && running_ > 0) done_cv_.wait_for(lock, std::chrono::milliseconds(200), [&] { return !done_.empty(); });
    if (!syncing_) break;
    // A slot thread is reporting the worker's last task and waits for
    // work itself (ReportLastTask); after it, wait for results again.
    sync_loop_waits_ = true;
    done_cv_.wait(lock, [&] { return !syncing_; });
    sync_loop_waits_ = false;
    patient = true;
  }
  syncing_ = true;
  return NextSyncRequest(leaving);
}

bool Worker::BackOffAfterFailedSync(const grpc::Status& status, SyncRetry& retry) {
  if (status.error_code() == grpc::StatusCode::UNAUTHENTICATED ||
      status.error_code() == grpc::StatusCode::PERMISSION_DENIED)
    throw InputError("coordinator " + o_.coordinator + " refused this worker: " + status.error_message());
  const auto now = Clock::now();
  if (!retry.failing_since) retry.failing_since = now;
  auto ms = [&](Clock::time_point since) {
    return std::chrono::duration_cast<std::chrono::milliseconds>(now - since).count();
  };
  if (!connected_ && ms(retry.started) > o_.connect_timeout_ms)
    throw InputError("cannot reach coordinator " + o_.coordinator + ": " + status.error_message());
  // Leaving and nobody has listened for a while. (Measured from the
  // first failure, not from the start: a Sync that WatchStop cancelled
  // carried results, and they go out again on the next one.)
  if (stop_ && ms(*retry.failing_since) > o_.connect_timeout_ms) return false;
  if (stop_ && status.error_code() != grpc::StatusCode::CANCELLED) {
    // Stopping and the coordinator does not answer: what is left (its
    // unreported results, unstarted leases) is recomputed after the
    // leases expire, so waiting for a coordinator that may never come
    // back gains nothing (systemd and Kubernetes would SIGKILL).
    std::lock_guard lock(mu_);
    log::Warn("worker_leaving_unreported", {{"worker", o_.worker_id},
                                            {"coordinator", o_.coordinator},
                                            {"error", status.error_message()},
                                            {"results", done_.size()},
                                            {"leases", in_flight_.size()}});
    return false;
  }
  if (!stop_)
    log::Warn("worker_reconnecting", {{"worker", o_.worker_id},
                                      {"coordinator", o_.coordinator},
                                      {"error", status.error_message()},
                                      {"backoff_ms", retry.backoff_ms}});
  std::this_thread::sleep_for(std::chrono::milliseconds(stop_ ? 200 : retry.backoff_ms));
  retry.backoff_ms = std::min<std::int64_t>(retry.backoff_ms * 2, 5000);
  return true;
}

bool Worker::RunLeasesHere() {
  std::optional<v1::Lease> lease = TakeLease();
  if (!lease) return false;
  RunLease(*lease);
  while (true) {
    {
      std::lock_guard lock(mu_);
      if (!short_tasks_ || done_.size() >= kResultsPerSync || held_seconds_ >= kShortTaskSeconds) break;
    }
    std::optional<v1::Lease> next = TakeLease();
    if (!next) break;
    RunLease(*next);
  }
  return true;
}

void Worker::SyncLoop() {
  SyncRetry retry;
  retry.started = Clock::now();
  bool patient = false;  // wait for a result (or a while) before the next Sync
  while (true) {
    bool leaving = false;
    v1::SyncRequest req = AwaitSyncTurn(patient, &leaving);
    v1::SyncResponse resp;
    grpc::Status status = CallSync(req, &resp);
    if (!status.ok()) {
      {
        std::unique_lock lock(mu_);
        EndSync(lock);
      }
      if (!BackOffAfterFailedSync(status, retry)) return;
      patient = false;
      continue;
    }
    const bool reconnected = retry.backoff_ms > 200;  // a Sync failed before this one
    retry.backoff_ms = 200;
    retry.failing_since.reset();
    {
      std::unique_lock lock(mu_);
      if (!connected_) retry.started = Clock::now();
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
      // Short tasks: the leases taken in advance run before the Sync, so
      // one Sync reports up to kResultsPerSync results, held back no longer
      // than about kShortTaskSeconds of work (a longer task reports at
      // once: its result is not held back, nor the leases behind it from
      // others).
      if (RunLeasesHere()) {
        patient = false;
        continue;
      }
    } else if (resp.leases_size() > 0) {
      queue_cv_.notify_all();
    }
  }
}

bool Worker::ReportLastTask() {
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

void Worker::HeartbeatLoop() {
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

void Worker::ShareLoop() {
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
        if (auto blob = HeldSolidBlob(*job, sampling::PointKey(ref.point_key().begin(), ref.point_key().end()))) {
          // Inline when it fits one chunk (worker.proto SharedSolid.blob):
          // nothing durable names a shared solid, so it need not pass
          // through the coordinator's blob store.
          if (blob->size() <= static_cast<std::size_t>(protocol::kBlobChunkBytes))
            answer.set_blob(std::move(*blob));
          else
            answer.set_digest(Upload(*blob));
          if (!answer.blob().empty() || !answer.digest().empty()) ++solids_shared_;
        }
      answers.push_back(std::move(answer));
    }
  }
}

void Worker::SlotLoop() {
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

v1::Lease Worker::PopLease() {
  v1::Lease lease = std::move(queue_.front());
  queue_.pop_front();
  ++running_;
  return lease;
}

std::optional<v1::Lease> Worker::TakeLease() {
  std::lock_guard lock(mu_);
  if (queue_.empty() || stop_) return std::nullopt;
  return PopLease();
}

void Worker::RunLease(const v1::Lease& lease) {
  auto started = Clock::now();
  v1::CompletedTask done = Execute(lease);
  const std::string kind = protocol::TaskKindName(lease.payload().kind());
  const double seconds = std::chrono::duration<double>(Clock::now() - started).count();
  task_seconds_.Observe(kind, seconds);
  if (!done.error().empty())
    log::Warn(
        "task_failed",
        {{"task", lease.task_key()}, {"job", lease.job_id()}, {"attempt", lease.attempt()}, {"reason", done.error()}});
  std::lock_guard lock(mu_);
  short_tasks_ = seconds < kShortTaskSeconds;
  held_seconds_ += seconds;
  ++tasks_by_kind_[kind];
  if (!done.error().empty()) ++failures_by_kind_[kind];
  --running_;
  ++summary_.tasks_run;
  in_flight_.erase(lease.lease_id());
  done_.push_back(std::move(done));
}

WorkerSummary RunWorker(const WorkerOptions& options, const std::atomic<bool>& stop) {
  Worker worker(options, stop);
  return worker.Run();
}

}  // namespace fabatlas::worker
