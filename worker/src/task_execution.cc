// One lease's task on the worker (see worker_process.h): the job's context,
// sample / ΔG / swept-volume / cache-plan tasks, blob upload and download.
#include <csignal>
#include <ctime>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/protocol/blob_transfer.h"
#include "fabatlas/protocol/cache_plan.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/protocol/tasks.h"
#include "worker_process.h"

namespace fabatlas::worker {

using Clock = std::chrono::steady_clock;

namespace {

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

}  // namespace

std::shared_ptr<JobContext> Worker::ContextFor(const v1::Lease& lease) {
  std::lock_guard lock(jobs_mu_);
  auto& ctx = jobs_[lease.job_bundle_digest()];
  if (ctx && ctx->evaluator) return ctx;
  try {
    std::string bytes;
    grpc::Status s =
        protocol::DownloadBlob(*blob_stub_, o_.security, lease.job_bundle_digest(), std::chrono::seconds(120), &bytes);
    if (!s.ok()) throw InputError("cannot fetch job bundle: " + s.error_message());
    v1::JobBundle bundle;
    if (!bundle.ParseFromString(bytes)) throw InputError("job bundle does not parse");
    ctx = LoadJobContext(bundle, o_.cache_dir / lease.job_bundle_digest().substr(0, 16), o_.memory_mb,
                         [this](const std::string& blob) { return Upload(blob); });
  } catch (const std::exception& e) {
    auto failed = std::make_shared<JobContext>();
    failed->error = e.what();
    ctx.reset();  // try again on the next lease
    return failed;
  }
  return ctx;
}

v1::CompletedTask Worker::Execute(const v1::Lease& lease) {
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

std::string Worker::Upload(const std::string& bytes) {
  std::string digest;
  grpc::Status s = protocol::UploadBlob(*blob_stub_, o_.security, bytes, std::chrono::seconds(30), &digest);
  if (!s.ok()) return "";
  ++blobs_uploaded_;
  return digest;
}

v1::TaskResult Worker::PlanCache(const v1::CachePlanTask& task) {
  std::string bytes;
  grpc::Status s =
      protocol::DownloadBlob(*blob_stub_, o_.security, task.input_digest(), std::chrono::seconds(300), &bytes);
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

v1::TaskResult Worker::EvaluateSample(JobContext& ctx, const sampling::SamplePoint& point) {
  design::SampleResult r = ctx.evaluator->Evaluate(point);
  UploadReusedSubtrees(ctx, r.subtrees);
  sampling::SampleOutcome outcome;
  outcome.valid = r.valid;
  outcome.failure_type = r.failure;
  outcome.properties = r.properties;
  v1::TaskResult result = protocol::SampleResultOf(outcome);
  v1::SampleResult* sample = result.mutable_sample();
  std::lock_guard lock(ctx.mu);
  for (const std::string& w : r.warnings)
    if (ctx.logged_warnings.size() < 1000 && ctx.logged_warnings.insert(w).second)
      log::Warn("sample_warning", {{"warning", w}});
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
    out->set_blob_digest(ctx.subtree_uploads.DigestOf(rec.key));
  }
  return result;
}

geometry::Solid Worker::SolidOf(JobContext& ctx, const v1::Lease& lease, const sampling::SamplePoint& point,
                                std::string digest, const std::string& holder) {
  if (auto solid = ctx.evaluator->RememberedSolid(point.key)) return *solid;
  if (auto blob = ctx.shelf.Get(point.key)) {
    geometry::Solid solid = protocol::SolidOfBlob(*blob);
    ctx.evaluator->Remember(point.key, solid);
    return solid;
  }
  std::string bytes;  // the solid's blob, sent inline by its holder or downloaded
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
    if (stub_->FetchSolid(&call, req, &resp).ok()) {
      digest = resp.digest();
      bytes = std::move(*resp.mutable_blob());
    }
  }
  if (bytes.empty() && !digest.empty() &&
      !protocol::DownloadBlob(*blob_stub_, o_.security, digest, std::chrono::seconds(60), &bytes).ok())
    bytes.clear();
  if (!bytes.empty()) {
    try {
      geometry::Solid solid = protocol::SolidOfBlob(bytes);
      ctx.evaluator->Remember(point.key, solid);
      ctx.shelf.Put(point.key, std::move(bytes));
      ++solids_downloaded_;
      return solid;
    } catch (const InputError&) {
    }
  }
  ++samples_reevaluated_;
  return ctx.evaluator->SolidOf(point);
}

}  // namespace fabatlas::worker
