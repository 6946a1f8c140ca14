// The operator's client (see job_client.h).
#include "fabatlas/coordinator/job_client.h"

#include <algorithm>
#include <cstdio>
#include <thread>

#include "fabatlas/error.h"
#include "fabatlas/protocol/blob_transfer.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/sha256.h"
#include "fabatlas/v1/blob.grpc.pb.h"

namespace fabatlas::coordinator {

JobClient::JobClient(std::string target, protocol::ClientSecurity security, std::chrono::milliseconds timeout)
    : target_(std::move(target)),
      security_(std::move(security)),
      timeout_(timeout),
      channel_(protocol::MakeChannel(target_, security_)) {}

void JobClient::Fail(const std::string& what, const grpc::Status& status) const {
  std::string reason = status.error_message();
  for (char& c : reason)
    if (c == '\n') c = ' ';
  if (status.error_code() == grpc::StatusCode::UNAVAILABLE ||
      status.error_code() == grpc::StatusCode::DEADLINE_EXCEEDED)
    throw InputError("cannot reach coordinator " + target_ + " (" + what + "): " + reason);
  static const char* names[] = {
      "OK",        "CANCELLED",      "UNKNOWN",           "INVALID_ARGUMENT",   "DEADLINE_EXCEEDED",
      "NOT_FOUND", "ALREADY_EXISTS", "PERMISSION_DENIED", "RESOURCE_EXHAUSTED", "FAILED_PRECONDITION",
      "ABORTED",   "OUT_OF_RANGE",   "UNIMPLEMENTED",     "INTERNAL",           "UNAVAILABLE",
      "DATA_LOSS", "UNAUTHENTICATED"};
  int code = static_cast<int>(status.error_code());
  std::string name = code >= 0 && code <= 16 ? names[code] : std::to_string(code);
  throw InputError("coordinator " + target_ + " (" + what + "): " + name + ": " + reason);
}

template <class Response, class Call>
Response JobClient::Unary(const std::string& what, std::chrono::milliseconds timeout, Call call) const {
  auto stub = v1::JobService::NewStub(channel_);
  grpc::ClientContext ctx;
  protocol::Prepare(ctx, security_, timeout);
  Response resp;
  grpc::Status s = call(*stub, &ctx, &resp);
  if (!s.ok()) Fail(what, s);
  return resp;
}

std::string JobClient::UploadBlob(const std::string& bytes) {
  auto stub = v1::BlobService::NewStub(channel_);
  std::string digest;
  grpc::Status s = protocol::UploadBlob(*stub, security_, bytes, timeout_, &digest);
  if (!s.ok()) Fail("blob upload", s);
  return digest;
}

std::string JobClient::DownloadBlob(const std::string& digest) {
  auto stub = v1::BlobService::NewStub(channel_);
  std::string out;
  grpc::Status s = protocol::DownloadBlob(*stub, security_, digest, timeout_ * 10, &out);
  if (s.error_code() == grpc::StatusCode::DATA_LOSS) throw InputError(s.error_message());
  if (!s.ok()) Fail("blob download", s);
  return out;
}

std::string JobClient::Submit(const std::filesystem::path& job_file, bool* created) {
  v1::JobBundle bundle = protocol::MakeJobBundle(job_file);
  std::string digest = UploadBlob(protocol::BundleBytes(bundle));
  v1::SubmitRequest req;
  req.set_bundle_digest(digest);
  const auto resp = Unary<v1::SubmitResponse>("submit " + job_file.string(), timeout_,
                                              [&](auto& stub, auto* ctx, auto* r) { return stub.Submit(ctx, req, r); });
  if (created) *created = resp.created();
  return resp.job_id();
}

v1::JobStatus JobClient::Status(const std::string& job_id) {
  v1::GetStatusRequest req;
  req.set_job_id(job_id);
  return Unary<v1::JobStatus>("status " + job_id, timeout_,
                              [&](auto& stub, auto* ctx, auto* r) { return stub.GetStatus(ctx, req, r); });
}

v1::JobStatus JobClient::Watch(const std::string& job_id, const std::function<bool(const v1::JobStatus&)>& on_status,
                               std::chrono::milliseconds reconnect_for) {
  auto stub = v1::JobService::NewStub(channel_);
  v1::GetStatusRequest req;
  req.set_job_id(job_id);
  v1::JobStatus last;
  auto last_heard = std::chrono::steady_clock::now();
  std::chrono::milliseconds backoff(200);
  while (true) {
    grpc::ClientContext ctx;
    protocol::Prepare(ctx, security_, std::chrono::hours(24 * 30));
    auto reader = stub->Watch(&ctx, req);
    v1::JobStatus status;
    bool stopped = false;
    while (reader->Read(&status)) {
      last = status;
      last_heard = std::chrono::steady_clock::now();
      backoff = std::chrono::milliseconds(200);
      if (!on_status(status)) {
        stopped = true;
        ctx.TryCancel();
        break;
      }
    }
    grpc::Status s = reader->Finish();
    if (stopped || last.state() >= v1::JOB_STATE_SUCCEEDED) return last;
    // The stream broke before the job ended (coordinator restarted, network
    // blip): watch again with backoff; answers that cannot change by waiting
    // end the watch at once.
    switch (s.error_code()) {
      case grpc::StatusCode::NOT_FOUND:
      case grpc::StatusCode::INVALID_ARGUMENT:
      case grpc::StatusCode::UNAUTHENTICATED:
      case grpc::StatusCode::PERMISSION_DENIED:
      case grpc::StatusCode::UNIMPLEMENTED:
        Fail("watch " + job_id, s);
      default:
        break;
    }
    if (std::chrono::steady_clock::now() - last_heard > reconnect_for) {
      if (s.ok()) s = grpc::Status(grpc::StatusCode::UNAVAILABLE, "the watch stream ended before the job did");
      Fail("watch " + job_id, s);
    }
    std::this_thread::sleep_for(backoff);
    backoff = std::min(backoff * 2, std::chrono::milliseconds(5000));
  }
}

v1::JobStatus JobClient::Cancel(const std::string& job_id) {
  v1::CancelRequest req;
  req.set_job_id(job_id);
  return Unary<v1::JobStatus>("cancel " + job_id, timeout_,
                              [&](auto& stub, auto* ctx, auto* r) { return stub.Cancel(ctx, req, r); });
}

std::vector<v1::JobStatus> JobClient::List() {
  const auto resp = Unary<v1::ListJobsResponse>("list jobs", timeout_, [&](auto& stub, auto* ctx, auto* r) {
    return stub.ListJobs(ctx, v1::ListJobsRequest(), r);
  });
  return {resp.jobs().begin(), resp.jobs().end()};
}

std::map<std::string, std::string> JobClient::Fetch(const std::string& job_id) {
  v1::FetchResultRequest req;
  req.set_job_id(job_id);
  const auto resp = Unary<v1::FetchResultResponse>(
      "fetch " + job_id, timeout_ * 5, [&](auto& stub, auto* ctx, auto* r) { return stub.FetchResult(ctx, req, r); });
  std::map<std::string, std::string> files;
  for (const auto& out : resp.outputs()) files[out.name()] = DownloadBlob(out.digest());
  return files;
}

std::string JobStateName(v1::JobState state) {
  std::string name = v1::JobState_Name(state);
  return name.rfind("JOB_STATE_", 0) == 0 ? name.substr(10) : name;
}

std::string ProgressLine(const v1::JobStatus& s) {
  char buffer[512];
  double valid = s.samples_done() ? 100.0 * s.samples_valid() / s.samples_done() : 0.0;
  std::string eta = "-";
  std::int64_t left = s.tasks_queued() + s.tasks_leased();
  if (s.eta_seconds() > 0)  // the whole job, from the adaptive schedule
    eta = std::to_string(static_cast<long long>(s.eta_seconds() + 0.5)) + " s";
  else if (s.tasks_per_second() > 0 && left > 0)
    eta = std::to_string(static_cast<long long>(left / s.tasks_per_second() + 0.5)) + " s";
  std::snprintf(buffer, sizeof buffer,
                "job %s %-9s samples %lld (%.1f%% valid)  tasks %lld/%lld  %.1f tasks/s  ETA %s  "
                "failures: %lld expired, %lld quarantined",
                s.job_id().c_str(), JobStateName(s.state()).c_str(), static_cast<long long>(s.samples_done()), valid,
                static_cast<long long>(s.tasks_done()), static_cast<long long>(s.tasks_total()), s.tasks_per_second(),
                eta.c_str(), static_cast<long long>(s.lease_expiries()), static_cast<long long>(s.tasks_quarantined()));
  if (!s.stalled_reason().empty()) return std::string(buffer) + "  STALLED: " + s.stalled_reason();
  return buffer;
}

}  // namespace fabatlas::coordinator
