// One job's driver (pipeline::RunJob on the remote executor) and a job's
// status (see coordinator_state.h).
#include <filesystem>

#include "coordinator_state.h"
#include "fabatlas/coordinator/job_eta.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/pipeline/cache_assembly.h"
#include "fabatlas/pipeline/run_job.h"
#include "fabatlas/precompute/form_outputs.h"
#include "remote_executor.h"

namespace fabatlas::coordinator {

namespace fs = std::filesystem;

void Coordinator::Impl::Event(const std::string& job_id, const std::string& kind, const std::string& message) {
  try {
    store->AddEvent({NowMs(), job_id, kind, message});
  } catch (const std::exception&) {
  }
}

v1::CachePlanReport Coordinator::Impl::PlanCacheOnWorkers(const std::string& job_id,
                                                          const std::string& evaluation_digest, int subdivisions,
                                                          const v1::CachePlanInput& input) {
  v1::TaskPayload payload;
  payload.set_kind(v1::TASK_KIND_CACHE_PLAN);
  payload.mutable_cache_plan()->set_input_digest(blobs->Put(input.SerializeAsString()));
  store->AddJobBlob(job_id, payload.cache_plan().input_digest());
  const std::string key = protocol::TaskKey(payload, evaluation_digest, subdivisions);
  Event(job_id, "cache_plan",
        "cache plan task " + key.substr(0, 16) + ": " + std::to_string(input.subtrees_size()) + " subtree records, " +
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

void Coordinator::Impl::Drive(const std::string& job_id) {
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
      Event(job_id, "cache",
            "geometry cache " + run.cache_manifest.strategy + ": " + std::to_string(run.written.cache_entries) +
                " entries, " + std::to_string(run.written.cache_entries_left_out) + " without geometry; " +
                pipeline::ExactText(run.cache_added.exact));
    // A kept subtree whose geometry no worker could give back is missing from
    // the artifact: say so where operators look, not only in the job's events.
    if (run.written.cache_entries_left_out > 0)
      log::Warn(
          "cache_entries_left_out",
          {{"job", job_id}, {"entries", run.written.cache_entries}, {"left_out", run.written.cache_entries_left_out}});
    for (const auto& entry : fs::directory_iterator(run_options.out_dir)) {
      if (!entry.is_regular_file()) continue;
      std::string name = entry.path().filename().string();
      if (name.find(".tmp") != std::string::npos) continue;
      store->PutJobOutput(job_id, name, blobs->PutFile(entry.path()));
    }
    store->SetJobState(job_id, storage::JobState::kSucceeded, "", NowMs());
    Event(job_id, "succeeded", precompute::Table3Row(loaded.design, run.sampling.statistics));
    log::Info("job_succeeded",
              {{"job", job_id},
               {"design", loaded.design.name},
               {"samples", run.sampling.statistics.samples},
               {"valid_samples", run.sampling.statistics.valid_samples},
               {"publish_seconds",
                std::chrono::duration<double>(std::chrono::steady_clock::now() - executor.publish_started()).count()}});
    // The published artifact holds what the cache plan kept: the job's
    // geometry blobs go now. A collection that cannot write (an I/O error)
    // is the sweeper's to retry, not a reason to run the published job again.
    try {
      CollectBlobs("job " + job_id + " published");
    } catch (const ResourceError& e) {
      StateWriteFailed("blob collection", e.what());
    }
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

void Coordinator::Impl::ForgetSchedule(const std::string& job_id) {
  std::lock_guard lock(schedule_mu);
  schedules.erase(job_id);
}

void Coordinator::Impl::StartDriver(const std::string& job_id) {
  std::lock_guard lock(drivers_mu);
  if (stopping || !running_drivers.insert(job_id).second) return;
  drivers.emplace_back([this, job_id] { Drive(job_id); });
}

v1::JobStatus Coordinator::Impl::StatusOf(const storage::JobRecord& job) {
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
      in.running_done.cpu_seconds = it->second.work.cpu_seconds - it->second.work_at_batch_start.cpu_seconds;
      in.running_done.tasks = it->second.work.tasks - it->second.work_at_batch_start.tasks;
      for (const auto& [when, total] : it->second.work_history) {
        in.progress.push_back(total);
        in.progress.back().seconds_ago = std::chrono::duration<double>(steady_now - when).count();
      }
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

}  // namespace fabatlas::coordinator
