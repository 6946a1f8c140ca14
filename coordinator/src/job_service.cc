// JobService (job.proto): submit, status, watch, cancel, list, fetch.
#include <thread>

#include "fabatlas/design/design.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/v1/job.grpc.pb.h"
#include "coordinator_state.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "services.h"

namespace fabatlas::coordinator {

namespace fs = std::filesystem;

namespace {

class JobServiceImpl final : public ServiceOn<v1::JobService::Service> {
 public:
  using ServiceOn::ServiceOn;

  Status Submit(ServerContext* ctx, const v1::SubmitRequest* req, v1::SubmitResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    const std::string& digest = req->bundle_digest();
    if (!storage::IsDigest(digest)) return Invalid("bundle_digest is not a SHA-256 hex digest");
    if (!impl_.blobs->Contains(digest))
      return Status(StatusCode::FAILED_PRECONDITION, "bundle " + digest + " not uploaded");
    return Guarded([&]() -> Status {
      v1::JobBundle bundle;
      if (!bundle.ParseFromString(impl_.blobs->Read(digest))) return Invalid("bundle is not a JobBundle");
      std::string id = digest.substr(0, 16);
      fs::path dir = impl_.options.state_dir / "jobs" / id;
      auto files = protocol::Materialize(bundle, dir);
      sampling::ParseJobFile(bundle.job_file(), files.job_file.string());
      design::Design design = design::LoadDesign(files.design_file);
      bool created = impl_.store->CreateJob({id, digest, design.name, storage::JobState::kRunning, "", NowMs(), 0});
      if (!created) {
        auto job = impl_.store->FindJob(id);
        if (job && (job->state == storage::JobState::kCancelled || job->state == storage::JobState::kFailed)) {
          impl_.store->SetJobState(id, storage::JobState::kRunning, "", 0);
          std::lock_guard lock(impl_.results_mu);
          impl_.cancelled_jobs.erase(id);
        }
      }
      // The client is told the job exists: that survives a power loss even
      // without --fsync-commits (JobStore::Sync).
      impl_.store->Sync();
      impl_.Event(id, created ? "submitted" : "resubmitted", "design " + design.name);
      log::Info("job_submitted", {{"job", id}, {"design", design.name}, {"created", created}});
      auto job = impl_.store->FindJob(id);
      if (job && job->state == storage::JobState::kRunning) impl_.StartDriver(id);
      resp->set_job_id(id);
      resp->set_created(created);
      return Status::OK;
    });
  }

  Status GetStatus(ServerContext* ctx, const v1::GetStatusRequest* req, v1::JobStatus* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    auto job = impl_.store->FindJob(req->job_id());
    if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
    *resp = impl_.StatusOf(*job);
    return Status::OK;
  }

  Status Watch(ServerContext* ctx, const v1::GetStatusRequest* req,
               grpc::ServerWriter<v1::JobStatus>* writer) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
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
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    auto job = impl_.store->FindJob(req->job_id());
    if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
    if (!Terminal(job->state)) {
      impl_.store->SetJobState(job->id, storage::JobState::kCancelled, "", NowMs());
      impl_.store->Sync();  // an acknowledged cancel survives a power loss
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
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    for (const auto& job : impl_.store->Jobs()) *resp->add_jobs() = impl_.StatusOf(job);
    return Status::OK;
  }

  Status FetchResult(ServerContext* ctx, const v1::FetchResultRequest* req, v1::FetchResultResponse* resp) override {
    if (Status s = Authorise(*ctx); !s.ok()) return s;
    auto job = impl_.store->FindJob(req->job_id());
    if (!job) return Status(StatusCode::NOT_FOUND, "no job " + req->job_id());
    if (job->state != storage::JobState::kSucceeded)
      return Status(StatusCode::FAILED_PRECONDITION,
                    "job " + job->id + " is " + v1::JobState_Name(static_cast<v1::JobState>(job->state)));
    return Guarded([&]() -> Status {
      for (const auto& [name, digest] : impl_.store->JobOutputs(job->id)) {
        v1::JobOutput* out = resp->add_outputs();
        out->set_name(name);
        out->set_digest(digest);
        out->set_size_bytes(static_cast<std::int64_t>(impl_.blobs->Size(digest)));
      }
      return Status::OK;
    });
  }
};

}  // namespace

std::unique_ptr<grpc::Service> MakeJobService(Coordinator::Impl& impl) {
  return std::make_unique<JobServiceImpl>(impl);
}

}  // namespace fabatlas::coordinator
