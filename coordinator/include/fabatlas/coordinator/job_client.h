// fabatlas/coordinator/job_client.h — the operator's side of JobService and
// BlobService, used by `fabatlas submit/status/watch/cancel/fetch/jobs/run`.
//
// Every call has a deadline; failures throw fabatlas::InputError with one
// line naming the coordinator and the gRPC status ("cannot reach coordinator
// 127.0.0.1:9: ..." or "...: UNAUTHENTICATED: missing or wrong bearer token").
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fabatlas/protocol/channel.h"
#include "fabatlas/v1/job.grpc.pb.h"

namespace fabatlas::coordinator {

class JobClient {
 public:
  JobClient(std::string target, protocol::ClientSecurity security,
            std::chrono::milliseconds timeout = std::chrono::seconds(20));

  // Uploads bytes as a blob (chunked, resuming what the server holds);
  // returns the digest.
  std::string UploadBlob(const std::string& bytes);
  // Reads a whole blob.
  std::string DownloadBlob(const std::string& digest);

  // Bundles the job file with its design (protocol/job_bundle.h), uploads
  // it and submits; returns the job id.
  std::string Submit(const std::filesystem::path& job_file, bool* created = nullptr);
  v1::JobStatus Status(const std::string& job_id);
  // Calls on_status for every update until the job ends (returns its final
  // status) or on_status returns false. When the stream breaks before the
  // job ends (e.g. the coordinator restarts), watches again with backoff
  // (200 ms doubling to 5 s) and fails only after nothing was heard for
  // reconnect_for; NOT_FOUND and refused credentials fail at once.
  v1::JobStatus Watch(const std::string& job_id, const std::function<bool(const v1::JobStatus&)>& on_status,
                      std::chrono::milliseconds reconnect_for = std::chrono::minutes(5));
  v1::JobStatus Cancel(const std::string& job_id);
  std::vector<v1::JobStatus> List();
  // File name -> bytes of a finished job's outputs.
  std::map<std::string, std::string> Fetch(const std::string& job_id);

 private:
  [[noreturn]] void Fail(const std::string& what, const grpc::Status& status) const;
  // One unary JobService rpc, `call(stub, context, response)`, with this
  // client's security and `timeout`; its response, or Fail(what).
  template <class Response, class Call>
  Response Unary(const std::string& what, std::chrono::milliseconds timeout, Call call) const;
  std::string target_;
  protocol::ClientSecurity security_;
  std::chrono::milliseconds timeout_;
  std::shared_ptr<grpc::Channel> channel_;
};

// "RUNNING" etc.
std::string JobStateName(v1::JobState state);
// One progress line: "job 1a2b… RUNNING  samples 120 (37.5% valid)  tasks 300/410  12.0 tasks/s  ETA 9 s  expiries 2",
// ending "  STALLED: <why>" while the coordinator reports the job stalled.
std::string ProgressLine(const v1::JobStatus& status);

}  // namespace fabatlas::coordinator
