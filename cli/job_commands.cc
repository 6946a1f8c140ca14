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

#include <google/protobuf/descriptor.h>
#include <nlohmann/json.hpp>

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
  bool json = false;  // machine-readable output on stdout (--json)
};

// A job's status as a JSON object: every JobStatus field by its proto name,
// numbers as numbers, the state as "RUNNING" etc. (new fields appear as
// they are added to job.proto).
nlohmann::json StatusJson(const v1::JobStatus& s) {
  nlohmann::json j = nlohmann::json::object();
  const auto* d = s.GetDescriptor();
  const auto* r = s.GetReflection();
  for (int i = 0; i < d->field_count(); ++i) {
    const auto* f = d->field(i);
    switch (f->cpp_type()) {
      case google::protobuf::FieldDescriptor::CPPTYPE_INT64:
        j[f->name()] = r->GetInt64(s, f);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_INT32:
        j[f->name()] = r->GetInt32(s, f);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE:
        j[f->name()] = r->GetDouble(s, f);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_BOOL:
        j[f->name()] = r->GetBool(s, f);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_STRING:
        j[f->name()] = r->GetString(s, f);
        break;
      case google::protobuf::FieldDescriptor::CPPTYPE_ENUM:
        j[f->name()] = f->name() == "state" ? coordinator::JobStateName(s.state()) : r->GetEnum(s, f)->name();
        break;
      default:
        break;
    }
  }
  return j;
}

void PrintJson(const nlohmann::json& j) { std::cout << j.dump() << std::endl; }

