// WorkerService (worker.proto): Sync (results in, leases out), FetchSolid,
// ShareSolids, Heartbeat.
#include <algorithm>

#include "fabatlas/protocol/channel.h"
#include "fabatlas/v1/worker.grpc.pb.h"
#include "coordinator_state.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/sampling/point_key_text.h"
#include "services.h"

namespace fabatlas::coordinator {

namespace {

class WorkerServiceImpl final : public ServiceOn<v1::WorkerService::Service> {
 public:
  using ServiceOn::ServiceOn;

  // A sample result's point key and subtree records, for the store's
  // subtree tables (JobStore::Subtrees).
  void SubtreesOf(const v1::CompletedTask& c, storage::Completion* done) {
    const v1::SampleResult& sample = c.result().sample();
    if (sample.subtrees_size() == 0) return;
    v1::TaskPayload payload;
    if (auto task = impl_.store->FindTask(c.task_key()); task && payload.ParseFromString(task->payload))
      done->point_key = sampling::PointKeyText({payload.point_a().key().begin(), payload.point_a().key().end()});
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
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    if (req->worker_id().empty()) return Invalid("worker_id is empty");
    const auto& o = impl_.options;
    const auto failed_write = [&](const ResourceError& e) { impl_.StateWriteFailed("sync", e.what()); };
    return Guarded(
        [&]() -> Status {
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
          storage::WorkerSync sync;
          sync.worker_id = req->worker_id();
          sync.in_flight.assign(req->in_flight_lease_ids().begin(), req->in_flight_lease_ids().end());
          sync.now_ms = now;
          sync.lease_ms = o.lease_ms;
          sync.retry_backoff_ms = o.retry_backoff_ms;
          sync.quarantine_after = o.quarantine_after;
          sync.quarantine_result = QuarantineBytes;
          std::vector<storage::Completion>& completions = sync.completions;
          for (const auto& c : req->completed()) {
            storage::Completion done;
            done.lease_id = c.lease_id();
            done.task_key = c.task_key();
            done.attempt = c.attempt();
            done.failed = !c.error().empty();
            done.error = c.error();
            if (done.failed) ++impl_.task_failures_total;
            if (done.failed)
              log::Warn("task_failed", {{"task", c.task_key()},
                                        {"worker", req->worker_id()},
                                        {"attempt", c.attempt()},
                                        {"reason", c.error()}});
            done.result = c.result().SerializeAsString();
            done.sample_valid = c.result().has_sample() ? (c.result().sample().valid() ? 1 : 0) : -1;
            if (c.result().has_sample()) SubtreesOf(c, &done);
            // Blobs a result names (a cache plan report, a cutter surface) are
            // referenced from before the result is stored, so the collector
            // never removes one that a replayed driver will read.
            const std::string& named = c.result().has_cache_plan()     ? c.result().cache_plan().report_digest()
                                       : c.result().has_swept_volume() ? c.result().swept_volume().surface_blob()
                                                                       : std::string();
            if (!named.empty())
              if (auto task = impl_.store->FindTask(c.task_key())) impl_.store->AddJobBlob(task->job_id, named);
            completions.push_back(std::move(done));
          }
          const bool granting = !(impl_.draining || impl_.stopping || req->leaving());
          sync.want = granting ? std::min(req->free_slots(), o.max_leases_per_sync) : 0;
          if (req->has_idle_slots()) sync.steal = std::max(0, req->idle_slots());
          std::uint64_t epoch;  // new work since this is not waited for below
          {
            std::lock_guard lock(impl_.work_mu);
            epoch = impl_.work_epoch;
          }
          // Results, lease bookkeeping and the first grants in one commit.
          storage::WorkerSyncOutcome synced = impl_.store->SyncWorker(sync);
          if (!completions.empty()) impl_.StateWriteSucceeded();
          const auto& outcomes = synced.outcomes;
          bool requeued = false;
          std::vector<Coordinator::Impl::Delivery> accepted;
          for (std::size_t i = 0; i < outcomes.size(); ++i) {
            resp->add_acknowledged_lease_ids(completions[i].lease_id);
            switch (outcomes[i]) {
              case storage::CompletionOutcome::kAccepted:
                ++impl_.completed_total;
                impl_.task_seconds.Observe(ResultKind(req->completed(static_cast<int>(i)).result()),
                                           req->completed(static_cast<int>(i)).result().wall_seconds());
                accepted.push_back({&completions[i].task_key, &completions[i].result,
                                    req->completed(static_cast<int>(i)).result().cpu_seconds()});
                break;
              case storage::CompletionOutcome::kFenced:
                ++impl_.fenced_total;
                break;
              case storage::CompletionOutcome::kDuplicate:
                ++impl_.duplicate_total;
                break;
              case storage::CompletionOutcome::kRequeued:
                requeued = true;
                break;
              case storage::CompletionOutcome::kQuarantined:
                log::Error("task_quarantined", {{"task", completions[i].task_key}, {"reason", completions[i].error}});
                if (auto task = impl_.store->FindTask(completions[i].task_key))
                  impl_.Deliver(completions[i].task_key, task->result);
                break;
              case storage::CompletionOutcome::kUnknown:
                break;
            }
          }
          if (!accepted.empty()) impl_.Deliver(accepted, req->worker_id());
          if (requeued) impl_.last_retry_ms = now;
          if (synced.returned > 0) impl_.SignalWork();
          for (const auto& id : synced.revoked) resp->add_revoked_lease_ids(id);
          resp->set_heartbeat_interval_ms(static_cast<int>(o.heartbeat_ms));
          if (!granting) {
            resp->set_draining(impl_.draining || impl_.stopping);
            return Status::OK;
          }
          int want = sync.want;
          std::int64_t wait_ms = std::min<std::int64_t>(req->max_wait_ms(), o.max_poll_ms);
          auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(std::max<std::int64_t>(wait_ms, 0));
          std::vector<storage::LeaseGrant>& grants = synced.grants;
          // Nothing to grant yet: a long poll waits for new work (a Sync that
          // reports results may wait too, worker.proto Sync: they were stored
          // and handed on above).
          while (want > 0 && grants.empty() && wait_ms > 0 && !impl_.stopping && !impl_.draining &&
                 !ctx->IsCancelled()) {
            {
              std::unique_lock lock(impl_.work_mu);
              auto slice = std::min(until, std::chrono::steady_clock::now() + std::chrono::milliseconds(250));
              impl_.work_cv.wait_until(lock, slice, [&] { return impl_.work_epoch != epoch || impl_.stopping.load(); });
              epoch = impl_.work_epoch;
            }
            grants = impl_.store->GrantLeases(req->worker_id(), want, NowMs(), o.lease_ms, sync.steal);
            if (std::chrono::steady_clock::now() >= until) break;
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
        },
        failed_write);
  }

  Status FetchSolid(ServerContext* ctx, const v1::FetchSolidRequest* req, v1::FetchSolidResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    if (req->worker_id().empty()) return Invalid("worker_id is empty");
    if (req->solid().point_key_size() == 0) return Invalid("solid.point_key is empty");
    return Guarded([&]() -> Status {
      impl_.FetchSolid(*req, resp, ctx);
      return Status::OK;
    });
  }

  Status ShareSolids(ServerContext* ctx, const v1::ShareSolidsRequest* req, v1::ShareSolidsResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    if (req->worker_id().empty()) return Invalid("worker_id is empty");
    return Guarded([&]() -> Status {
      impl_.ShareSolids(*req, resp, ctx);
      return Status::OK;
    });
  }

  Status Heartbeat(ServerContext* ctx, const v1::HeartbeatRequest* req, v1::HeartbeatResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    return Guarded([&]() -> Status {
      std::int64_t now = NowMs();
      // A heartbeat shows the worker alive as a Sync does (a 1-slot worker
      // does not Sync while its task runs).
      impl_.WorkerAlive(req->worker_id(), -1, now);
      std::vector<std::string> ids(req->lease_ids().begin(), req->lease_ids().end());
      for (const auto& id : impl_.store->ExtendLeases(req->worker_id(), ids, now + impl_.options.lease_ms))
        resp->add_revoked_lease_ids(id);
      return Status::OK;
    });
  }
};

}  // namespace

std::unique_ptr<grpc::Service> MakeWorkerService(Coordinator::Impl& impl) {
  return std::make_unique<WorkerServiceImpl>(impl);
}

}  // namespace fabatlas::coordinator
