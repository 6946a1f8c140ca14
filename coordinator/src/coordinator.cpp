// The coordinator: JobService, WorkerService and BlobService over the durable
// store, one sampling driver thread per running job, the lease sweeper and
// the /metrics endpoint (see coordinator.h).
#include "fabatlas/coordinator/coordinator.h"

#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <httplib.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cctype>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <deque>
#include <functional>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>
#include <unordered_map>

#include "fabatlas/coordinator/job_eta.h"
#include "fabatlas/design/design.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/log/metrics_text.h"
#include "fabatlas/pipeline/cache_assembly.h"
#include "fabatlas/pipeline/executor.h"
#include "fabatlas/pipeline/run_job.h"
#include "fabatlas/precompute/form_outputs.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/protocol/tasks.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/storage/artifact.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/v1/blob.grpc.pb.h"
#include "fabatlas/v1/job.grpc.pb.h"
#include "fabatlas/v1/worker.grpc.pb.h"
#include "store_subtrees.h"

namespace fabatlas::coordinator {

namespace fs = std::filesystem;
using grpc::ServerContext;
using grpc::Status;
using grpc::StatusCode;

namespace {

std::int64_t NowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// The result a quarantined task finishes with (an invalid sample of failure
// type "quarantined" for sample tasks), as stored bytes.
std::string QuarantineBytes(int kind) {
  return protocol::QuarantineResult(static_cast<v1::TaskKind>(kind)).SerializeAsString();
}

struct Stopping {};
struct JobCancelled {};

// The task kind of a result, named as protocol::TaskKindName names kinds.
std::string ResultKind(const v1::TaskResult& r) {
  switch (r.result_case()) {
    case v1::TaskResult::kSample: return "sample";
    case v1::TaskResult::kGeometryChange: return "geometry_change";
    case v1::TaskResult::kNoop: return "noop";
    case v1::TaskResult::kSweptVolume: return "swept_volume";
    case v1::TaskResult::kCachePlan: return "cache_plan";
    default: return "unknown";
  }
}

bool Terminal(storage::JobState s) {
  return s == storage::JobState::kSucceeded || s == storage::JobState::kFailed ||
         s == storage::JobState::kCancelled;
}

}  // namespace

struct Coordinator::Impl {
  explicit Impl(CoordinatorOptions o) : options(std::move(o)) {}

  CoordinatorOptions options;
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

  void StateWriteFailed(const std::string& where, const std::string& error) {
    ++state_write_failures_total;
    std::int64_t now = NowMs();
    std::lock_guard lock(stall_mu);
    if (!stalled) stall_since_ms = now;
    stalled = true;
    stall_last_ms = now;
    stall_reason = error;
    if (now - stall_logged_ms < 10000) return;
    stall_logged_ms = now;
    log::Error("state_write_failed", {{"where", where}, {"error", error}, {"state_dir", options.state_dir.string()},
                                      {"stalled_ms", now - stall_since_ms}});
  }
  // A write succeeded; the stall ends once no write failed for 5 s (on a
  // nearly full disk small writes succeed between failing large ones).
  void StateWriteSucceeded() {
    if (!stalled) return;
    std::lock_guard lock(stall_mu);
    if (!stalled || NowMs() - stall_last_ms < 5000) return;
    stalled = false;
    stall_logged_ms = 0;
    log::Info("state_write_recovered", {{"stalled_ms", NowMs() - stall_since_ms}});
  }
  // "" when writes succeed, else why running jobs are stalled.
  std::string StallText() {
    if (!stalled) return "";
    std::lock_guard lock(stall_mu);
    return "coordinator cannot write its state for " + std::to_string((NowMs() - stall_since_ms) / 1000) +
           " s: " + stall_reason;
  }

  // tasks/s per job: (time, tasks done) samples over the last 10 s.
  std::mutex rate_mu;
  std::map<std::string, std::deque<std::pair<std::int64_t, std::int64_t>>> rate_samples;

  std::mutex shutdown_mu;
  std::condition_variable shutdown_cv;
  bool shut_down = false;

  // Solid sharing (worker.proto FetchSolid / ShareSolids), in memory only: a
  // coordinator restart forgets it and workers evaluate a missing solid
  // again. shares: SolidKey -> the blob a holder shared (answered with an
  // empty digest: it does not hold the solid); share_wanted: holder -> the
  // requests to pass on; share_polled: holder -> when its ShareSolids loop
  // was last seen (a holder not polling is not asked).
  struct Share {
    std::string digest;
    bool answered = false;
    std::int64_t asked_ms = 0;
  };
  std::mutex share_mu;
  std::condition_variable share_cv;
  std::map<std::string, Share> shares;
  std::map<std::string, std::vector<v1::SolidRef>> share_wanted;
  std::map<std::string, std::int64_t> share_polled;

  // The adaptive schedule of each running job as its driver last saw it, for
  // the ETA (JobStatus.eta_seconds, job_eta.h): the batches so far, when the
  // running one began and, once sampling is over, when publishing began.
  struct Schedule {
    JobEtaInput input;
    std::chrono::steady_clock::time_point batch_started, publish_started;
  };
  std::mutex schedule_mu;
  std::map<std::string, Schedule> schedules;

  std::atomic<std::int64_t> blobs_collected_total{0}, blob_bytes_collected_total{0};
  std::mutex collect_mu;

  void SignalWork() {
    {
      std::lock_guard lock(work_mu);
      ++work_epoch;
    }
    work_cv.notify_all();
  }

  struct Delivery {
    const std::string* key;
    const std::string* result;
  };
  // Hands results to the waiting drivers; wakes them only when one has all
  // its results (one wake-up per batch, not per task).
  void Deliver(const std::vector<Delivery>& results, const std::string& worker = "") {
    bool complete = false;
    {
      std::lock_guard lock(results_mu);
      for (const Delivery& d : results) {
        auto range = waiting.equal_range(*d.key);
        for (auto it = range.first; it != range.second; ++it)
          if (it->second->results.emplace(*d.key, *d.result).second) {
            it->second->workers.emplace(*d.key, worker);
            if (--it->second->pending == 0) complete = true;
          }
      }
    }
    if (complete) results_cv.notify_all();
  }
  void Deliver(const std::string& key, const std::string& result) { Deliver({{&key, &result}}); }

  // A worker showed it is alive, by a Sync (slots: free and in flight) or a
  // Heartbeat (slots = -1: it carries none, and refreshes only a worker a
  // Sync introduced): the workers table behind the `workers` metric and
  // workers_seen for lease affinity.
  void WorkerAlive(const std::string& id, int slots, std::int64_t now) {
    {
      std::lock_guard lock(workers_mu);
      auto it = workers_seen.find(id);
      if (slots < 0) {
        if (it == workers_seen.end()) return;
        slots = it->second.slots;
      }
      if (it == workers_seen.end()) log::Info("worker_joined", {{"worker", id}, {"slots", slots}});
      workers_seen[id] = {slots, now};
    }
    store->TouchWorker(id, slots, now);
  }

  // Workers that synced within the last lease period with at least one
  // slot, by id.
  std::vector<std::pair<std::string, int>> ConnectedWorkers() {
    std::vector<std::pair<std::string, int>> out;
    std::int64_t since = NowMs() - options.lease_ms;
    std::lock_guard lock(workers_mu);
    for (const auto& [id, seen] : workers_seen)
      if (seen.slots > 0 && seen.last_ms >= since) out.emplace_back(id, seen.slots);
    return out;
  }

  static std::string SolidKey(const v1::SolidRef& ref) {
    std::string key = ref.job_bundle_digest() + ":";
    for (int i = 0; i < ref.point_key_size(); ++i) key += (i ? "," : "") + std::to_string(ref.point_key(i));
    return key;
  }