void AddConnectionOptions(CLI::App* cmd, ClusterArgs& a) {
  const char* env = std::getenv("FABATLAS_COORDINATOR");
  a.coordinator = env ? env : "127.0.0.1:7450";
  cmd->add_option("--coordinator", a.coordinator, "coordinator HOST:PORT (env FABATLAS_COORDINATOR)")
      ->capture_default_str();
  cmd->add_option("--token", a.token, "bearer token (env FABATLAS_TOKEN; default: none)");
  cmd->add_option(
      "--tls-ca", a.tls_ca,
      "the deployment's CA certificate (PEM, ops/tls/make-certs.sh); enables TLS (default: plaintext, loopback only)");
  cmd->add_option("--tls-cert", a.tls_cert, "client certificate (PEM), when the coordinator requires one");
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
// With json, one JSON object per update on stdout instead (the last one is
// the final status).
v1::JobStatus WatchJob(coordinator::JobClient& client, const std::string& id, bool quiet, bool json = false) {
  if (json) {
    v1::JobStatus last;
    v1::JobStatus final_status = client.Watch(id, [&](const v1::JobStatus& s) {
      PrintJson(StatusJson(s));
      last = s;
      return true;
    });
    if (final_status.SerializeAsString() != last.SerializeAsString()) PrintJson(StatusJson(final_status));
    return final_status;
  }
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
    ::execl(binary_text.c_str(), binary_text.c_str(), "--coordinator", target.c_str(), "--slots", slots_text.c_str(),
            "--cache-dir", cache_text.c_str(), "--log-level", "warn", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

int Run(const ClusterArgs& a) {
  if (a.workers < 1) throw InputError("run: --workers must be at least 1");
  fs::path self = fs::read_symlink("/proc/self/exe");
  fs::path worker_binary = self.parent_path() / "fabatlas-worker";
  if (!fs::exists(worker_binary))
    throw InputError(worker_binary.string() + ": fabatlas-worker not found beside fabatlas");
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
    workers.push_back(
        SpawnWorker(worker_binary, target, a.slots, out / "cluster-state" / ("worker-" + std::to_string(i))));
  auto stop_workers = [&] {
    for (pid_t p : workers) ::kill(p, SIGTERM);
    for (pid_t p : workers) ::waitpid(p, nullptr, 0);
    workers.clear();
  };
  try {
    coordinator::JobClient client(target, {});
    std::string id = client.Submit(JobOrModel(a.job, (out / "model").string()));
    if (!a.quiet) std::cerr << "job " << id << " on " << a.workers << " worker(s) at " << target << "\n";
    v1::JobStatus s = WatchJob(client, id, a.quiet || a.json);
    int code = FinishedExitCode(s);
    nlohmann::json written = nlohmann::json::array();
    if (code == 0) {
      auto files = client.Fetch(id);
      WriteOutputs(files, out);
      std::string artifact;
      for (const auto& [name, bytes] : files) {
        if (fs::path(name).extension() == ".fabatlas") artifact = (out / name).string();
        written.push_back((out / name).string());
      }
      if (!a.json)
        std::cout << "wrote " << (artifact.empty() ? "" : artifact + ", ")
                  << (files.count("form.json") ? (out / "form.json").string() + ", " : std::string())
                  << "statistics.json\n";
    }
    if (a.json) PrintJson({{"job", StatusJson(s)}, {"outputs", written}});
    stop_workers();
    coordinator.Shutdown();
    return code;
  } catch (...) {
    stop_workers();
    throw;
  }
}

// fabatlas submit: an OpenSCAD model is imported into a temporary directory
// first; the bundle carries its files, so the directory goes once submitted.
void Submit(const ClusterArgs& a) {
  bool created = false;
  auto client = ClientOf(a);
  std::string job = a.job;
  fs::path staging;
  if (IsScadModel(job)) {
    char tmpl[] = "/tmp/fabatlas-import-XXXXXX";
    if (!::mkdtemp(tmpl)) throw ResourceError("submit: cannot create a temporary directory");
    staging = tmpl;
    job = JobOrModel(job, staging.string());
  }
  std::string id;
  try {
    id = client.Submit(job, &created);
  } catch (...) {
    if (!staging.empty()) fs::remove_all(staging);
    throw;
  }
  if (!staging.empty()) fs::remove_all(staging);
  if (a.json)
    PrintJson({{"job_id", id}, {"created", created}});
  else
    std::cout << id << (created ? "" : " (already submitted)") << "\n";
}

// fabatlas jobs: every job's status line, or {"jobs": [status, ...]}.
void ListJobs(const ClusterArgs& a) {
  auto list = ClientOf(a).List();
  if (a.json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& s : list) out.push_back(StatusJson(s));
    PrintJson({{"jobs", out}});
    return;
  }
  for (const auto& s : list) std::cout << coordinator::ProgressLine(s) << "\n";
}

// run and submit: a job computed here, or sent to a coordinator.
void AddRunAndSubmit(CLI::App& app, const std::shared_ptr<ClusterArgs>& a, int& exit_code) {
  auto* run = app.add_subcommand(
      "run", "compute a job's form on this machine: a coordinator in this process and N worker processes");
  run->add_option("job", a->job, "job file (YAML, docs/job-format.md) or OpenSCAD model (.scad)")->required();
  run->add_option("--workers", a->workers, "worker processes");
  run->add_option("--slots", a->slots, "tasks each worker runs at once");
  run->add_option("--out", a->out,
                  "output directory (<design>.fabatlas, form.json, statistics.json; cluster-state/ keeps the store, so "
                  "the same command resumes after a crash)")
      ->required();
  run->add_flag("--quiet", a->quiet, "no progress line");
  run->add_flag("--json", a->json, "print the final status and the files written as one JSON object on stdout");
  run->callback([a, &exit_code] { exit_code = Run(*a); });

  auto* submit = app.add_subcommand("submit", "send a job file (and its design) to a coordinator; prints the job id");
  submit->add_option("job", a->job, "job file (YAML, docs/job-format.md) or OpenSCAD model (.scad)")->required();
  submit->add_flag("--json", a->json, "print {\"job_id\", \"created\"} as JSON");
  AddConnectionOptions(submit, *a);
  submit->callback([a] { Submit(*a); });
}

// status, watch, cancel, fetch and jobs: a coordinator's jobs.
void AddJobFollowing(CLI::App& app, const std::shared_ptr<ClusterArgs>& a, int& exit_code) {
  auto* status = app.add_subcommand(
      "status", "show a job's progress: samples, valid %, tasks, tasks/s, ETA, failures, why it is stalled");
  status->add_option("job_id", a->job, "job id (from submit or jobs)")->required();
  status->add_flag("--json", a->json, "print the status as one JSON object");
  AddConnectionOptions(status, *a);
  status->callback([a] {
    v1::JobStatus s = ClientOf(*a).Status(a->job);
    if (a->json)
      PrintJson(StatusJson(s));
    else
      std::cout << coordinator::ProgressLine(s) << "\n";
  });

  auto* watch = app.add_subcommand(
      "watch", "follow a job until it ends (samples, valid %, tasks/s, ETA, failures); exit 0 when it succeeded");
  watch->add_option("job_id", a->job, "job id (from submit or jobs)")->required();
  watch->add_flag("--json", a->json, "print each status change as one JSON object per line on stdout");
  AddConnectionOptions(watch, *a);
  watch->callback([a, &exit_code] {
    auto client = ClientOf(*a);
    exit_code = FinishedExitCode(WatchJob(client, a->job, false, a->json));
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

  auto* jobs = app.add_subcommand("jobs", "list the coordinator's jobs with their progress");
  jobs->add_flag("--json", a->json, "print {\"jobs\": [status, ...]} as JSON");
  AddConnectionOptions(jobs, *a);
  jobs->callback([a] { ListJobs(*a); });
}

}  // namespace

void AddJobCommands(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<ClusterArgs>();
  AddRunAndSubmit(app, a, exit_code);
  AddJobFollowing(app, a, exit_code);
}

}  // namespace fabatlas::cli
