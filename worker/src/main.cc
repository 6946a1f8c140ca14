// fabatlas-worker — one process per worker machine (worker.h).
//   fabatlas-worker --coordinator HOST:PORT [--slots N] [--threads T] [--memory-mb M] [--token T | --token-file F]
//                   [--tls-ca ca.pem [--tls-cert c.pem --tls-key c.key]]
// SIGTERM / SIGINT: finish the running tasks, report them, return the leases
// not started, exit 0. Exit 2 with one line on stderr when the coordinator
// cannot be reached or refuses the worker.
#include <CLI/CLI.hpp>

#include <atomic>
#include <csignal>
#include <iostream>
#include <thread>

#include "fabatlas/error.h"
#include "fabatlas/log/log_flags.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/protocol/tasks.h"
#include "fabatlas/version.h"
#include "fabatlas/worker/worker.h"

int main(int argc, char** argv) {
  CLI::App app{"fabatlas worker: runs sampling tasks leased by a coordinator"};
  app.option_defaults()->always_capture_default();  // --help shows the defaults
  fabatlas::worker::WorkerOptions o;
  std::string token_file;
  double connect_timeout = 30;
  fabatlas::log::LogFlags log_flags;
  app.set_version_flag("--version", std::string("fabatlas-worker ") + fabatlas::kVersion + " (task code " +
                                        fabatlas::protocol::kCodeVersion + ", protocol fabatlas.v1)");
  app.add_option("--coordinator", o.coordinator, "coordinator HOST:PORT")->required();
  app.add_option("--slots", o.slots, "tasks run at once (about one per core)");
  app.add_option("--threads", o.threads,
                 "threads the evaluations may keep busy in total (default: --slots, one per slot)");
  app.add_option("--memory-mb", o.memory_mb,
                 "resident memory budget of the worker process, MiB (default 1024, at least 256): solids kept "
                 "for ΔG and the subtree cache are bounded to fit");
  app.add_option("--token", o.security.token, "bearer token");
  app.add_option("--token-file", token_file, "file holding the bearer token");
  app.add_option("--tls-ca", o.security.tls_ca, "CA certificate of the deployment (PEM); enables TLS");
  app.add_option("--tls-cert", o.security.tls_cert, "client certificate (PEM)");
  app.add_option("--tls-key", o.security.tls_key, "client key (PEM)");
  app.add_option("--cache-dir", o.cache_dir, "where job bundles are unpacked");
  app.add_option("--id", o.worker_id, "worker id (default host-pid-time)");
  app.add_option("--connect-timeout", connect_timeout, "seconds to wait for the first answer");
  app.add_option("--metrics", o.metrics_listen,
                 "serve /metrics (Prometheus) and /healthz on HOST:PORT, plaintext (default: off)");
  log_flags.Add(app);
  CLI11_PARSE(app, argc, argv);
  o.connect_timeout_ms = static_cast<std::int64_t>(connect_timeout * 1000);

  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  static std::atomic<bool> stop{false};
  std::thread([signals]() mutable {
    int sig = 0;
    sigwait(&signals, &sig);
    stop = true;
  }).detach();
  try {
    log_flags.Apply();
    if (!token_file.empty()) o.security.token = fabatlas::protocol::ReadTokenFile(token_file);
    auto summary = fabatlas::worker::RunWorker(o, stop);
    fabatlas::log::Info("worker_exit", {{"tasks_run", summary.tasks_run},
                                        {"results_acknowledged", summary.results_acknowledged},
                                        {"blobs_uploaded", summary.blobs_uploaded},
                                        {"solids_downloaded", summary.solids_downloaded},
                                        {"samples_reevaluated", summary.samples_reevaluated},
                                        {"solids_shared", summary.solids_shared}});
    return 0;
  } catch (const fabatlas::InputError& e) {
    return log_flags.BadInputExit("fabatlas-worker", "worker_exit", e);
  }
}