  // Blob garbage collection (docs/protocol.md "Blob lifecycle"): mark every
  // blob the store references (JobStore::ReferencedBlobs), sweep the rest
  // that are older than the oldest live lease (a worker uploads before it
  // reports, so a blob of a result not yet reported is newer than its
  // lease) and than 10 s (a client uploads a bundle just before it submits
  // it; a held blob named again is touched: BlobStore::Touch). Mark and
  // sweep are read-only on the store and idempotent on disk, so a kill -9
  // between any two steps loses nothing and the next pass finishes the work. Order matters: the cutoff is taken before the
  // references, so a lease that completes in between has its blobs marked.
  void CollectBlobs(const std::string& reason) {
    std::lock_guard lock(collect_mu);
    std::int64_t cutoff = NowMs() - 10000;
    const std::int64_t oldest_lease = store->OldestActiveLeaseMs();
    if (oldest_lease >= 0) cutoff = std::min(cutoff, oldest_lease - 1000);
    const std::vector<std::string> keep = store->ReferencedBlobs();
    const storage::BlobStore::Collection c = blobs->Collect(keep, cutoff);
    blobs_collected_total += c.blobs_removed;
    blob_bytes_collected_total += c.bytes_removed;
    if (c.blobs_removed > 0)
      log::Info("blobs_collected", {{"reason", reason}, {"removed", c.blobs_removed},
                                    {"removed_bytes", c.bytes_removed}, {"kept", c.blobs_kept},
                                    {"kept_bytes", c.bytes_kept}});
  }

  // Runs the tasks (serialized payloads) through the workers; results in
  // order. preferred[i]: workers task i prefers (lease affinity; may be
  // empty). workers_out[i]: the worker whose result was accepted, or "" for
  // a result already in the store.
  std::vector<std::string> RunTasks(const std::string& job_id, const std::vector<std::string>& payloads,
                                    const std::vector<std::string>& keys, const std::vector<int>& kinds,
                                    const std::vector<std::vector<std::string>>& preferred = {},
                                    std::vector<std::string>* workers_out = nullptr) {
    Waiter waiter;
    waiter.job_id = job_id;
    std::vector<storage::NewTask> tasks;
    std::set<std::string> unique;
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (unique.insert(keys[i]).second) {
        tasks.push_back({keys[i], job_id, kinds[i], payloads[i], {}});
        if (options.lease_affinity && i < preferred.size()) tasks.back().preferred_workers = preferred[i];
      }
    {
      std::lock_guard lock(results_mu);
      waiter.pending = unique.size();
      for (const auto& key : unique) waiting.emplace(key, &waiter);
    }
    auto unregister = [&] {
      for (const auto& key : unique) {
        auto range = waiting.equal_range(key);
        for (auto it = range.first; it != range.second; ++it)
          if (it->second == &waiter) {
            waiting.erase(it);
            break;
          }
      }
    };
    std::map<std::string, std::string> finished;
    try {
      finished = store->AddTasks(tasks);
    } catch (...) {
      std::lock_guard lock(results_mu);
      unregister();
      throw;
    }
    log::Info("round_started", {{"job", job_id}, {"kind", kinds.empty() ? "" : protocol::TaskKindName(kinds[0])},
                                {"tasks", tasks.size()}, {"stored", finished.size()}});
    std::vector<Delivery> stored;
    for (const auto& [key, result] : finished) stored.push_back({&key, &result});
    Deliver(stored);
    SignalWork();
    std::unique_lock lock(results_mu);
    results_cv.wait(lock, [&] {
      return waiter.pending == 0 || stopping || cancelled_jobs.count(job_id) > 0;
    });
    unregister();
    if (waiter.pending > 0) {
      if (stopping) throw Stopping{};
      throw JobCancelled{};
    }
    std::vector<std::string> out;
    out.reserve(keys.size());
    for (const auto& key : keys) out.push_back(waiter.results.at(key));
    if (workers_out) {
      workers_out->clear();
      for (const auto& key : keys) workers_out->push_back(waiter.workers[key]);
    }
    return out;
  }

  // pipeline::Executor whose tasks run on the workers.
  class RemoteExecutor : public pipeline::Executor {
   public:
    // bundle_digest: the job's bundle blob (JobRecord::bundle_digest).
    RemoteExecutor(Impl& impl, std::string job_id, std::string bundle_digest, const pipeline::Job& job)
        : impl_(impl), job_id_(std::move(job_id)), bundle_digest_(std::move(bundle_digest)), job_(job),
          digest_(protocol::EvaluationDigest(job.bundle)), subdivisions_(job.file.subdivisions),
          sampling_(job.file.sampling) {}

    std::vector<sampling::SampleOutcome> RunSampleTasks(const std::vector<sampling::SampleTask>& tasks,
                                                        sampling::SampleEvaluator&,
                                                        std::vector<sampling::TaskTiming>* timings) override {
      std::vector<v1::TaskPayload> payloads;
      for (const auto& t : tasks) payloads.push_back(protocol::SamplePayload(t));
      // Lease affinity: the batch (sorted by point key) cut into contiguous
      // runs, one per connected worker in proportion to its slots, so that
      // neighbouring samples, which share subtrees and ΔG edges, mostly
      // land on one worker.
      std::vector<std::vector<std::string>> preferred(tasks.size());
      auto workers = impl_.ConnectedWorkers();
      if (workers.size() >= 2) {
        std::size_t total = 0;
        for (const auto& w : workers) total += static_cast<std::size_t>(w.second);
        std::size_t begin = 0, slots_before = 0;
        for (const auto& [id, slots] : workers) {
          slots_before += static_cast<std::size_t>(slots);
          std::size_t end = tasks.size() * slots_before / total;
          for (std::size_t i = begin; i < end; ++i) preferred[i] = {id};
          begin = end;
        }
      }
      std::vector<std::string> producers;
      if (!tasks.empty()) dims_ = tasks[0].point.key.size();
      BeginBatch(/*samples=*/true, tasks.size());
      auto results = Run(payloads, preferred, &producers);
      EndBatch(results);
      std::vector<sampling::SampleOutcome> out;
      if (timings) timings->assign(tasks.size(), {});
      for (std::size_t i = 0; i < results.size(); ++i) {
        if (!producers[i].empty()) holders_[tasks[i].point.key] = producers[i];
        out.push_back(protocol::SampleOutcomeOf(results[i]));
        if (timings) (*timings)[i].wall_seconds = results[i].wall_seconds();
      }
      return out;
    }

    std::vector<sampling::GeometryChangeResult> RunGeometryChangeTasks(
        const std::vector<sampling::GeometryChangeTask>& tasks, sampling::SampleEvaluator&,
        std::vector<sampling::TaskTiming>* timings) override {
      std::vector<v1::TaskPayload> payloads;
      std::vector<std::vector<std::string>> preferred;
      for (const auto& t : tasks) {
        // The workers holding the samples' root solids, so that any worker
        // can ask them instead of evaluating again (tasks.proto "Geometry
        // blobs").
        v1::TaskPayload p = protocol::GeometryChangePayload(t);
        if (auto it = holders_.find(t.point_a.key); it != holders_.end()) p.set_solid_holder_a(it->second);
        if (auto it = holders_.find(t.point_b.key); it != holders_.end()) p.set_solid_holder_b(it->second);
        payloads.push_back(std::move(p));
        // Lease affinity: the workers holding the solids in memory.
        std::vector<std::string> holders;
        for (const auto* key : {&t.point_a.key, &t.point_b.key})
          if (auto it = holders_.find(*key); it != holders_.end() &&
              std::find(holders.begin(), holders.end(), it->second) == holders.end())
            holders.push_back(it->second);
        preferred.push_back(std::move(holders));
      }
      BeginBatch(/*samples=*/false, tasks.size());
      auto results = Run(payloads, preferred);
      EndBatch(results);
      std::vector<sampling::GeometryChangeResult> out;
      if (timings) timings->assign(tasks.size(), {});
      for (std::size_t i = 0; i < results.size(); ++i) {
        out.push_back({results[i].geometry_change(), results[i].cpu_seconds()});
        if (timings) (*timings)[i].wall_seconds = results[i].wall_seconds();
      }
      return out;
    }

    // Sampling is over: the ETA is the publishing left, and the job's
    // shared solids are forgotten.
    void SamplingFinished() override {
      publish_started_ = std::chrono::steady_clock::now();
      {
        std::lock_guard lock(impl_.schedule_mu);
        if (auto it = impl_.schedules.find(job_id_); it != impl_.schedules.end())
          it->second.publish_started = publish_started_;
      }
      impl_.ForgetShares(bundle_digest_);
    }
    // When SamplingFinished was called.
    std::chrono::steady_clock::time_point publish_started() const { return publish_started_; }

