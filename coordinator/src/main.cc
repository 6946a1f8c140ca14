// fabatlas-coordinator — the cluster's coordinator process (coordinator.h).
//   fabatlas-coordinator --listen 0.0.0.0:7450 --state-dir /var/lib/fabatlas
//       --tls-cert server.pem --tls-key server.key [--token-file F] [--metrics 0.0.0.0:9450]
// SIGTERM / SIGINT: drain (no new leases, wait up to --drain-seconds for
// running leases), then stop; running jobs resume on the next start.
// Exit status: 0 after a signal; 2 (one line) for bad input or
// configuration, a state directory another process holds or a state.db
// that is not a job store; 75 (one line) when the state directory cannot be
// read or written at start (an I/O error, a full disk), which may pass.
#include <CLI/CLI.hpp>

#include <csignal>
#include <fstream>
#include <iostream>
#include <thread>

#include "fabatlas/coordinator/coordinator.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log_flags.h"
#include "fabatlas/protocol/channel.h"
#include "fabatlas/coordinator/version_text.h"

int main(int argc, char** argv) {
  CLI::App app{"fabatlas coordinator: jobs, leases and blobs over gRPC"};
  app.option_defaults()->always_capture_default();  // --help shows the defaults
  fabatlas::coordinator::CoordinatorOptions o;
  std::string token_file, port_file;
  double drain_seconds = 30;
  fabatlas::log::LogFlags log_flags;
  app.set_version_flag("--version", fabatlas::coordinator::VersionText("fabatlas-coordinator"));
  app.add_option("--listen", o.listen, "gRPC address HOST:PORT (port 0: pick one)");
  app.add_option("--state-dir", o.state_dir, "durable state directory")->required();
  app.add_option("--token", o.token, "bearer token required on every call");
  app.add_option("--token-file", token_file, "file holding the bearer token");
  app.add_option("--tls-cert", o.tls_cert, "server certificate chain (PEM)");
  app.add_option("--tls-key", o.tls_key, "server private key (PEM)");
  app.add_option("--tls-client-ca", o.tls_client_ca, "require client certificates signed by this CA (PEM)");
  app.add_flag("--allow-insecure-network", o.allow_insecure_network,
               "allow plaintext on a non-loopback address (isolated test networks only)");
  app.add_option("--metrics", o.metrics_listen, "serve Prometheus /metrics on HOST:PORT");
  app.add_option("--lease-ms", o.lease_ms, "lease duration");
  app.add_option("--heartbeat-ms", o.heartbeat_ms, "worker heartbeat interval");
  app.add_option("--retry-backoff-ms", o.retry_backoff_ms, "first requeue delay after an expiry");
  app.add_option("--quarantine-after", o.quarantine_after, "lease expiries before a task is quarantined");
  app.add_option("--drain-seconds", drain_seconds, "how long SIGTERM waits for running leases");
  app.add_option("--port-file", port_file, "write the bound port here once listening");
  bool no_affinity = false;
  app.add_flag("--no-lease-affinity", no_affinity,
               "lease tasks oldest first to whoever asks, ignoring which worker holds their inputs");
  app.add_flag("--fsync-commits", o.fsync_commits,
               "fsync the store on every commit, so acknowledged results also survive a power loss");
  log_flags.Add(app);
  CLI11_PARSE(app, argc, argv);
  o.lease_affinity = !no_affinity;
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);  // every thread inherits the mask
  try {
    log_flags.Apply();
    if (!token_file.empty()) o.token = fabatlas::protocol::ReadTokenFile(token_file);
    fabatlas::coordinator::Coordinator coordinator(o);
    coordinator.Start();
    if (!port_file.empty()) {
      std::string tmp = port_file + ".tmp";
      std::ofstream(tmp) << coordinator.port() << "\n";
      std::rename(tmp.c_str(), port_file.c_str());
    }
    int sig = 0;
    sigwait(&signals, &sig);
    fabatlas::log::Info("signal_received",
                        {{"signal", sig == SIGTERM ? "SIGTERM" : "SIGINT"}, {"drain_seconds", drain_seconds}});
    coordinator.Drain(static_cast<std::int64_t>(drain_seconds * 1000));
    coordinator.Shutdown();
    return 0;
  } catch (const fabatlas::ResourceError& e) {
    // The state directory cannot be read or written (an I/O error, a full
    // disk): a restart once the disk is back resumes every job.
    return log_flags.ErrorExit("fabatlas-coordinator", "coordinator_exit", e,
                               fabatlas::coordinator::kExitStateUnavailable);
  } catch (const fabatlas::InputError& e) {
    return log_flags.BadInputExit("fabatlas-coordinator", "coordinator_exit", e);
  }
}
