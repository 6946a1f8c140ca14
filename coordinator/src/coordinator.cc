// The coordinator's server: start-up (store, gRPC services, sweeper,
// /metrics, resumed jobs), drain and shutdown (coordinator_state.h says
// where the rest lives).
#include "fabatlas/coordinator/coordinator.h"
#include "fabatlas/coordinator/run_tasks.h"

#include <grpcpp/grpcpp.h>
#include <grpcpp/health_check_service_interface.h>
#include <httplib.h>

#include <cstdlib>
#include <thread>

#include "coordinator_state.h"
#include "fabatlas/directory_lock.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/protocol/channel.h"
#include "services.h"

namespace fabatlas::coordinator {

namespace {
// gRPC threads kept polling for calls when idle (gRPC's default: 2).
constexpr int kIdlePollers = 16;

// The gRPC port's credentials: TLS when a certificate and key are given
// (client certificates required with a client CA), else plaintext, which
// only a loopback address gets unless the network is allowed explicitly.
std::shared_ptr<grpc::ServerCredentials> ServerCredentials(const CoordinatorOptions& o) {
  if (!o.tls_cert.empty() || !o.tls_key.empty()) {
    if (o.tls_cert.empty() || o.tls_key.empty())
      throw InputError("coordinator: TLS needs both a certificate (--tls-cert) and a key (--tls-key)");
    grpc::SslServerCredentialsOptions ssl(o.tls_client_ca.empty()
                                              ? GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE
                                              : GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY);
    if (!o.tls_client_ca.empty()) ssl.pem_root_certs = protocol::ReadPemFile(o.tls_client_ca, "client CA");
    ssl.pem_key_cert_pairs.push_back(
        {protocol::ReadPemFile(o.tls_key, "TLS key"), protocol::ReadPemFile(o.tls_cert, "TLS certificate")});
    return grpc::SslServerCredentials(ssl);
  }
  if (!protocol::IsLoopback(o.listen) && !o.allow_insecure_network)
    throw InputError("coordinator: refusing plaintext on non-loopback address " + o.listen +
                     " (give --tls-cert/--tls-key, see ops/tls/make-certs.sh)");
  return grpc::InsecureServerCredentials();
}

// The state directory, locked: the job store and the blob store, with every
// lease given one lease period of grace and no worker affinity (which
// workers are alive is not known yet).
void OpenState(Coordinator::Impl& m) {
  const auto& o = m.options;
  // One coordinator per state directory: a second one exits naming the first.
  m.state_lock = std::make_unique<DirectoryLock>(o.state_dir, "state directory");
  storage::JobStoreOptions store_options;
  store_options.fsync_every_commit = o.fsync_commits;
  store_options.background_checkpoints = true;  // Sweep() checkpoints, off the request path
  m.store = std::make_unique<storage::JobStore>(o.state_dir / "state.db", store_options);
  m.blobs = std::make_unique<storage::BlobStore>(o.state_dir / "blobs");
  m.store->ExtendAllLeases(NowMs() + o.lease_ms);
  m.store->ClearAffinity();
}

// The gRPC server with the job, worker and blob services, listening and
// reported serving to health checks.
void StartServer(Coordinator::Impl& m, const std::shared_ptr<grpc::ServerCredentials>& credentials) {
  const auto& o = m.options;
  protocol::HoldGrpcUntilExit();
  protocol::RouteGrpcLogs();
  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  builder.AddListeningPort(o.listen, credentials, &m.port);
  builder.SetMaxReceiveMessageSize(protocol::kMaxMessageBytes);
  builder.SetMaxSendMessageSize(protocol::kMaxMessageBytes);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIME_MS, 20000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_TIMEOUT_MS, 10000);
  builder.AddChannelArgument(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MIN_RECV_PING_INTERVAL_WITHOUT_DATA_MS, 5000);
  builder.AddChannelArgument(GRPC_ARG_HTTP2_MAX_PING_STRIKES, 0);
  // Threads that finish a call go back to polling instead of exiting: each
  // worker keeps long polls open (Sync, ShareSolids, the CLI's WatchJob), so
  // with gRPC's default of 2 idle pollers nearly every call created and
  // ended a thread (docs/benchmarks.md "Scale": the coordinator's CPU).
  builder.SetSyncServerOption(grpc::ServerBuilder::SyncServerOption::MAX_POLLERS, kIdlePollers);
  m.services.push_back(MakeJobService(m));
  m.services.push_back(MakeWorkerService(m));
  m.services.push_back(MakeBlobService(m));
  for (auto& s : m.services) builder.RegisterService(s.get());
  m.server = builder.BuildAndStart();
  if (!m.server || m.port == 0) throw InputError("coordinator: cannot listen on " + o.listen);
  m.server->GetHealthCheckService()->SetServingStatus(true);
}

// /healthz and /metrics on --metrics HOST:PORT, plaintext, on a thread of
// their own.
void StartMetrics(Coordinator::Impl& m) {
  const auto& o = m.options;
  auto colon = o.metrics_listen.rfind(':');
  if (colon == std::string::npos) throw InputError("coordinator: --metrics wants HOST:PORT, got " + o.metrics_listen);
  std::string host = o.metrics_listen.substr(0, colon);
  int port = std::atoi(o.metrics_listen.c_str() + colon + 1);
  m.metrics = std::make_unique<httplib::Server>();
  // Plaintext health for probes that cannot speak the gRPC port's TLS
  // (Kubernetes httpGet): 200 while serving, 503 while draining.
  m.metrics->Get("/healthz", [&m](const httplib::Request&, httplib::Response& res) {
    const bool serving = !m.draining && !m.stopping;
    res.status = serving ? 200 : 503;
    res.set_content(serving ? "serving\n" : "draining\n", "text/plain");
  });
  m.metrics->Get("/metrics", [&m](const httplib::Request&, httplib::Response& res) {
    try {
      res.set_content(m.Metrics(), "text/plain; version=0.0.4");
    } catch (const std::exception& e) {
      res.status = 500;
      res.set_content(e.what(), "text/plain");
    }
  });
  if (!m.metrics->bind_to_port(host, port)) throw InputError("coordinator: cannot listen on " + o.metrics_listen);
  m.metrics_thread = std::thread([&m] { m.metrics->listen_after_bind(); });
}

}  // namespace