    // TASK_KIND_SWEPT_VOLUME tasks; each worker uploads its cutter surface
    // as a blob, read back here.
    std::vector<design::SweptVolumeResult> RunSweptVolumeTasks(
        const std::vector<pipeline::SweptVolumeTask>& tasks) override {
      std::vector<v1::TaskPayload> payloads;
      for (const auto& t : tasks) {
        v1::TaskPayload p = protocol::SamplePayload({t.point});
        p.set_kind(v1::TASK_KIND_SWEPT_VOLUME);
        p.mutable_swept()->set_node_path(t.node_path);
        payloads.push_back(std::move(p));
      }
      std::vector<design::SweptVolumeResult> out;
      for (const v1::TaskResult& result : Run(payloads)) {
        const v1::SweptVolumeResult& r = result.swept_volume();
        design::SweptVolumeResult s;
        s.volume = r.volume();
        s.triangles = r.triangles();
        s.time_steps = r.time_steps();
        s.active_voxels = r.active_voxels();
        s.surface_sha256 = r.surface_sha256();
        if (!r.surface_blob().empty()) {
          impl_.store->AddJobBlob(job_id_, r.surface_blob());
          // The blob's digest is the surface's SHA-256 when it holds it.
          if (r.surface_blob() == r.surface_sha256()) s.surface_bytes = impl_.blobs->Read(r.surface_blob());
        }
        out.push_back(std::move(s));
      }
      return out;
    }

    // The subtrees the workers reported while sampling. Every subtree blob
    // the store names is still here (the collector keeps a running job's
    // geometry); one that is not is evaluated again, and recorded.
    pipeline::CacheAssembly CacheSubtrees(const sampling::Form& form) override {
      for (const auto& row : impl_.store->Subtrees(job_id_))
        if (!row.blob_digest.empty() && !impl_.blobs->Contains(row.blob_digest))
          impl_.Event(job_id_, "blob_missing", "subtree " + row.key + " names blob " + row.blob_digest +
                                                   ", which is not in the store");
      return CollectSubtreesFromStore(*impl_.store, *impl_.blobs, job_id_, job_.design, form);
    }

    v1::CachePlanReport RunCachePlan(const v1::CachePlanInput& input) override {
      return impl_.PlanCacheOnWorkers(job_id_, digest_, subdivisions_, input);
    }

    // Any tasks, run by the workers; results in
    // order. preferred: lease affinity per task (may be empty); producers:
    // the worker whose result was accepted ("" = already in the store).
    std::vector<v1::TaskResult> Run(const std::vector<v1::TaskPayload>& payloads,
                                    const std::vector<std::vector<std::string>>& preferred = {},
                                    std::vector<std::string>* producers = nullptr) {
      std::vector<std::string> bytes, keys;
      std::vector<int> kinds;
      for (const auto& p : payloads) {
        bytes.push_back(p.SerializeAsString());
        keys.push_back(protocol::TaskKey(p, digest_, subdivisions_));
        kinds.push_back(static_cast<int>(p.kind()));
      }
      auto results = impl_.RunTasks(job_id_, bytes, keys, kinds, preferred, producers);
      std::vector<v1::TaskResult> out(results.size());
      for (std::size_t i = 0; i < results.size(); ++i) out[i].ParseFromString(results[i]);
      return out;
    }

   private:
    // The schedule for the ETA (JobStatus.eta_seconds, job_eta.h): every
    // batch with its wall seconds, handed to the status calls.
    void BeginBatch(bool samples, std::size_t size) {
      batches_.push_back({samples, static_cast<double>(size), 0});
      batch_started_ = std::chrono::steady_clock::now();
      Publish();
    }
    void EndBatch(const std::vector<v1::TaskResult>& results) {
      if (results.empty()) return;
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - batch_started_).count();
      for (const auto& r : results) batches_.back().cpu_seconds += r.cpu_seconds();
      // Batches replayed from the store take no time: their rate teaches nothing.
      if (seconds >= 0.05 * static_cast<double>(results.size()) * 1e-3) batches_.back().seconds = seconds;
      Publish();
    }
    void Publish() {
      std::lock_guard lock(impl_.schedule_mu);
      auto& sch = impl_.schedules[job_id_];
      sch.input.batches = batches_;
      sch.input.max_depth = sampling_.max_depth;
      sch.input.max_samples = static_cast<double>(sampling_.max_samples);
      sch.input.dimensions = static_cast<int>(dims_);
      sch.batch_started = batch_started_;
    }

    Impl& impl_;
    std::string job_id_, bundle_digest_;
    const pipeline::Job& job_;
    std::string digest_;
    int subdivisions_;
    sampling::SamplingOptions sampling_;
    // The worker that evaluated each sample in this run of the driver (it
    // holds the root solid in memory), for ΔG lease affinity and solid
    // sharing (TaskPayload.solid_holder_a/b).
    std::map<sampling::PointKey, std::string> holders_;
    std::vector<EtaBatch> batches_;
    std::size_t dims_ = 1;
    std::chrono::steady_clock::time_point batch_started_, publish_started_;
  };

  void Event(const std::string& job_id, const std::string& kind, const std::string& message) {
    try {
      store->AddEvent({NowMs(), job_id, kind, message});
    } catch (const std::exception&) {
    }
  }

  // The geometry cache plan of a job whose sampling finished, as one
  // TASK_KIND_CACHE_PLAN task (tasks.proto): the input goes into the blob
  // store, a worker leases the task, runs protocol::RunCachePlan and uploads
  // the report. Retried like any task; a replayed job finds the stored
  // result. Throws InputError when the task was quarantined.
  v1::CachePlanReport PlanCacheOnWorkers(const std::string& job_id, const std::string& evaluation_digest,
                                         int subdivisions, const v1::CachePlanInput& input) {
    v1::TaskPayload payload;
    payload.set_kind(v1::TASK_KIND_CACHE_PLAN);
    payload.mutable_cache_plan()->set_input_digest(blobs->Put(input.SerializeAsString()));
    store->AddJobBlob(job_id, payload.cache_plan().input_digest());
    const std::string key = protocol::TaskKey(payload, evaluation_digest, subdivisions);
    Event(job_id, "cache_plan", "cache plan task " + key.substr(0, 16) + ": " +
                                    std::to_string(input.subtrees_size()) + " subtree records, " +
                                    std::to_string(input.sample_roots_size()) + " samples");
    const auto results = RunTasks(job_id, {payload.SerializeAsString()}, {key}, {v1::TASK_KIND_CACHE_PLAN});
    v1::TaskResult result;
    result.ParseFromString(results.at(0));
    const std::string& digest = result.cache_plan().report_digest();
    if (digest.empty())
      throw InputError("job " + job_id + ": the geometry cache plan task " + key.substr(0, 16) +
                       " was quarantined (it lost too many workers)");
    store->AddJobBlob(job_id, digest);
    v1::CachePlanReport report;
    if (!blobs->Contains(digest) || !report.ParseFromString(blobs->Read(digest)))
      throw InputError("job " + job_id + ": cache plan report " + digest + " is missing or not a CachePlanReport");
    return report;
  }

  // Forgets the job's shared solids (its sampling is over).
  void ForgetShares(const std::string& bundle_digest) {
    std::lock_guard lock(share_mu);
    for (auto it = shares.lower_bound(bundle_digest + ":"); it != shares.end() && it->first.rfind(bundle_digest + ":", 0) == 0;)
      it = shares.erase(it);
  }

