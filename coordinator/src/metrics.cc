// The coordinator's /metrics (Prometheus text; see coordinator_state.h).
#include <sys/statvfs.h>

#include <cctype>

#include "coordinator_state.h"
#include "fabatlas/log/log.h"

namespace fabatlas::coordinator {

std::string Coordinator::Impl::Metrics() {
  log::MetricsText m;
  storage::TaskCounts c = store->CountTasks("");
  std::int64_t now = NowMs();
  for (const auto& [state, n] :
       {std::pair{"queued", c.queued}, {"leased", c.leased}, {"done", c.done}, {"quarantined", c.quarantined}})
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
    for (const auto& [state, n] :
         {std::pair{"queued", jc.queued}, {"leased", jc.leased}, {"done", jc.done}, {"quarantined", jc.quarantined}}) {
      log::Labels l = id;
      l.emplace_back("state", state);
      m.Gauge("fabatlas_job_tasks", "Tasks of a running job by state.", static_cast<double>(n), l);
    }
    m.Gauge("fabatlas_job_samples", "Samples evaluated so far in a running job.", static_cast<double>(jc.samples_done),
            id);
    m.Gauge("fabatlas_job_valid_samples", "Valid samples so far in a running job.",
            static_cast<double>(jc.samples_valid), id);
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

}  // namespace fabatlas::coordinator
