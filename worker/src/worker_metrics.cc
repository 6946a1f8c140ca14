// The worker's /metrics and /healthz (see worker_process.h).
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "worker_process.h"

namespace fabatlas::worker {

void Worker::ServeMetrics() {
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

std::string Worker::MetricsPage() {
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
    m.Counter("fabatlas_worker_tasks_total", "Tasks this worker ran, by kind.", static_cast<double>(n),
              {{"kind", kind}});
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
  m.Gauge("fabatlas_worker_subtree_cache_bytes", "Subtree cache of the design evaluators.",
          static_cast<double>(subtrees));
  m.Gauge("fabatlas_worker_memory_budget_bytes", "The resident budget (--memory-mb).",
          static_cast<double>(static_cast<std::int64_t>(o_.memory_mb) << 20));
  m.Gauge("process_resident_memory_bytes", "Resident memory of the worker.",
          static_cast<double>(log::ResidentMemoryBytes()));
  m.Gauge("fabatlas_worker_slots", "Tasks this worker runs at once (--slots).", o_.slots);
  m.Gauge("fabatlas_worker_running_tasks", "Tasks running now.", running);
  m.Gauge("fabatlas_worker_connected", "1 once the coordinator has answered.", connected ? 1 : 0);
  return m.text();
}

}  // namespace fabatlas::worker