  // worker.proto FetchSolid: the blob of a solid another worker holds, or ""
  // (evaluate again).
  std::string FetchSolid(const v1::FetchSolidRequest& req, grpc::ServerContext* ctx) {
    const std::string& holder = req.holder_worker_id();
    if (holder.empty() || holder == req.worker_id()) return "";
    const std::string key = SolidKey(req.solid());
    const std::int64_t wait_ms = std::clamp<std::int64_t>(req.max_wait_ms(), 0, 10000);
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(wait_ms);
    std::unique_lock lock(share_mu);
    while (true) {
      auto it = shares.find(key);
      if (it != shares.end() && it->second.answered) {
        if (it->second.digest.empty()) return "";
        if (blobs->Touch(it->second.digest)) return it->second.digest;
        shares.erase(it);  // collected since: ask the holder again
        continue;
      }
      if (it == shares.end()) {
        // Ask the holder only while its ShareSolids loop is alive.
        auto polled = share_polled.find(holder);
        if (polled == share_polled.end() || polled->second < NowMs() - 3000) return "";
        shares[key] = Share{"", false, NowMs()};
        share_wanted[holder].push_back(req.solid());
        share_cv.notify_all();
      }
      if (stopping || ctx->IsCancelled() || std::chrono::steady_clock::now() >= until) {
        // No answer in time (holder busy, killed or gone): the next caller asks again.
        if (auto again = shares.find(key); again != shares.end() && !again->second.answered) shares.erase(again);
        return "";
      }
      share_cv.wait_until(lock, std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(250)));
    }
  }

  // worker.proto ShareSolids: records the holder's answers, then waits for
  // requests addressed to it.
  void ShareSolids(const v1::ShareSolidsRequest& req, v1::ShareSolidsResponse* resp, grpc::ServerContext* ctx) {
    const std::int64_t wait_ms = std::clamp<std::int64_t>(req.max_wait_ms(), 0, 10000);
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(wait_ms);
    std::unique_lock lock(share_mu);
    share_polled[req.worker_id()] = NowMs();
    for (const auto& shared : req.shared()) {
      Share& share = shares[SolidKey(shared.solid())];
      share.digest = blobs->Touch(shared.digest()) ? shared.digest() : "";
      share.answered = true;
    }
    if (req.shared_size() > 0) share_cv.notify_all();
    while (true) {
      auto& wanted = share_wanted[req.worker_id()];
      if (!wanted.empty()) {
        for (auto& ref : wanted) *resp->add_wanted() = std::move(ref);
        wanted.clear();
        break;
      }
      if (stopping || ctx->IsCancelled() || std::chrono::steady_clock::now() >= until) break;
      share_cv.wait_until(lock, std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(250)));
      share_polled[req.worker_id()] = NowMs();
    }
    share_polled[req.worker_id()] = NowMs();
  }

  void Drive(const std::string& job_id) {
    try {
      auto job = store->FindJob(job_id);
      if (!job) return;
      v1::JobBundle bundle;
      if (!bundle.ParseFromString(blobs->Read(job->bundle_digest)))
        throw InputError("job " + job_id + ": the bundle blob is not a JobBundle");
      const fs::path dir = options.state_dir / "jobs" / job_id;
      const pipeline::Job loaded = pipeline::JobOfBundle(std::move(bundle), dir);
      RemoteExecutor executor(*this, job_id, job->bundle_digest, loaded);
      Event(job_id, "driver_started", "sampling driver started (replaying stored results)");
      log::Info("job_started", {{"job", job_id}, {"design", loaded.design.name}});
      pipeline::RunOptions run_options;
      run_options.out_dir = dir / "out";
      const pipeline::RunSummary run = pipeline::RunJob(loaded, executor, run_options);
      if (run.cache)
        Event(job_id, "cache", "geometry cache " + run.cache_manifest.strategy + ": " +
                                   std::to_string(run.written.cache_entries) + " entries, " +
                                   std::to_string(run.written.cache_entries_left_out) + " without geometry; " +
                                   pipeline::ExactText(run.cache_added.exact));
      for (const auto& entry : fs::directory_iterator(run_options.out_dir)) {
        if (!entry.is_regular_file()) continue;
        std::string name = entry.path().filename().string();
        if (name.find(".tmp") != std::string::npos) continue;
        store->PutJobOutput(job_id, name, blobs->PutFile(entry.path()));
      }
      store->SetJobState(job_id, storage::JobState::kSucceeded, "", NowMs());
      Event(job_id, "succeeded", precompute::Table3Row(loaded.design, run.sampling.statistics));
      log::Info("job_succeeded",
                {{"job", job_id}, {"design", loaded.design.name}, {"samples", run.sampling.statistics.samples},
                 {"valid_samples", run.sampling.statistics.valid_samples},
                 {"publish_seconds",
                  std::chrono::duration<double>(std::chrono::steady_clock::now() - executor.publish_started()).count()}});
      // The published artifact holds what the cache plan kept: the job's
      // geometry blobs go now.
      CollectBlobs("job " + job_id + " published");
    } catch (const Stopping&) {
    } catch (const JobCancelled&) {
    } catch (const ResourceError& e) {
      // State or outputs could not be written: the job stays running and the
      // sweeper starts the driver again (a replay) until they can.
      StateWriteFailed("job " + job_id, e.what());
      ForgetSchedule(job_id);
      std::lock_guard lock(drivers_mu);
      running_drivers.erase(job_id);
      if (!stopping) restart_drivers.insert(job_id);
      return;
    } catch (const std::exception& e) {
      if (!stopping) {
        log::Error("job_failed", {{"job", job_id}, {"error", e.what()}});
        store->SetJobState(job_id, storage::JobState::kFailed, e.what(), NowMs());
        Event(job_id, "failed", e.what());
      }
    }
    ForgetSchedule(job_id);
    std::lock_guard lock(drivers_mu);
    running_drivers.erase(job_id);
  }

  void ForgetSchedule(const std::string& job_id) {
    std::lock_guard lock(schedule_mu);
    schedules.erase(job_id);
  }

  void StartDriver(const std::string& job_id) {
    std::lock_guard lock(drivers_mu);
    if (stopping || !running_drivers.insert(job_id).second) return;
    drivers.emplace_back([this, job_id] { Drive(job_id); });
  }

  v1::JobStatus StatusOf(const storage::JobRecord& job) {
    v1::JobStatus s;
    s.set_job_id(job.id);
    s.set_state(static_cast<v1::JobState>(job.state));
    s.set_design_name(job.design_name);
    storage::TaskCounts c = store->CountTasks(job.id);
    s.set_tasks_total(c.total);
    s.set_tasks_done(c.done + c.quarantined);
    s.set_tasks_leased(c.leased);
    s.set_tasks_queued(c.queued);
    s.set_tasks_quarantined(c.quarantined);
    s.set_samples_done(c.samples_done);
    s.set_samples_valid(c.samples_valid);
    s.set_lease_expiries(c.lease_expiries);
    s.set_fenced_results(c.fenced_results);
    s.set_error(job.error);
    if (job.state == storage::JobState::kRunning) s.set_stalled_reason(StallText());
    s.set_created_unix_ms(job.created_ms);
    s.set_finished_unix_ms(job.finished_ms);
    std::int64_t now = NowMs(), done = c.done + c.quarantined;
    {
      std::lock_guard lock(schedule_mu);
      if (auto it = schedules.find(job.id); it != schedules.end() && !Terminal(job.state)) {
        JobEtaInput in = it->second.input;
        const auto steady_now = std::chrono::steady_clock::now();
        in.running_left = static_cast<double>(c.queued + c.leased);
        in.running_seconds = std::chrono::duration<double>(steady_now - it->second.batch_started).count();
        if (it->second.publish_started != std::chrono::steady_clock::time_point{})
          in.publishing_seconds = std::chrono::duration<double>(steady_now - it->second.publish_started).count();
        if (const JobEta eta = EstimateJobEta(in); eta.known) s.set_eta_seconds(eta.seconds);
      }
    }
    std::lock_guard lock(rate_mu);
    auto& samples = rate_samples[job.id];
    samples.emplace_back(now, done);
    while (samples.size() > 1 && samples.front().first < now - 10000) samples.pop_front();
    if (samples.size() > 1 && now > samples.front().first)
      s.set_tasks_per_second(1000.0 * static_cast<double>(done - samples.front().second) /
                             static_cast<double>(now - samples.front().first));
    return s;
  }

  std::string Metrics() {
    log::MetricsText m;
    storage::TaskCounts c = store->CountTasks("");
    std::int64_t now = NowMs();
    for (const auto& [state, n] : {std::pair{"queued", c.queued}, {"leased", c.leased}, {"done", c.done},
                                   {"quarantined", c.quarantined}})
      m.Gauge("fabatlas_tasks", "Tasks in the store by state.", static_cast<double>(n), {{"state", state}});
    m.Counter("fabatlas_tasks_completed_total", "Results accepted since start-up (rate() = throughput).",
              static_cast<double>(completed_total.load()));
    m.Counter("fabatlas_task_failures_total", "Tasks a worker reported it could not run, since start-up.",
              static_cast<double>(task_failures_total.load()));
    m.Counter("fabatlas_results_fenced_total", "Late results of expired leases since start-up.",
              static_cast<double>(fenced_total.load()));
    m.Counter("fabatlas_results_duplicate_total", "Results of tasks already finished since start-up.",
              static_cast<double>(duplicate_total.load()));
    m.Counter("fabatlas_lease_expiries_total", "Lease expiries recorded in the store (all jobs, all time).",
              static_cast<double>(c.lease_expiries));
    task_seconds.Write(m, "fabatlas_task_duration_seconds", "Wall time of accepted task results, by task kind.");
    m.Gauge("fabatlas_workers", "Workers seen within two lease periods.",
            static_cast<double>(store->CountWorkers(now - 2 * options.lease_ms)));
    std::map<int, int> jobs;
    std::vector<storage::JobRecord> running;
    for (const auto& j : store->Jobs()) {
      ++jobs[static_cast<int>(j.state)];
      if (j.state == storage::JobState::kRunning) running.push_back(j);
    }
    for (int st = 1; st <= 5; ++st) {
      std::string name = v1::JobState_Name(static_cast<v1::JobState>(st)).substr(10);
      for (char& ch : name) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
      m.Gauge("fabatlas_jobs", "Jobs by state.", jobs[st], {{"state", name}});
    }
    // Progress of every running job (finished jobs drop out, so the series
    // stay few). Tasks total grows round by round as the sampler subdivides.
    for (const auto& j : running) {
      storage::TaskCounts jc = store->CountTasks(j.id);
      log::Labels id = {{"job", j.id}, {"design", j.design_name}};
      for (const auto& [state, n] : {std::pair{"queued", jc.queued}, {"leased", jc.leased}, {"done", jc.done},
                                     {"quarantined", jc.quarantined}}) {
        log::Labels l = id;
        l.emplace_back("state", state);
        m.Gauge("fabatlas_job_tasks", "Tasks of a running job by state.", static_cast<double>(n), l);
      }
      m.Gauge("fabatlas_job_samples", "Samples evaluated so far in a running job.", static_cast<double>(jc.samples_done), id);
      m.Gauge("fabatlas_job_valid_samples", "Valid samples so far in a running job.", static_cast<double>(jc.samples_valid), id);
      m.Gauge("fabatlas_job_start_time_seconds", "When a running job was submitted (Unix time).",
              static_cast<double>(j.created_ms) / 1000.0, id);
    }
    m.Counter("fabatlas_blobs_collected_total", "Blobs removed by the collector since start-up.",
              static_cast<double>(blobs_collected_total.load()));
    m.Counter("fabatlas_blob_bytes_collected_total", "Bytes of blobs removed by the collector since start-up.",
              static_cast<double>(blob_bytes_collected_total.load()));
    m.Gauge("fabatlas_draining", "1 while the coordinator drains.", draining ? 1 : 0);
    m.Gauge("fabatlas_state_stalled", "1 while the state directory cannot be written (jobs wait, nothing is lost).",
            stalled ? 1 : 0);
    m.Counter("fabatlas_state_write_failures_total", "Failed writes of the store, blobs or job outputs since start-up.",
              static_cast<double>(state_write_failures_total.load()));
    struct statvfs fs_stat {};
    if (::statvfs(options.state_dir.c_str(), &fs_stat) == 0)
      m.Gauge("fabatlas_state_free_bytes", "Free bytes on the state directory's file system (for unprivileged users).",
              static_cast<double>(fs_stat.f_bavail) * static_cast<double>(fs_stat.f_frsize));
    m.Gauge("process_resident_memory_bytes", "Resident memory of the coordinator.",
            static_cast<double>(log::ResidentMemoryBytes()));
    return m.text();
  }

  void Sweep() {
    std::int64_t last_checkpoint_ms = NowMs(), last_collect_ms = 0;
    while (!stopping) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      try {
        std::int64_t now = NowMs();
        if (now - last_checkpoint_ms >= 1000) {
          last_checkpoint_ms = now;
          store->Checkpoint();
          StateWriteSucceeded();
          std::set<std::string> restart;
          {
            std::lock_guard lock(drivers_mu);
            restart.swap(restart_drivers);
          }
          for (const auto& id : restart) StartDriver(id);
        }
        auto expired = store->ExpireLeases(now, options.retry_backoff_ms, options.quarantine_after, QuarantineBytes);
        for (const auto& e : expired) {
          log::Warn("lease_expired", {{"task", e.task_key}, {"job", e.job_id}, {"worker", e.worker_id},
                                      {"attempt", e.attempt}, {"expiries", e.expiries}});
          if (!e.quarantined) continue;
          log::Error("task_quarantined", {{"task", e.task_key}, {"job", e.job_id}, {"expiries", e.expiries}});
          if (auto task = store->FindTask(e.task_key)) Deliver(e.task_key, task->result);
        }
        if (!expired.empty()) last_retry_ms = now;
        std::vector<std::string> silent;
        {
          std::lock_guard lock(workers_mu);
          for (auto it = workers_seen.begin(); it != workers_seen.end();)
            if (it->second.last_ms < now - options.lease_ms) {
              log::Warn("worker_lost", {{"worker", it->first}, {"silent_ms", now - it->second.last_ms}});
              silent.push_back(it->first);
              it = workers_seen.erase(it);
            } else {
              ++it;
            }
        }
        for (const auto& id : silent)
          if (store->ForgetAffinity(id) > 0) SignalWork();
        if (!silent.empty()) {
          // Requests a silent holder will never answer: answered "not held".
          std::lock_guard lock(share_mu);
          for (const auto& id : silent) {
            for (const auto& ref : share_wanted[id]) shares[SolidKey(ref)].answered = true;
            share_wanted.erase(id);
            share_polled.erase(id);
          }
          share_cv.notify_all();
        }
        if (now - last_collect_ms >= 10000) {
          CollectBlobs("periodic");
          last_collect_ms = now;
        }
        if (!expired.empty() || now - last_retry_ms < 31000) SignalWork();
      } catch (const ResourceError& e) {
        StateWriteFailed("sweep", e.what());
      } catch (const std::exception& e) {
        log::Error("sweep_failed", {{"error", e.what()}});
      }
    }
  }
};