grpc::Status Invalid(const std::string& message) { return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, message); }

grpc::Status FromException(const std::exception& e) {
  if (dynamic_cast<const ResourceError*>(&e)) return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, e.what());
  if (dynamic_cast<const InputError*>(&e)) return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, e.what());
  return grpc::Status(grpc::StatusCode::INTERNAL, e.what());
}

Coordinator::Coordinator(CoordinatorOptions options) : impl_(std::make_unique<Impl>(std::move(options))) {}

Coordinator::~Coordinator() { Shutdown(); }

void Coordinator::Start() {
  Impl& m = *impl_;
  const auto& o = m.options;
  if (o.state_dir.empty()) throw InputError("coordinator: a state directory is required (--state-dir)");
  const std::shared_ptr<grpc::ServerCredentials> credentials = ServerCredentials(o);
  OpenState(m);
  StartServer(m, credentials);
  m.started = true;
  m.sweeper = std::thread([&m] { m.Sweep(); });
  if (!o.metrics_listen.empty()) StartMetrics(m);
  std::int64_t resumed = 0, in_grace = m.store->ActiveLeases();
  for (const auto& job : m.store->Jobs())
    if (job.state == storage::JobState::kRunning) {
      m.StartDriver(job.id);
      ++resumed;
    }
  log::Info("coordinator_started", {{"listen", o.listen},
                                    {"port", m.port},
                                    {"state_dir", o.state_dir.string()},
                                    {"jobs_resumed", resumed},
                                    {"leases_in_grace", in_grace},
                                    {"tls", static_cast<bool>(!o.tls_cert.empty())}});
}

int Coordinator::port() const { return impl_->port; }

void Coordinator::Drain(std::int64_t timeout_ms) {
  Impl& m = *impl_;
  if (!m.started) return;
  m.draining = true;
  m.server->GetHealthCheckService()->SetServingStatus(false);
  m.SignalWork();
  log::Info("drain_started", {{"active_leases", m.store->ActiveLeases()}, {"timeout_ms", timeout_ms}});
  auto started = std::chrono::steady_clock::now();
  auto until = started + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < until && m.store->ActiveLeases() > 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  log::Info(
      "drain_finished",
      {{"active_leases", m.store->ActiveLeases()},
       {"waited_ms",
        std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - started).count()}});
}

void Coordinator::Shutdown() {
  Impl& m = *impl_;
  {
    std::lock_guard lock(m.shutdown_mu);
    if (m.shut_down) return;
    m.shut_down = true;
  }
  m.stopping = true;
  m.SignalWork();
  m.results_cv.notify_all();
  if (m.server) m.server->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(2));
  if (m.sweeper.joinable()) m.sweeper.join();
  if (m.metrics) m.metrics->stop();
  if (m.metrics_thread.joinable()) m.metrics_thread.join();
  std::vector<std::thread> drivers;
  {
    std::lock_guard lock(m.drivers_mu);
    drivers.swap(m.drivers);
  }
  for (auto& t : drivers) t.join();
  if (m.started) log::Info("coordinator_stopped", {{"port", m.port}});
  m.shutdown_cv.notify_all();
}

void Coordinator::Wait() {
  Impl& m = *impl_;
  std::unique_lock lock(m.shutdown_mu);
  m.shutdown_cv.wait(lock, [&] { return m.shut_down; });
}

std::vector<std::string> RunTasks(Coordinator& coordinator, const std::string& job_id,
                                  const std::vector<std::string>& payloads, const std::vector<std::string>& keys) {
  Coordinator::Impl& m = *coordinator.impl_;
  if (!m.store->FindJob(job_id))
    m.store->CreateJob({job_id, std::string(64, '0'), "tasks", storage::JobState::kRunning, "", NowMs(), 0});
  std::vector<int> kinds;
  for (const auto& p : payloads) {
    v1::TaskPayload payload;
    payload.ParseFromString(p);
    kinds.push_back(static_cast<int>(payload.kind()));
  }
  try {
    return m.RunTasks(job_id, payloads, keys, kinds);
  } catch (const Stopping&) {
    throw InputError("coordinator: shutting down");
  } catch (const JobCancelled&) {
    throw InputError("job " + job_id + " cancelled");
  }
}

}  // namespace fabatlas::coordinator
