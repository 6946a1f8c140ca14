// Cluster job commands (issue 4): submit, status, watch, cancel, fetch, jobs
// against a running coordinator, and `run`, which starts an embedded
// coordinator and N fabatlas-worker processes on loopback and runs one job to
// completion.
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <thread>

#include "commands.h"
#include "fabatlas/coordinator/coordinator.h"
#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/error.h"
#include "fabatlas/log/log.h"
#include "fabatlas/precompute/form_outputs.h"

namespace fabatlas::cli {

namespace {

namespace fs = std::filesystem;

struct ClusterArgs {
  std::string coordinator;
  std::string token, tls_ca, tls_cert, tls_key;
  std::string job, out;
  int workers = 2, slots = 1;
  bool quiet = false;
};

void AddConnectionOptions(CLI::App* cmd, ClusterArgs& a) {
  const char* env = std::getenv("FABATLAS_COORDINATOR");
  a.coordinator = env ? env : "127.0.0.1:7450";
  cmd->add_option("--coordinator", a.coordinator, "coordinator HOST:PORT (env FABATLAS_COORDINATOR)");
  cmd->add_option("--token", a.token, "bearer token (env FABATLAS_TOKEN)");
  cmd->add_option("--tls-ca", a.tls_ca, "deployment CA certificate (PEM); enables TLS");
  cmd->add_option("--tls-cert", a.tls_cert, "client certificate (PEM)");
  cmd->add_option("--tls-key", a.tls_key, "client key (PEM)");
}

coordinator::JobClient ClientOf(const ClusterArgs& a) {
  protocol::ClientSecurity security;
  security.token = a.token;
  if (security.token.empty())
    if (const char* t = std::getenv("FABATLAS_TOKEN")) security.token = t;
  security.tls_ca = a.tls_ca;
  security.tls_cert = a.tls_cert;
  security.tls_key = a.tls_key;
  return coordinator::JobClient(a.coordinator, security);
}

// Prints the live progress line (carriage return on a terminal).
v1::JobStatus WatchJob(coordinator::JobClient& client, const std::string& id, bool quiet) {
  bool tty = ::isatty(STDERR_FILENO);
  auto last_print = std::chrono::steady_clock::now() - std::chrono::hours(1);
  v1::JobStatus final_status = client.Watch(id, [&](const v1::JobStatus& s) {
    auto now = std::chrono::steady_clock::now();
    if (!quiet && (tty || now - last_print > std::chrono::seconds(5))) {
      std::cerr << (tty ? "\r" : "") << coordinator::ProgressLine(s) << (tty ? "\033[K" : "\n") << std::flush;
      last_print = now;
    }
    return true;
  });
  if (!quiet) std::cerr << (tty ? "\r" : "") << coordinator::ProgressLine(final_status) << (tty ? "\033[K\n" : "\n");
  return final_status;
}

void WriteOutputs(const std::map<std::string, std::string>& files, const fs::path& out) {
  fs::create_directories(out);
  for (const auto& [name, bytes] : files) precompute::WriteFileAtomically(out / name, bytes);
}

int FinishedExitCode(const v1::JobStatus& s) {
  if (s.state() == v1::JOB_STATE_SUCCEEDED) return 0;
  std::cerr << "job " << s.job_id() << " " << coordinator::JobStateName(s.state())
            << (s.error().empty() ? "" : ": " + s.error()) << "\n";
  return 1;
}

pid_t SpawnWorker(const fs::path& binary, const std::string& target, int slots, const fs::path& cache) {
  // Arguments are prepared before fork: the coordinator's threads may hold
  // the allocator's locks, so the child only calls async-signal-safe code.
  std::string binary_text = binary.string(), slots_text = std::to_string(slots), cache_text = cache.string();
  pid_t pid = ::fork();
  if (pid < 0) throw ResourceError("fork: cannot start " + binary.string());
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);
    ::execl(binary_text.c_str(), binary_text.c_str(), "--coordinator", target.c_str(), "--slots",
            slots_text.c_str(), "--cache-dir", cache_text.c_str(), "--log-level", "warn", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int Run(const ClusterArgs& a) {
  if (a.workers < 1) throw InputError("run: --workers must be at least 1");
  fs::path self = fs::read_symlink("/proc/self/exe");
  fs::path worker_binary = self.parent_path() / "fabatlas-worker";
  if (!fs::exists(worker_binary)) throw InputError(worker_binary.string() + ": fabatlas-worker not found beside fabatlas");
  fs::path out = a.out;
  // The progress line is the report here; the embedded coordinator and the
  // workers log only warnings and errors (lease expiries, a full disk).
  log::Configure({log::Level::kWarn, log::Format::kText});
  coordinator::CoordinatorOptions options;
  options.listen = "127.0.0.1:0";
  options.state_dir = out / "cluster-state";
  options.lease_ms = 10000;
  options.heartbeat_ms = 2000;
  coordinator::Coordinator coordinator(options);
  coordinator.Start();
  std::string target = "127.0.0.1:" + std::to_string(coordinator.port());
  std::vector<pid_t> workers;
  for (int i = 0; i < a.workers; ++i)
    workers.push_back(SpawnWorker(worker_binary, target, a.slots, out / "cluster-state" / ("worker-" + std::to_string(i))));
  auto stop_workers = [&] {
    for (pid_t p : workers) ::kill(p, SIGTERM);
    for (pid_t p : workers) ::waitpid(p, nullptr, 0);
    workers.clear();
  };
  try {
    coordinator::JobClient client(target, {});
    std::string id = client.Submit(a.job);
    if (!a.quiet) std::cerr << "job " << id << " on " << a.workers << " worker(s) at " << target << "\n";
    v1::JobStatus s = WatchJob(client, id, a.quiet);
    int code = FinishedExitCode(s);
    if (code == 0) {
      auto files = client.Fetch(id);
      WriteOutputs(files, out);
      std::string artifact;
      for (const auto& [name, bytes] : files)
        if (fs::path(name).extension() == ".fabatlas") artifact = (out / name).string();
      std::cout << "wrote " << (artifact.empty() ? "" : artifact + ", ")
                << (files.count("form.json") ? (out / "form.json").string() + ", " : std::string())
                << "statistics.json\n";
    }
    stop_workers();
    coordinator.Shutdown();
    return code;
  } catch (...) {
    stop_workers();
    throw;
  }
}

}  // namespace

void AddJobCommands(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<ClusterArgs>();

  auto* run = app.add_subcommand("run", "run a job on an embedded coordinator with N local worker processes");
  run->add_option("job", a->job, "job YAML (docs/job-format.md)")->required();
  run->add_option("--workers", a->workers, "worker processes (default 2)");
  run->add_option("--slots", a->slots, "tasks per worker at once (default 1)");
  run->add_option("--out", a->out, "output directory (<design>.fabatlas, form.json, statistics.json; cluster-state/ keeps the store)")->required();
  run->add_flag("--quiet", a->quiet, "no progress line");
  run->callback([a, &exit_code] { exit_code = Run(*a); });

  auto* submit = app.add_subcommand("submit", "submit a job file to a coordinator");
  submit->add_option("job", a->job, "job YAML")->required();
  AddConnectionOptions(submit, *a);
  submit->callback([a] {
    bool created = false;
    auto client = ClientOf(*a);
    std::string id = client.Submit(a->job, &created);
    std::cout << id << (created ? "" : " (already submitted)") << "\n";
  });

  auto* status = app.add_subcommand("status", "show a job's progress");
  status->add_option("job_id", a->job, "job id")->required();
  AddConnectionOptions(status, *a);
  status->callback([a] { std::cout << coordinator::ProgressLine(ClientOf(*a).Status(a->job)) << "\n"; });

  auto* watch = app.add_subcommand("watch", "follow a job until it ends (samples, valid %, tasks/s, ETA, failures)");
  watch->add_option("job_id", a->job, "job id")->required();
  AddConnectionOptions(watch, *a);
  watch->callback([a, &exit_code] {
    auto client = ClientOf(*a);
    exit_code = FinishedExitCode(WatchJob(client, a->job, false));
  });

  auto* cancel = app.add_subcommand("cancel", "cancel a job");
  cancel->add_option("job_id", a->job, "job id")->required();
  AddConnectionOptions(cancel, *a);
  cancel->callback([a] { std::cout << coordinator::ProgressLine(ClientOf(*a).Cancel(a->job)) << "\n"; });

  auto* fetch = app.add_subcommand("fetch", "download a finished job's outputs");
  fetch->add_option("job_id", a->job, "job id")->required();
  fetch->add_option("--out", a->out, "output directory")->required();
  AddConnectionOptions(fetch, *a);
  fetch->callback([a] {
    WriteOutputs(ClientOf(*a).Fetch(a->job), a->out);
    std::cout << "wrote " << a->out << "\n";
  });

  auto* jobs = app.add_subcommand("jobs", "list the coordinator's jobs");
  AddConnectionOptions(jobs, *a);
  jobs->callback([a] {
    for (const auto& s : ClientOf(*a).List()) std::cout << coordinator::ProgressLine(s) << "\n";
  });
}

}  // namespace fabatlas::cli