namespace {

Status Invalid(const std::string& message) { return Status(StatusCode::INVALID_ARGUMENT, message); }

Status FromException(const std::exception& e) {
  if (dynamic_cast<const ResourceError*>(&e)) return Status(StatusCode::RESOURCE_EXHAUSTED, e.what());
  if (dynamic_cast<const InputError*>(&e)) return Status(StatusCode::INVALID_ARGUMENT, e.what());
  return Status(StatusCode::INTERNAL, e.what());
}

class JobServiceImpl final : public v1::JobService::Service {
 public:
  explicit JobServiceImpl(Coordinator::Impl& impl) : impl_(impl) {}

  Status Submit(ServerContext* ctx, const v1::SubmitRequest* req, v1::SubmitResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    const std::string& digest = req->bundle_digest();
    if (!storage::IsDigest(digest)) return Invalid("bundle_digest is not a SHA-256 hex digest");
    if (!impl_.blobs->Contains(digest))
      return Status(StatusCode::FAILED_PRECONDITION, "bundle " + digest + " not uploaded");
    try {
      v1::JobBundle bundle;
      if (!bundle.ParseFromString(impl_.blobs->Read(digest))) return Invalid("bundle is not a JobBundle");
      std::string id = digest.substr(0, 16);
      fs::path dir = impl_.options.state_dir / "jobs" / id;
      auto files = protocol::Materialize(bundle, dir);
      sampling::ParseJobFile(bundle.job_file(), files.job_file.string());
      design::Design design = design::LoadDesign(files.design_file);
      bool created = impl_.store->CreateJob(
          {id, digest, design.name, storage::JobState::kRunning, "", NowMs(), 0});
      if (!created) {
        auto job = impl_.store->FindJob(id);
        if (job && (job->state == storage::JobState::kCancelled || job->state == storage::JobState::kFailed)) {
          impl_.store->SetJobState(id, storage::JobState::kRunning, "", 0);
          std::lock_guard lock(impl_.results_mu);
          impl_.cancelled_jobs.erase(id);
        }
      }
      impl_.Event(id, created ? "submitted" : "resubmitted", "design " + design.name);
      log::Info("job_submitted", {{"job", id}, {"design", design.name}, {"created", created}});
      auto job = impl_.store->FindJob(id);
      if (job && job->state == storage::JobState::kRunning) impl_.StartDriver(id);
      resp->set_job_id(id);
      resp->set_created(created);
      return Status::OK;
    } catch (const std::exception& e) {
      return FromException(e);
    }
  }

  Status GetStatus(ServerContext* ctx, const v1::GetStatusRequest* req, v1::JobStatus* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    auto job = impl_.store->FindJob(req->job_id());
    if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
    *resp = impl_.StatusOf(*job);
    return Status::OK;
  }

  Status Watch(ServerContext* ctx, const v1::GetStatusRequest* req,
               grpc::ServerWriter<v1::JobStatus>* writer) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    std::string last;
    while (!ctx->IsCancelled() && !impl_.stopping) {
      auto job = impl_.store->FindJob(req->job_id());
      if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
      v1::JobStatus status = impl_.StatusOf(*job);
      v1::JobStatus compare = status;
      compare.clear_tasks_per_second();
      std::string bytes = compare.SerializeAsString();
      if (bytes != last) {
        if (!writer->Write(status)) break;
        last = bytes;
      }
      if (Terminal(job->state)) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    if (impl_.stopping) return Status(StatusCode::UNAVAILABLE, "coordinator shutting down");
    return Status::OK;
  }

  Status Cancel(ServerContext* ctx, const v1::CancelRequest* req, v1::JobStatus* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    auto job = impl_.store->FindJob(req->job_id());
    if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
    if (!Terminal(job->state)) {
      impl_.store->SetJobState(job->id, storage::JobState::kCancelled, "", NowMs());
      {
        std::lock_guard lock(impl_.results_mu);
        impl_.cancelled_jobs.insert(job->id);
      }
      impl_.results_cv.notify_all();
      impl_.Event(job->id, "cancelled", "cancelled by an operator");
      log::Info("job_cancelled", {{"job", job->id}});
    }
    *resp = impl_.StatusOf(*impl_.store->FindJob(job->id));
    return Status::OK;
  }

  Status ListJobs(ServerContext* ctx, const v1::ListJobsRequest*, v1::ListJobsResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    for (const auto& job : impl_.store->Jobs()) *resp->add_jobs() = impl_.StatusOf(job);
    return Status::OK;
  }

  Status FetchResult(ServerContext* ctx, const v1::FetchResultRequest* req,
                     v1::FetchResultResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    auto job = impl_.store->FindJob(req->job_id());
    if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
    if (job->state != storage::JobState::kSucceeded)
      return Status(StatusCode::FAILED_PRECONDITION,
                    "job " + job->id + " is " + v1::JobState_Name(static_cast<v1::JobState>(job->state)));
    try {
      for (const auto& [name, digest] : impl_.store->JobOutputs(job->id)) {
        v1::JobOutput* out = resp->add_outputs();
        out->set_name(name);
        out->set_digest(digest);
        out->set_size_bytes(static_cast<std::int64_t>(impl_.blobs->Size(digest)));
      }
    } catch (const std::exception& e) {
      return FromException(e);
    }
    return Status::OK;
  }

 private:
  Coordinator::Impl& impl_;
};

class WorkerServiceImpl final : public v1::WorkerService::Service {
 public:
  explicit WorkerServiceImpl(Coordinator::Impl& impl) : impl_(impl) {}

  // A sample result's point key and subtree records, for the store's
  // subtree tables (JobStore::Subtrees).
  void SubtreesOf(const v1::CompletedTask& c, storage::Completion* done) {
    const v1::SampleResult& sample = c.result().sample();
    if (sample.subtrees_size() == 0) return;
    v1::TaskPayload payload;
    if (auto task = impl_.store->FindTask(c.task_key()); task && payload.ParseFromString(task->payload))
      for (int i = 0; i < payload.point_a().key_size(); ++i)
        done->point_key += (i ? "," : "") + std::to_string(payload.point_a().key(i));
    for (const auto& r : sample.subtrees()) {
      storage::SubtreeUse u;
      u.key = r.key();
      u.topology = r.topology();
      u.op = r.op();
      u.seconds = r.seconds();
      u.measured = !r.from_cache();
      u.bytes = r.bytes();
      u.children.assign(r.children().begin(), r.children().end());
      // A digest the worker uploaded for a result that was never accepted
      // may have been collected since: record only blobs that exist.
      if (!r.blob_digest().empty() && impl_.blobs->Contains(r.blob_digest())) u.blob_digest = r.blob_digest();
      done->subtrees.push_back(std::move(u));
    }
  }

  Status Sync(ServerContext* ctx, const v1::SyncRequest* req, v1::SyncResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    if (req->worker_id().empty()) return Invalid("worker_id is empty");
    const auto& o = impl_.options;
    try {
      std::int64_t now = NowMs();
      if (req->leaving()) {
        {
          std::lock_guard lock(impl_.workers_mu);
          impl_.workers_seen.erase(req->worker_id());
        }
        impl_.store->TouchWorker(req->worker_id(), 0, now);
        if (impl_.store->ForgetAffinity(req->worker_id()) > 0) impl_.SignalWork();
        log::Info("worker_left", {{"worker", req->worker_id()}});
      } else {
        impl_.WorkerAlive(req->worker_id(), req->free_slots() + req->in_flight_lease_ids_size(), now);
      }
      std::vector<storage::Completion> completions;
      std::vector<std::string> known(req->in_flight_lease_ids().begin(), req->in_flight_lease_ids().end());
      for (const auto& c : req->completed()) {
        storage::Completion done;
        done.lease_id = c.lease_id();
        done.task_key = c.task_key();
        done.attempt = c.attempt();
        done.failed = !c.error().empty();
        done.error = c.error();
        if (done.failed) ++impl_.task_failures_total;
        if (done.failed)
          log::Warn("task_failed", {{"task", c.task_key()}, {"worker", req->worker_id()}, {"attempt", c.attempt()},
                                    {"reason", c.error()}});
        done.result = c.result().SerializeAsString();
        done.sample_valid = c.result().has_sample() ? (c.result().sample().valid() ? 1 : 0) : -1;
        if (c.result().has_sample()) SubtreesOf(c, &done);
        // Blobs a result names (a cache plan report, a cutter surface) are
        // referenced from before the result is stored, so the collector
        // never removes one that a replayed driver will read.
        const std::string& named = c.result().has_cache_plan() ? c.result().cache_plan().report_digest()
                                   : c.result().has_swept_volume() ? c.result().swept_volume().surface_blob()
                                                                   : std::string();
        if (!named.empty())
          if (auto task = impl_.store->FindTask(c.task_key())) impl_.store->AddJobBlob(task->job_id, named);
        completions.push_back(std::move(done));
        known.push_back(c.lease_id());
      }
      auto outcomes = impl_.store->Complete(completions, now, o.retry_backoff_ms, o.quarantine_after, QuarantineBytes);
      if (!completions.empty()) impl_.StateWriteSucceeded();
      bool requeued = false;
      std::vector<Coordinator::Impl::Delivery> accepted;
      for (std::size_t i = 0; i < outcomes.size(); ++i) {
        resp->add_acknowledged_lease_ids(completions[i].lease_id);
        switch (outcomes[i]) {
          case storage::CompletionOutcome::kAccepted:
            ++impl_.completed_total;
            impl_.task_seconds.Observe(ResultKind(req->completed(static_cast<int>(i)).result()),
                                       req->completed(static_cast<int>(i)).result().wall_seconds());
            accepted.push_back({&completions[i].task_key, &completions[i].result});
            break;
          case storage::CompletionOutcome::kFenced: ++impl_.fenced_total; break;
          case storage::CompletionOutcome::kDuplicate: ++impl_.duplicate_total; break;
          case storage::CompletionOutcome::kRequeued: requeued = true; break;
          case storage::CompletionOutcome::kQuarantined:
            log::Error("task_quarantined", {{"task", completions[i].task_key}, {"reason", completions[i].error}});
            if (auto task = impl_.store->FindTask(completions[i].task_key))
              impl_.Deliver(completions[i].task_key, task->result);
            break;
          case storage::CompletionOutcome::kUnknown: break;
        }
      }
      if (!accepted.empty()) impl_.Deliver(accepted, req->worker_id());
      if (requeued) impl_.last_retry_ms = now;
      if (impl_.store->ReturnUnknownLeases(req->worker_id(), known) > 0) impl_.SignalWork();
      std::vector<std::string> in_flight(req->in_flight_lease_ids().begin(), req->in_flight_lease_ids().end());
      // Heartbeats extend leases fully; a Sync only tops up those with less
      // than half a lease period left (no write on most Syncs).
      for (const auto& id : impl_.store->ExtendLeases(req->worker_id(), in_flight, now + o.lease_ms, o.lease_ms / 2))
        resp->add_revoked_lease_ids(id);
      resp->set_heartbeat_interval_ms(static_cast<int>(o.heartbeat_ms));
      if (impl_.draining || impl_.stopping || req->leaving()) {
        resp->set_draining(impl_.draining || impl_.stopping);
        return Status::OK;
      }
      int want = std::min(req->free_slots(), o.max_leases_per_sync);
      std::int64_t wait_ms = std::min<std::int64_t>(req->max_wait_ms(), o.max_poll_ms);
      auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(std::max<std::int64_t>(wait_ms, 0));
      std::vector<storage::LeaseGrant> grants;
      while (want > 0) {
        std::uint64_t epoch;
        {
          std::lock_guard lock(impl_.work_mu);
          epoch = impl_.work_epoch;
        }
        grants = impl_.store->GrantLeases(req->worker_id(), want, NowMs(), o.lease_ms);
        // A Sync that reports results may wait too (worker.proto Sync): the
        // results were stored and handed on above.
        if (!grants.empty() || wait_ms <= 0 || impl_.stopping || impl_.draining || ctx->IsCancelled()) break;
        std::unique_lock lock(impl_.work_mu);
        auto slice = std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(250));
        impl_.work_cv.wait_until(lock, slice, [&] { return impl_.work_epoch != epoch || impl_.stopping.load(); });
        if (std::chrono::steady_clock::now() >= until) {
          lock.unlock();
          grants = impl_.store->GrantLeases(req->worker_id(), want, NowMs(), o.lease_ms);
          break;
        }
      }
      for (auto& g : grants) {
        v1::Lease* lease = resp->add_leases();
        lease->set_lease_id(g.lease_id);
        lease->set_task_key(g.task_key);
        lease->set_attempt(g.attempt);
        lease->set_job_id(g.job_id);
        lease->set_job_bundle_digest(g.bundle_digest);
        lease->mutable_payload()->ParseFromString(g.payload);
        lease->set_deadline_unix_ms(g.deadline_ms);
      }
      return Status::OK;
    } catch (const ResourceError& e) {
      impl_.StateWriteFailed("sync", e.what());
      return FromException(e);
    } catch (const std::exception& e) {
      return FromException(e);
    }
  }

  Status FetchSolid(ServerContext* ctx, const v1::FetchSolidRequest* req, v1::FetchSolidResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    if (req->worker_id().empty()) return Invalid("worker_id is empty");
    if (req->solid().point_key_size() == 0) return Invalid("solid.point_key is empty");
    try {
      resp->set_digest(impl_.FetchSolid(*req, ctx));
      return Status::OK;
    } catch (const std::exception& e) {
      return FromException(e);
    }
  }

  Status ShareSolids(ServerContext* ctx, const v1::ShareSolidsRequest* req, v1::ShareSolidsResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    if (req->worker_id().empty()) return Invalid("worker_id is empty");
    try {
      impl_.ShareSolids(*req, resp, ctx);
      return Status::OK;
    } catch (const std::exception& e) {
      return FromException(e);
    }
  }

  Status Heartbeat(ServerContext* ctx, const v1::HeartbeatRequest* req, v1::HeartbeatResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    try {
      std::int64_t now = NowMs();
      // A heartbeat shows the worker alive as a Sync does (a 1-slot worker
      // does not Sync while its task runs).
      impl_.WorkerAlive(req->worker_id(), -1, now);
      std::vector<std::string> ids(req->lease_ids().begin(), req->lease_ids().end());
      for (const auto& id : impl_.store->ExtendLeases(req->worker_id(), ids, now + impl_.options.lease_ms))
        resp->add_revoked_lease_ids(id);
      return Status::OK;
    } catch (const std::exception& e) {
      return FromException(e);
    }
  }

 private:
  Coordinator::Impl& impl_;
};

class BlobServiceImpl final : public v1::BlobService::Service {
 public:
  explicit BlobServiceImpl(Coordinator::Impl& impl) : impl_(impl) {}

  Status FindMissing(ServerContext* ctx, const v1::FindMissingRequest* req,
                     v1::FindMissingResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    for (const auto& d : req->digests())
      if (!impl_.blobs->Contains(d)) resp->add_missing_digests(d);
    return Status::OK;
  }

  Status QueryWriteStatus(ServerContext* ctx, const v1::QueryWriteStatusRequest* req,
                          v1::QueryWriteStatusResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    try {
      resp->set_committed_size(impl_.blobs->CommittedSize(req->digest()));
      // A held blob is fresh again for the collector's cutoff: the caller
      // skips the upload and goes on to name it.
      resp->set_complete(impl_.blobs->Touch(req->digest()));
      return Status::OK;
    } catch (const std::exception& e) {
      return FromException(e);
    }
  }

  Status Write(ServerContext* ctx, grpc::ServerReader<v1::WriteChunk>* reader, v1::WriteResponse* resp) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    v1::WriteChunk chunk;
    std::string digest;
    std::int64_t held = 0;
    try {
      while (reader->Read(&chunk)) {
        if (digest.empty()) digest = chunk.digest();
        if (chunk.digest() != digest) return Invalid("one Write stream carries one blob");
        if (chunk.data().size() > static_cast<std::size_t>(protocol::kBlobChunkBytes))
          return Invalid("chunk larger than 1 MiB");
        if (chunk.size() > (std::int64_t{4} << 30)) return Invalid("blob larger than 4 GiB");
        if (!chunk.data().empty()) held = impl_.blobs->Append(digest, chunk.offset(), chunk.data());
        if (chunk.finish()) {
          try {
            impl_.blobs->Finish(digest);
          } catch (const ResourceError& e) {
            impl_.StateWriteFailed("blob", e.what());
            return Status(StatusCode::RESOURCE_EXHAUSTED, e.what());
          } catch (const InputError& e) {
            return Status(StatusCode::DATA_LOSS, e.what());
          }
          held = impl_.blobs->Size(digest);
        }
      }
    } catch (const ResourceError& e) {
      impl_.StateWriteFailed("blob", e.what());
      return Status(StatusCode::RESOURCE_EXHAUSTED, e.what());
    } catch (const InputError& e) {
      return Status(StatusCode::FAILED_PRECONDITION, e.what());
    }
    resp->set_committed_size(held);
    resp->set_complete(!digest.empty() && impl_.blobs->Contains(digest));
    return Status::OK;
  }

  Status Read(ServerContext* ctx, const v1::ReadRequest* req, grpc::ServerWriter<v1::ReadChunk>* writer) override {
    if (Status s = protocol::CheckToken(*ctx, impl_.options.token); !s.ok()) return s;
    std::int64_t size = impl_.blobs->Size(req->digest());
    if (size < 0) {
      // Someone needed a blob the store does not hold (collected too early,
      // or never uploaded): recorded, so a test or an operator sees it.
      impl_.Event("", "blob_missing", "read of blob " + req->digest() + ", which is not in the store");
      log::Warn("blob_missing", {{"digest", req->digest()}});
      return Status(StatusCode::NOT_FOUND, "no blob " + req->digest());
    }
    try {
      for (std::int64_t offset = req->offset(); offset < size; offset += protocol::kBlobChunkBytes) {
        v1::ReadChunk chunk;
        chunk.set_data(impl_.blobs->Read(req->digest(), offset, protocol::kBlobChunkBytes));
        if (!writer->Write(chunk)) break;
      }
    } catch (const std::exception& e) {
      return FromException(e);
    }
    return Status::OK;
  }

 private:
  Coordinator::Impl& impl_;
};

}  // namespace

Coordinator::Coordinator(CoordinatorOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

Coordinator::~Coordinator() { Shutdown(); }

void Coordinator::Start() {
  Impl& m = *impl_;
  const auto& o = m.options;
  if (o.state_dir.empty()) throw InputError("coordinator: a state directory is required (--state-dir)");
  std::shared_ptr<grpc::ServerCredentials> credentials;
  if (!o.tls_cert.empty() || !o.tls_key.empty()) {
    if (o.tls_cert.empty() || o.tls_key.empty())
      throw InputError("coordinator: TLS needs both a certificate (--tls-cert) and a key (--tls-key)");
    grpc::SslServerCredentialsOptions ssl(o.tls_client_ca.empty()
                                              ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                              : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
    if (!o.tls_client_ca.empty()) ssl.pem_root_certs = protocol::ReadPemFile(o.tls_client_ca, "client CA");
    ssl.pem_key_cert_pairs.push_back({protocol::ReadPemFile(o.tls_key, "TLS key"),
                                      protocol::ReadPemFile(o.tls_cert, "TLS certificate")});
    credentials = grpc::SslServerCredentials(ssl);
  } else {
    if (!protocol::IsLoopback(o.listen) && !o.allow_insecure_network)
      throw InputError("coordinator: refusing plaintext on non-loopback address " + o.listen +
                       " (give --tls-cert/--tls-key, see ops/tls/make-certs.sh)");
    credentials = grpc::InsecureServerCredentials();
  }
  storage::JobStoreOptions store_options;
  store_options.fsync_every_commit = o.fsync_commits;
  store_options.background_checkpoints = true;  // Sweep() checkpoints, off the request path
  m.store = std::make_unique<storage::JobStore>(o.state_dir / "state.db", store_options);
  m.blobs = std::make_unique<storage::BlobStore>(o.state_dir / "blobs");
  m.store->ExtendAllLeases(NowMs() + o.lease_ms);
  m.store->ClearAffinity();  // which workers are alive is not known yet

  protocol::RouteGrpcLogs();
  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(o.listen, credentials, &m.port);
  builder.SetMaxReceiveMessageSize(protocol::kMaxMessageBytes);
  builder.SetMaxSendMessageSize(protocol::kMaxMessageBytes);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 20000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 5000);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 0);
  m.services.push_back(std::make_unique<JobServiceImpl>(m));
  m.services.push_back(std::make_unique<WorkerServiceImpl>(m));
  m.services.push_back(std::make_unique<BlobServiceImpl>(m));
  for (auto& s : m.services) builder.RegisterService(s.get());
  m.server = builder.BuildAndStart();
  if (!m.server || m.port == 0) throw InputError("coordinator: cannot listen on " + o.listen);
  m.server->GetHealthCheckService()->SetServingStatus(true);
  m.started = true;
  m.sweeper = std::thread([&m] { m.Sweep(); });

  if (!o.metrics_listen.empty()) {
    auto colon = o.metrics_listen.rfind(':');
    if (colon == std::string::npos) throw InputError("coordinator: --metrics wants HOST:PORT, got " + o.metrics_listen);
    std::string host = o.metrics_listen.substr(0, colon);
    int port = std::atoi(o.metrics_listen.c_str() + colon + 1);
    m.metrics = std::make_unique<httplib::Server>();
    // Plaintext health for probes that cannot speak the gRPC port's TLS
    // (Kubernetes httpGet): 200 while serving, 503 while draining.
    m.metrics->Get("/healthz", [&m](const httplib::Request&, httplib::Response& res) {
      const bool serving = !m.draining && !m.stopping;
      res.status = serving ? 200 : 503;
      res.set_content(serving ? "serving\n" : "draining\n", "text/plain");
    });
    m.metrics->Get("/metrics", [&m](const httplib::Request&, httplib::Response& res) {
      try {
        res.set_content(m.Metrics(), "text/plain; version=0.0.4");
      } catch (const std::exception& e) {
        res.status = 500;
        res.set_content(e.what(), "text/plain");
      }
    });
    if (!m.metrics->bind_to_port(host, port)) throw InputError("coordinator: cannot listen on " + o.metrics_listen);
    m.metrics_thread = std::thread([&m] { m.metrics->listen_after_bind(); });
  }
  std::int64_t resumed = 0, in_grace = m.store->ActiveLeases();
  for (const auto& job : m.store->Jobs())
    if (job.state == storage::JobState::kRunning) {
      m.StartDriver(job.id);
      ++resumed;
    }
  log::Info("coordinator_started", {{"listen", o.listen}, {"port", m.port}, {"state_dir", o.state_dir.string()},
                                    {"jobs_resumed", resumed}, {"leases_in_grace", in_grace},
                                    {"tls", static_cast<bool>(!o.tls_cert.empty())}});
}

int Coordinator::port() const { return impl_->port; }

void Coordinator::Drain(std::int64_t timeout_ms) {
  Impl& m = *impl_;
  if (!m.started) return;
  m.draining = true;
  m.server->GetHealthCheckService()->SetServingStatus(false);
  m.SignalWork();
  log::Info("drain_started", {{"active_leases", m.store->ActiveLeases()}, {"timeout_ms", timeout_ms}});
  auto started = std::chrono::steady_clock::now();
  auto until = started + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < until && m.store->ActiveLeases() > 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  log::Info("drain_finished", {{"active_leases", m.store->ActiveLeases()},
                               {"waited_ms", std::chrono::duration_cast<std::chrono::milliseconds>(
                                                 std::chrono::steady_clock::now() - started).count()}});
}

void Coordinator::Shutdown() {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.shutdown_mu);
    if (m.shut_down) return;
    m.shut_down = true;
  }
  m.stopping = true;
  m.SignalWork();
  m.results_cv.notify_all();
  if (m.server) m.server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  if (m.sweeper.joinable()) m.sweeper.join();
  if (m.metrics) m.metrics->stop();
  if (m.metrics_thread.joinable()) m.metrics_thread.join();
  std::vector<std::thread> drivers;
  {
    std::lock_guard lock(m.drivers_mu);
    drivers.swap(m.drivers);
  }
  for (auto& t : drivers) t.join();
  if (m.started) log::Info("coordinator_stopped", {{"port", m.port}});
  m.shutdown_cv.notify_all();
}

void Coordinator::Wait() {
  Impl& m = *impl_;
  std::unique_lock lock(m.shutdown_mu);
  m.shutdown_cv.wait(lock, [&] { return m.shut_down; });
}

storage::JobStore& Coordinator::store() { return *impl_->store; }
storage::BlobStore& Coordinator::blobs() { return *impl_->blobs; }

std::vector<std::string> Coordinator::RunTasks(const std::string& job_id,
                                               const std::vector<std::string>& payloads,
                                               const std::vector<std::string>& keys) {
  Impl& m = *impl_;
  if (!m.store->FindJob(job_id))
    m.store->CreateJob({job_id, std::string(64, '0'), "tasks", storage::JobState::kRunning, "", NowMs(), 0});
  std::vector<int> kinds;
  for (const auto& p : payloads) {
    v1::TaskPayload payload;
    payload.ParseFromString(p);
    kinds.push_back(static_cast<int>(payload.kind()));
  }
  try {
    return m.RunTasks(job_id, payloads, keys, kinds);
  } catch (const Stopping&) {
    throw InputError("coordinator: shutting down");
  } catch (const JobCancelled&) {
    throw InputError("job " + job_id + " cancelled");
  }
}

}  // namespace fabatlas::coordinator
