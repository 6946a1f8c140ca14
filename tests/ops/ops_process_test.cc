// Operations as an operator meets them (issue 16): real coordinator and
// worker processes on loopback, their JSON log lines, SIGTERM, and the CLI
// with paths typed the way users type them.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <httplib.h>
#include <netinet/in.h>
#include <nlohmann/json.hpp>
#include <sys/socket.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "../cluster/cluster_process.h"
#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/error.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/testing/small_filesystem.h"

namespace fabatlas::ops_test {
namespace {

using namespace fabatlas::cluster_test;

fs::path JobPath() { return SourceDir() / "tests/cluster/data/tube_small.yaml"; }

coordinator::JobClient Client(int port) {
  return coordinator::JobClient("127.0.0.1:" + std::to_string(port), {}, std::chrono::seconds(5));
}

// Polls the job until it ends or `timeout` passes.
v1::JobStatus WaitForJob(int port, const std::string& id, std::chrono::seconds timeout) {
  auto until = std::chrono::steady_clock::now() + timeout;
  v1::JobStatus last;
  while (std::chrono::steady_clock::now() < until) {
    last = Client(port).Status(id);
    if (last.state() >= v1::JOB_STATE_SUCCEEDED) return last;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return last;
}

// Waits until `path` contains `text` (a process reached a state), or the
// process exited, or 60 s passed.
bool WaitForText(const fs::path& path, const std::string& text, pid_t pid) {
  for (int i = 0; i < 3000; ++i) {
    if (ReadText(path).find(text) != std::string::npos) return true;
    if (WaitExit(pid, std::chrono::milliseconds(0)) != -1) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

// Every line of a JSON log, parsed; a line that does not parse, or lacks
// ts, level or event, fails the test.
std::vector<nlohmann::json> JsonLines(const fs::path& log) {
  std::vector<nlohmann::json> lines;
  std::istringstream in(ReadText(log));
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    nlohmann::json j = nlohmann::json::parse(line, nullptr, false);
    EXPECT_FALSE(j.is_discarded()) << log << ": not a JSON line: " << line;
    if (j.is_discarded()) continue;
    EXPECT_TRUE(j.is_object() && j.contains("ts") && j.contains("level") && j.contains("event")) << line;
    lines.push_back(std::move(j));
  }
  return lines;
}

// GET http://127.0.0.1:PORT/PATH in this process (no curl): the status
// (0 when nothing answered) and the body.
std::pair<int, std::string> HttpGet(int port, const std::string& path) {
  httplib::Client http("127.0.0.1", port);
  http.set_connection_timeout(std::chrono::seconds(10));
  http.set_read_timeout(std::chrono::seconds(10));
  auto res = http.Get(path);
  if (!res) return {0, ""};
  return {res->status, res->body};
}

std::vector<nlohmann::json> Events(const std::vector<nlohmann::json>& lines, const std::string& event) {
  std::vector<nlohmann::json> out;
  for (const auto& j : lines)
    if (j.value("event", "") == event) out.push_back(j);
  return out;
}

// Runs a shell command line in `dir`; exit status and stdout+stderr.
// With stderr false, only stdout (stderr dropped).
std::pair<int, std::string> Shell(const fs::path& dir, const std::string& command, bool stderr = true) {
  std::string cmd = "cd '" + dir.string() + "' && " + command + (stderr ? " 2>&1" : " 2>/dev/null");
  FILE* pipe = ::popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

// form.json of the job as `fabatlas sample` computes it in this process
// (run in `dir`, outputs in dir/reference): what the cluster must publish.
std::string InProcessForm(const fs::path& dir) {
  auto [code, out] =
      Shell(dir, (BinDir() / "fabatlas").string() + " sample " + JobPath().string() + " --out reference");
  EXPECT_EQ(code, 0) << out;
  return ReadText(dir / "reference/form.json");
}

TEST(OpsLogs, JsonLinesTellTheStoryOfAJobWithAKilledWorker) {
  fs::path dir = FreshDir("ops_logs");
  const int coordinator_metrics = FreePort(), worker_metrics = FreePort();
  CoordinatorProcess c = StartCoordinator(dir / "state", 0,
                                          {"--lease-ms", "1500", "--retry-backoff-ms", "50", "--log-format", "json",
                                           "--metrics", "127.0.0.1:" + std::to_string(coordinator_metrics)});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  // w1 SIGKILLs itself when it starts a task whose key begins with "0"
  // (about one task in 16): it dies holding that lease.
  ::setenv("FABATLAS_WORKER_CRASH_KEY_PREFIX", "0", 1);
  pid_t w1 = StartWorker(c.port, dir / "w1", {"--id", "w1", "--log-format", "json"});
  ::unsetenv("FABATLAS_WORKER_CRASH_KEY_PREFIX");
  ASSERT_TRUE(WaitForText(dir / "w1/worker.log", "worker_connected", w1)) << ReadText(dir / "w1/worker.log");
  std::string id = Client(c.port).Submit(JobPath());
  EXPECT_EQ(WaitExit(w1, std::chrono::seconds(120)), 128 + SIGKILL);
  pid_t w2 =
      StartWorker(c.port, dir / "w2",
                  {"--id", "w2", "--log-format", "json", "--metrics", "127.0.0.1:" + std::to_string(worker_metrics)});
  v1::JobStatus s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  // Metrics: every accepted sample result is one observation of the
  // coordinator's sample histogram; the worker counts the tasks it ran.
  auto scrape = [&](int port) {
    auto [status, text] = HttpGet(port, "/metrics");
    EXPECT_EQ(status, 200) << text;
    return text;
  };
  auto value = [](const std::string& text, const std::string& series) {
    auto at = text.find("\n" + series + " ");
    return at == std::string::npos ? -1.0 : std::atof(text.c_str() + at + series.size() + 2);
  };
  const std::string cm = scrape(coordinator_metrics), wm = scrape(worker_metrics);
  EXPECT_EQ(value(cm, "fabatlas_task_duration_seconds_count{kind=\"sample\"}"), s.samples_done()) << cm;
  EXPECT_GE(value(cm, "fabatlas_lease_expiries_total"), 1) << cm;
  EXPECT_EQ(value(cm, "fabatlas_state_stalled"), 0) << cm;
  double w2_tasks = 0;  // over all kinds
  {
    std::istringstream lines(wm);
    std::string line;
    while (std::getline(lines, line))
      if (line.rfind("fabatlas_worker_tasks_total{", 0) == 0) w2_tasks += std::atof(line.c_str() + line.rfind(' '));
  }
  EXPECT_GT(value(wm, "process_resident_memory_bytes"), 0) << wm;
  EXPECT_EQ(value(wm, "fabatlas_worker_connected"), 1) << wm;
  EXPECT_EQ(HttpGet(worker_metrics, "/healthz"), std::make_pair(200, std::string("working\n")));
  ::kill(w2, SIGTERM);
  EXPECT_EQ(WaitExit(w2, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);

  auto coordinator = JsonLines(dir / "state/coordinator.log");
  for (const char* event :
       {"coordinator_started", "job_submitted", "job_started", "round_started", "worker_joined", "lease_expired",
        "job_succeeded", "signal_received", "drain_started", "drain_finished", "coordinator_stopped"})
    EXPECT_FALSE(Events(coordinator, event).empty()) << "coordinator logged no " << event;
  // The expiry names the task, the worker that died and the attempt. (w1
  // may also have held leases taken in advance, a 1-slot worker of short
  // tasks does: those expire beside it.)
  auto expired = Events(coordinator, "lease_expired");
  auto crashed = std::find_if(expired.begin(), expired.end(),
                              [](const auto& e) { return e["task"].template get<std::string>().substr(0, 1) == "0"; });
  ASSERT_NE(crashed, expired.end());
  EXPECT_EQ((*crashed)["worker"], "w1");
  EXPECT_EQ((*crashed)["attempt"], 1);
  EXPECT_EQ((*crashed)["job"], id);
  std::set<std::string> joined;
  for (const auto& j : Events(coordinator, "worker_joined")) joined.insert(j["worker"].get<std::string>());
  EXPECT_EQ(joined, (std::set<std::string>{"w1", "w2"}));
  auto submitted = Events(coordinator, "job_submitted");
  ASSERT_EQ(submitted.size(), 1u);
  EXPECT_EQ(submitted[0]["job"], id);
  EXPECT_EQ(submitted[0]["design"], "tube_wall_2d");
  auto succeeded = Events(coordinator, "job_succeeded");
  ASSERT_EQ(succeeded.size(), 1u);
  EXPECT_EQ(succeeded[0]["samples"], s.samples_done());
  for (const auto& round : Events(coordinator, "round_started")) EXPECT_GT(round["tasks"].get<int>(), 0) << round;

  auto killed = JsonLines(dir / "w1/worker.log");
  EXPECT_FALSE(Events(killed, "worker_connected").empty());
  EXPECT_TRUE(Events(killed, "worker_exit").empty());  // SIGKILL: no last words
  auto worker = JsonLines(dir / "w2/worker.log");
  for (const char* event : {"worker_connected", "worker_stopping", "worker_exit"})
    EXPECT_FALSE(Events(worker, event).empty()) << "worker logged no " << event;
  auto exit = Events(worker, "worker_exit");
  ASSERT_EQ(exit.size(), 1u);
  EXPECT_GT(exit[0]["tasks_run"].get<int>(), 0);
  EXPECT_EQ(exit[0]["tasks_run"].get<double>(), w2_tasks) << wm;
  fs::remove_all(dir);
}

// A worker whose coordinator stopped answering (SIGSTOP: the connection
// stays open, nothing comes back, as with a host that has gone) exits soon
// after SIGTERM instead of waiting out its long poll's deadline and its
// reconnect attempts (20 s to a minute before; systemd and Kubernetes
// SIGKILL after their stop timeout).
TEST(OpsWorker, SigtermExitsWithinSecondsWhenTheCoordinatorHasGone) {
  fs::path dir = FreshDir("ops_sigterm");
  CoordinatorProcess c = StartCoordinator(dir / "state", 0, {"--log-format", "json"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  pid_t w = StartWorker(c.port, dir / "w", {"--log-format", "json"});
  ASSERT_TRUE(WaitForText(dir / "w/worker.log", "worker_connected", w)) << ReadText(dir / "w/worker.log");
  ::kill(c.pid, SIGSTOP);
  auto t0 = std::chrono::steady_clock::now();
  ::kill(w, SIGTERM);
  int status = WaitExit(w, std::chrono::seconds(10));
  auto waited = std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - t0).count();
  if (status == -1) KillAndReap(w);
  EXPECT_EQ(status, 0) << "worker still running " << waited << " ms after SIGTERM\n" << ReadText(dir / "w/worker.log");
  auto lines = JsonLines(dir / "w/worker.log");
  EXPECT_FALSE(Events(lines, "worker_leaving_unreported").empty()) << ReadText(dir / "w/worker.log");
  EXPECT_FALSE(Events(lines, "worker_exit").empty());
  ::kill(c.pid, SIGCONT);
  KillAndReap(c.pid);
  fs::remove_all(dir);
}

// This machine's host name, as the LOCK line names it.
std::string HostName() {
  char host[256] = {};
  ::gethostname(host, sizeof(host) - 1);
  return host;
}

// The one line a process refused by a lock wrote, checked: it names the
// directory and the holder's pid and host, and the process exited 2.
void ExpectRefusedByHolder(pid_t refused, const fs::path& log, const std::string& program, const fs::path& dir,
                           const std::string& what, pid_t holder) {
  EXPECT_EQ(WaitExit(refused, std::chrono::seconds(30)), 2) << ReadText(log);
  const std::string text = ReadText(log);
  const std::string want = program + ": " + dir.string() + ": " + what + " in use by pid " + std::to_string(holder) +
                           " host " + HostName() + " since ";
  EXPECT_EQ(text.rfind(want, 0), 0u) << text;
  EXPECT_NE(text.find("(" + (dir / "LOCK").string() + ")"), std::string::npos) << text;
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
}

// Two coordinators on one state directory (split brain: both would resume,
// lease and publish the same jobs): the second exits 2 with one line naming
// the first (pid, host, since when). Once the first is killed with SIGKILL
// (no cleanup), the kernel has released its flock and a new coordinator
// starts on the same directory, resumes the job and finishes it.
TEST(OpsLock, ASecondCoordinatorOnOneStateDirectoryExits2AndAKilledOnesLockIsTakenOver) {
  fs::path dir = FreshDir("ops_lock_coordinator");
  CoordinatorProcess first = StartCoordinator(dir / "state", 0, {"--retry-backoff-ms", "50"});
  ASSERT_GT(first.port, 0) << ReadText(dir / "state/coordinator.log");
  const std::string id = Client(first.port).Submit(JobPath());
  pid_t second = Spawn({(BinDir() / "fabatlas-coordinator").string(), "--listen", "127.0.0.1:0", "--state-dir",
                        (dir / "state").string(), "--port-file", (dir / "second.port").string()},
                       dir / "second.log");
  ExpectRefusedByHolder(second, dir / "second.log", "fabatlas-coordinator", dir / "state", "state directory",
                        first.pid);
  EXPECT_FALSE(fs::exists(dir / "second.port"));
  // The holder's line stays the first's while it runs.
  EXPECT_EQ(ReadText(dir / "state/LOCK").rfind("pid " + std::to_string(first.pid) + " host ", 0), 0u);

  KillAndReap(first.pid);
  CoordinatorProcess third = StartCoordinator(dir / "state", 0, {"--retry-backoff-ms", "50"});
  ASSERT_GT(third.port, 0) << ReadText(dir / "state/coordinator.log");
  EXPECT_EQ(ReadText(dir / "state/LOCK").rfind("pid " + std::to_string(third.pid) + " host ", 0), 0u)
      << ReadText(dir / "state/LOCK");
  pid_t w = StartWorker(third.port, dir / "w");
  const v1::JobStatus s = WaitForJob(third.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  ::kill(w, SIGTERM);
  EXPECT_EQ(WaitExit(w, std::chrono::seconds(30)), 0);
  ::kill(third.pid, SIGTERM);
  EXPECT_EQ(WaitExit(third.pid, std::chrono::seconds(30)), 0);
  fs::remove_all(dir);
}

// Two workers on one cache directory: the second exits 2 with one line
// naming the first; after SIGKILL of the first a new worker takes the
// directory over and runs a job to its end.
TEST(OpsLock, ASecondWorkerOnOneCacheDirectoryExits2AndAKilledOnesLockIsTakenOver) {
  fs::path dir = FreshDir("ops_lock_worker");
  CoordinatorProcess c = StartCoordinator(dir / "state", 0, {"--retry-backoff-ms", "50", "--lease-ms", "3000"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  pid_t first = StartWorker(c.port, dir / "w1", {"--log-format", "json"});
  ASSERT_TRUE(WaitForText(dir / "w1/worker.log", "worker_connected", first)) << ReadText(dir / "w1/worker.log");
  pid_t second = Spawn({(BinDir() / "fabatlas-worker").string(), "--coordinator", "127.0.0.1:" + std::to_string(c.port),
                        "--cache-dir", (dir / "w1/cache").string()},
                       dir / "second.log");
  ExpectRefusedByHolder(second, dir / "second.log", "fabatlas-worker", dir / "w1/cache", "worker cache directory",
                        first);

  KillAndReap(first);
  pid_t third = Spawn({(BinDir() / "fabatlas-worker").string(), "--coordinator", "127.0.0.1:" + std::to_string(c.port),
                       "--cache-dir", (dir / "w1/cache").string(), "--log-format", "json"},
                      dir / "third.log");
  ASSERT_TRUE(WaitForText(dir / "third.log", "worker_connected", third)) << ReadText(dir / "third.log");
  EXPECT_EQ(ReadText(dir / "w1/cache/LOCK").rfind("pid " + std::to_string(third) + " host ", 0), 0u)
      << ReadText(dir / "w1/cache/LOCK");
  const std::string id = Client(c.port).Submit(JobPath());
  const v1::JobStatus s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  ::kill(third, SIGTERM);
  EXPECT_EQ(WaitExit(third, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  fs::remove_all(dir);
}

// `fabatlas run` (an embedded coordinator) on an --out whose cluster-state
// a coordinator holds: exit 2, one line naming the holder.
TEST(OpsLock, RunOnAStateDirectoryInUseExits2) {
  fs::path dir = FreshDir("ops_lock_run");
  CoordinatorProcess c = StartCoordinator(dir / "out/cluster-state", 0);
  ASSERT_GT(c.port, 0) << ReadText(dir / "out/cluster-state/coordinator.log");
  pid_t run = Spawn(
      {(BinDir() / "fabatlas").string(), "run", JobPath().string(), "--workers", "1", "--out", (dir / "out").string()},
      dir / "run.log");
  ExpectRefusedByHolder(run, dir / "run.log", "fabatlas", dir / "out/cluster-state", "state directory", c.pid);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  fs::remove_all(dir);
}

// A state.db that is not SQLite (a text file, or the first 4 KiB of a
// database overwritten): the coordinator exits 2 with one line naming the
// file and SQLite's reason, and leaves the file as it was.
TEST(OpsStore, AStateDbThatIsNotSqliteIsOneLineAndExit2) {
  fs::path dir = FreshDir("ops_not_sqlite");
  fs::create_directories(dir / "state");
  std::string text;
  for (int i = 0; i < 200; ++i) text += "this is not a database, line " + std::to_string(i) + "\n";
  std::ofstream(dir / "state/state.db", std::ios::binary) << text;
  pid_t c = Spawn({(BinDir() / "fabatlas-coordinator").string(), "--listen", "127.0.0.1:0", "--state-dir",
                   (dir / "state").string()},
                  dir / "coordinator.log");
  EXPECT_EQ(WaitExit(c, std::chrono::seconds(30)), 2) << ReadText(dir / "coordinator.log");
  const std::string log = ReadText(dir / "coordinator.log");
  EXPECT_EQ(log, "fabatlas-coordinator: " + (dir / "state/state.db").string() + ": file is not a database\n");
  EXPECT_EQ(ReadText(dir / "state/state.db"), text);
  fs::remove_all(dir);
}

// `fabatlas sample` and `fabatlas run` with a job file and --out named
// without a directory part (as typed in the job's own directory) write the
// same form as with full paths.
TEST(OpsCli, JobFileAndOutWithoutADirectoryPart) {
  fs::path dir = FreshDir("ops_relative");
  fs::copy_file(SourceDir() / "configs/designs/tube_wall_2d.yaml", dir / "tube_wall_2d.yaml");
  std::string job = ReadText(JobPath());
  job.replace(job.find("../../../configs/designs/"), std::string("../../../configs/designs/").size(), "");
  std::ofstream(dir / "job.yaml") << job;
  const std::string bin = (BinDir() / "fabatlas").string();
  auto [full_status, full_out] =
      Shell(dir, bin + " sample " + (dir / "job.yaml").string() + " --out " + (dir / "full").string());
  ASSERT_EQ(full_status, 0) << full_out;
  auto [sample_status, sample_out] = Shell(dir, bin + " sample job.yaml --out out");
  ASSERT_EQ(sample_status, 0) << sample_out;
  EXPECT_EQ(sample_out.find("internal error"), std::string::npos) << sample_out;
  EXPECT_EQ(ReadText(dir / "out/form.json"), ReadText(dir / "full/form.json"));
  auto [run_status, run_out] = Shell(dir, bin + " run job.yaml --workers 2 --out cluster --quiet");
  ASSERT_EQ(run_status, 0) << run_out;
  EXPECT_EQ(ReadText(dir / "cluster/form.json"), ReadText(dir / "full/form.json"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fabatlas::ops_test

namespace fabatlas::ops_test {
namespace {

// A full disk under the coordinator's state: the job stalls, the operator
// is told at once (an error log line, the reason in `fabatlas status`, the
// fabatlas_state_stalled metric), and when space comes back the job
// finishes with the same form as an in-process run: nothing lost.
TEST(OpsDiskFull, CoordinatorStateOnAFullFileSystemStallsVisiblyAndLosesNothing) {
  if (!testing::SmallFileSystem::Possible()) GTEST_SKIP() << "mounting a small tmpfs needs root";
  fs::path dir = FreshDir("ops_diskfull");
  testing::SmallFileSystem disk(dir / "mnt", 64);
  ASSERT_TRUE(disk.mounted()) << disk.error();
  const fs::path mnt = disk.dir();
  const int metrics_port = FreePort();
  // The log goes beside the small file system, not onto it.
  const fs::path log = dir / "coordinator.log";
  CoordinatorProcess c;
  c.pid = Spawn({(BinDir() / "fabatlas-coordinator").string(), "--listen", "127.0.0.1:0", "--state-dir",
                 (mnt / "state").string(), "--port-file", (dir / "port").string(), "--log-format", "json", "--metrics",
                 "127.0.0.1:" + std::to_string(metrics_port)},
                log);
  ASSERT_TRUE(WaitForText(dir / "port", "\n", c.pid)) << ReadText(log);
  c.port = std::atoi(ReadText(dir / "port").c_str());
  std::string id = Client(c.port).Submit(JobPath());
  // The driver has queued the first round; no worker yet. Now fill the disk.
  for (int i = 0; i < 500 && Client(c.port).Status(id).tasks_queued() == 0; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  disk.Fill();
  pid_t w = StartWorker(c.port, dir / "w", {"--log-format", "json"});
  v1::JobStatus s;
  for (int i = 0; i < 600 && s.stalled_reason().empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    s = Client(c.port).Status(id);
  }
  EXPECT_EQ(s.state(), v1::JOB_STATE_RUNNING);
  EXPECT_NE(s.stalled_reason().find("cannot write its state"), std::string::npos) << s.stalled_reason();
  EXPECT_NE(coordinator::ProgressLine(s).find("STALLED: "), std::string::npos);
  auto [status_code, status_out] = Shell(
      dir, (BinDir() / "fabatlas").string() + " status " + id + " --coordinator 127.0.0.1:" + std::to_string(c.port));
  EXPECT_EQ(status_code, 0);
  EXPECT_NE(status_out.find("STALLED: coordinator cannot write its state"), std::string::npos) << status_out;
  auto [metrics_status, metrics] = HttpGet(metrics_port, "/metrics");
  ASSERT_EQ(metrics_status, 200) << metrics;
  EXPECT_NE(metrics.find("\nfabatlas_state_stalled 1\n"), std::string::npos) << metrics;
  EXPECT_NE(metrics.find("\nfabatlas_state_free_bytes 0\n"), std::string::npos) << metrics;
  EXPECT_EQ(metrics.find("\nfabatlas_state_write_failures_total 0\n"), std::string::npos) << metrics;
  bool logged = false;
  for (const auto& j : JsonLines(log))
    if (j["event"] == "state_write_failed") {
      logged = true;
      EXPECT_EQ(j["level"], "error");
      EXPECT_NE(j["error"].get<std::string>().find(mnt.string()), std::string::npos) << j;
    }
  EXPECT_TRUE(logged) << ReadText(log);

  // Space comes back: the job finishes, and its form is the in-process one.
  disk.Free();
  s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  EXPECT_TRUE(s.stalled_reason().empty()) << s.stalled_reason();
  auto outputs = Client(c.port).Fetch(id);
  EXPECT_EQ(outputs["form.json"], InProcessForm(dir));
  // The stall ends once no write has failed for 5 s; the job may finish
  // sooner, so wait for the recovery line rather than for the job.
  EXPECT_TRUE(WaitForText(log, "state_write_recovered", c.pid)) << ReadText(log);
  ::kill(w, SIGTERM);
  EXPECT_EQ(WaitExit(w, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  bool recovered = false;
  for (const auto& j : JsonLines(log)) recovered |= j["event"] == "state_write_recovered";
  EXPECT_TRUE(recovered);
}

// A full disk under a worker's cache directory (--cache-dir), where it
// unpacks each job's bundle: every task it leases fails with one line
// naming the file and the full disk (worker log task_failed; the
// coordinator requeues the task), no partial file is left for a later lease
// to read, the job is neither failed nor quarantined, and once space is
// back the same worker loads the job and finishes it with the in-process
// form.
TEST(OpsDiskFull, WorkerCacheDirOnAFullFileSystemFailsTasksCleanlyAndRecovers) {
  if (!testing::SmallFileSystem::Possible()) GTEST_SKIP() << "mounting a small tmpfs needs root";
  fs::path dir = FreshDir("ops_cachefull");
  testing::SmallFileSystem disk(dir / "mnt", 2);
  ASSERT_TRUE(disk.mounted()) << disk.error();
  disk.Fill();
  CoordinatorProcess c = StartCoordinator(dir / "state", 0, {"--retry-backoff-ms", "50"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  pid_t w = Spawn({(BinDir() / "fabatlas-worker").string(), "--coordinator", "127.0.0.1:" + std::to_string(c.port),
                   "--cache-dir", (disk.dir() / "cache").string(), "--log-format", "json"},
                  dir / "worker.log");
  std::string id = Client(c.port).Submit(JobPath());
  ASSERT_TRUE(WaitForText(dir / "worker.log", "task_failed", w)) << ReadText(dir / "worker.log");
  auto failed = Events(JsonLines(dir / "worker.log"), "task_failed");
  ASSERT_FALSE(failed.empty());
  const std::string reason = failed.front().value("reason", "");
  EXPECT_NE(reason.find((disk.dir() / "cache").string()), std::string::npos) << reason;
  EXPECT_NE(reason.find("disk full while writing"), std::string::npos) << reason;
  EXPECT_EQ(reason.find('\n'), std::string::npos) << reason;
  v1::JobStatus s = Client(c.port).Status(id);
  EXPECT_EQ(s.state(), v1::JOB_STATE_RUNNING);
  EXPECT_EQ(s.tasks_quarantined(), 0);
  EXPECT_EQ(s.tasks_done(), 0);
  // Nothing half-written: only directories (and the filler, and the worker's
  // lock, empty as the disk is full) on the disk. The
  // worker keeps leasing and failing meanwhile, so a write it has under way
  // may show its temporary file (never read by a lease); that none is left
  // behind is checked once the worker has exited, below.
  auto under_way = [](const fs::path& p) { return p.filename().string().find(".tmp-") != std::string::npos; };
  for (const auto& entry : fs::recursive_directory_iterator(disk.dir()))
    EXPECT_TRUE(entry.is_directory() || entry.path().filename() == ".filler" ||
                entry.path() == disk.dir() / "cache/LOCK" || under_way(entry.path()))
        << "left behind: " << entry.path();

  disk.Free();
  s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  EXPECT_EQ(s.tasks_quarantined(), 0);
  auto outputs = Client(c.port).Fetch(id);
  EXPECT_EQ(outputs["form.json"], InProcessForm(dir));
  // The bundle the worker unpacked once space was back is whole.
  std::set<std::string> unpacked;
  for (const auto& entry : fs::recursive_directory_iterator(disk.dir() / "cache"))
    if (entry.is_regular_file()) unpacked.insert(entry.path().filename().string());
  EXPECT_TRUE(unpacked.count("tube_small.yaml") && unpacked.count("tube_wall_2d.yaml")) << unpacked.size();
  ::kill(w, SIGTERM);
  EXPECT_EQ(WaitExit(w, std::chrono::seconds(30)), 0);
  for (const auto& entry : fs::recursive_directory_iterator(disk.dir()))
    EXPECT_FALSE(under_way(entry.path())) << "left behind: " << entry.path();
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
}

}  // namespace
}  // namespace fabatlas::ops_test

namespace fabatlas::ops_test {
namespace {

// stdout of a shell command line run in `dir` (stderr dropped), and its status.
std::pair<int, std::string> Stdout(const fs::path& dir, const std::string& command) {
  return Shell(dir, command, false);
}

// --json on submit, watch, status, jobs and run: every line a user's script
// reads is one JSON object, with the numbers the progress line shows.
TEST(OpsCli, JsonOutputOfSubmitWatchStatusJobsAndRun) {
  fs::path dir = FreshDir("ops_json");
  CoordinatorProcess c = StartCoordinator(dir / "state", 0, {"--log-level", "warn"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  pid_t w = StartWorker(c.port, dir / "w", {"--log-level", "warn"});
  const std::string bin = (BinDir() / "fabatlas").string();
  const std::string at = " --coordinator 127.0.0.1:" + std::to_string(c.port);

  auto [submit_code, submit_out] = Stdout(dir, bin + " submit " + JobPath().string() + at + " --json");
  ASSERT_EQ(submit_code, 0) << submit_out;
  nlohmann::json submitted = nlohmann::json::parse(submit_out);
  const std::string id = submitted["job_id"];
  EXPECT_EQ(id.size(), 16u);
  EXPECT_EQ(submitted["created"], true);

  auto [watch_code, watch_out] = Stdout(dir, bin + " watch " + id + at + " --json");
  EXPECT_EQ(watch_code, 0) << watch_out;
  std::istringstream lines(watch_out);
  std::string line;
  nlohmann::json last;
  int updates = 0;
  while (std::getline(lines, line)) {
    last = nlohmann::json::parse(line);  // throws on a line that is not JSON
    EXPECT_EQ(last["job_id"], id);
    ++updates;
  }
  EXPECT_GE(updates, 1);
  EXPECT_EQ(last["state"], "SUCCEEDED");

  v1::JobStatus s = Client(c.port).Status(id);
  auto [status_code, status_out] = Stdout(dir, bin + " status " + id + at + " --json");
  ASSERT_EQ(status_code, 0) << status_out;
  nlohmann::json status = nlohmann::json::parse(status_out);
  EXPECT_EQ(status["state"], "SUCCEEDED");
  EXPECT_EQ(status["samples_done"], s.samples_done());
  EXPECT_EQ(status["samples_valid"], s.samples_valid());
  EXPECT_EQ(status["tasks_done"], status["tasks_total"]);
  EXPECT_EQ(last["samples_done"], s.samples_done());

  auto [jobs_code, jobs_out] = Stdout(dir, bin + " jobs" + at + " --json");
  ASSERT_EQ(jobs_code, 0) << jobs_out;
  nlohmann::json jobs = nlohmann::json::parse(jobs_out);
  ASSERT_EQ(jobs["jobs"].size(), 1u);
  EXPECT_EQ(jobs["jobs"][0]["job_id"], id);

  auto [run_code, run_out] = Stdout(dir, bin + " run " + JobPath().string() + " --workers 1 --out run --json");
  ASSERT_EQ(run_code, 0) << run_out;
  nlohmann::json run = nlohmann::json::parse(run_out);
  EXPECT_EQ(run["job"]["state"], "SUCCEEDED");
  EXPECT_EQ(run["job"]["samples_done"], s.samples_done());  // the same job, computed again
  bool form = false;
  for (const auto& path : run["outputs"]) {
    EXPECT_TRUE(fs::exists(dir / path.get<std::string>())) << path;
    form |= fs::path(path.get<std::string>()).filename() == "form.json";
  }
  EXPECT_TRUE(form) << run_out;
  // fetch: the coordinator's outputs of the submitted job, the same form.
  auto [fetch_code, fetch_out] = Shell(dir, bin + " fetch " + id + at + " --out fetched");
  ASSERT_EQ(fetch_code, 0) << fetch_out;
  EXPECT_EQ(ReadText(dir / "fetched/form.json"), ReadText(dir / "run/form.json"));
  EXPECT_FALSE(ReadText(dir / "fetched/form.json").empty());

  ::kill(w, SIGTERM);
  EXPECT_EQ(WaitExit(w, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  fs::remove_all(dir);
}

// What submit, fetch and jobs cannot do, each said in one line with exit
// status 2, paths as typed: a job file that is not there, one naming a
// design that is not there, fetching a job that has not finished (nothing
// written) and a job that does not exist; jobs lists the running job.
TEST(OpsCli, SubmitFetchAndJobsRefuseWhatTheyCannotDoInOneLine) {
  fs::path dir = FreshDir("ops_refusals");
  CoordinatorProcess c = StartCoordinator(dir / "state", 0, {"--log-level", "warn"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  const std::string bin = (BinDir() / "fabatlas").string();
  const std::string at = " --coordinator 127.0.0.1:" + std::to_string(c.port);
  auto expect_refused = [&](const std::string& args, const std::string& says) {
    auto [code, out] = Shell(dir, bin + " " + args + at);
    EXPECT_EQ(code, 2) << args << ": " << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << args << ": " << out;
    EXPECT_NE(out.find(says), std::string::npos) << args << ": " << out;
  };
  expect_refused("submit nothing.yaml", "nothing.yaml");
  std::ofstream(dir / "bad.yaml") << "design: nowhere.yaml\n";
  expect_refused("submit bad.yaml", "nowhere.yaml");
  // No worker: the job stays RUNNING.
  auto [submit_code, submit_out] = Stdout(dir, bin + " submit " + JobPath().string() + at);
  ASSERT_EQ(submit_code, 0) << submit_out;
  const std::string id = submit_out.substr(0, submit_out.find_first_of(" \n"));
  ASSERT_EQ(id.size(), 16u) << submit_out;
  expect_refused("fetch " + id + " --out early", "is JOB_STATE_RUNNING");
  EXPECT_FALSE(fs::exists(dir / "early"));
  expect_refused("fetch 0123456789abcdef --out none", "NOT_FOUND");
  EXPECT_FALSE(fs::exists(dir / "none"));
  auto [jobs_code, jobs_out] = Stdout(dir, bin + " jobs" + at);
  EXPECT_EQ(jobs_code, 0) << jobs_out;
  EXPECT_EQ(std::count(jobs_out.begin(), jobs_out.end(), '\n'), 1) << jobs_out;
  EXPECT_NE(jobs_out.find(id), std::string::npos) << jobs_out;
  EXPECT_NE(jobs_out.find("RUNNING"), std::string::npos) << jobs_out;
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  if (!HasFailure()) fs::remove_all(dir);
}

// Every subcommand's --help exits 0, shows defaults and speaks the user's
// words (no bare "seed 001" references to the papers); the benchmarks'
// --help prints usage instead of running them.
TEST(OpsCli, HelpShowsDefaultsInTheUsersWords) {
  fs::path dir = FreshDir("ops_help");
  const std::string bin = (BinDir() / "fabatlas").string();
  auto [top_code, top] = Stdout(dir, bin + " --help");
  ASSERT_EQ(top_code, 0) << top;
  std::vector<std::string> subcommands;
  std::istringstream in(top.substr(top.find("Subcommands:")));
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string name;
    if (words >> name) subcommands.push_back(name);
  }
  EXPECT_GE(subcommands.size(), 10u) << top;
  for (const auto& sub : subcommands) {
    auto [code, help] = Stdout(dir, bin + " " + sub + " --help");
    EXPECT_EQ(code, 0) << sub;
    EXPECT_EQ(help.find("seed 0"), std::string::npos) << sub << ":\n" << help;
    EXPECT_EQ(help.find("seed-0"), std::string::npos) << sub << ":\n" << help;
  }
  EXPECT_NE(Stdout(dir, bin + " run --help").second.find("--workers INT=2"), std::string::npos);
  EXPECT_NE(Stdout(dir, bin + " status --help").second.find("=127.0.0.1:7450"), std::string::npos);
  auto coordinator = Stdout(dir, (BinDir() / "fabatlas-coordinator").string() + " --help").second;
  EXPECT_NE(coordinator.find("--lease-ms INT=30000"), std::string::npos) << coordinator;
  EXPECT_NE(coordinator.find("--log-format TEXT=text"), std::string::npos) << coordinator;
  auto worker = Stdout(dir, (BinDir() / "fabatlas-worker").string() + " --help").second;
  EXPECT_NE(worker.find("--slots INT=1"), std::string::npos) << worker;
  const fs::path bench = BinDir() / "cluster_bench";
  if (fs::exists(bench)) {
    auto [code, help] = Stdout(dir, bench.string() + " --help");
    EXPECT_EQ(code, 0);
    EXPECT_NE(help.find("--tasks INT=20000"), std::string::npos) << help;
    EXPECT_EQ(help.find("round trips/s"), std::string::npos) << "cluster_bench --help ran the benchmark";
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fabatlas::ops_test

namespace fabatlas::ops_test {
namespace {

// What the drain tests start from: a coordinator, one worker connected to it
// and the test job submitted, the worker holding a lease.
struct LeaseHeld {
  CoordinatorProcess coordinator;
  pid_t worker = -1;
  std::string job_id;
};

// Starts a coordinator in dir/state with `coordinator_args`, a worker in
// dir/<worker_dir> with `worker_args`, submits the job and returns once the
// worker holds a lease (event-driven: the job's status says so).
void StartUntilALeaseIsHeld(const fs::path& dir, const std::vector<std::string>& coordinator_args,
                            const std::string& worker_dir, const std::vector<std::string>& worker_args,
                            LeaseHeld& run) {
  run.coordinator = StartCoordinator(dir / "state", 0, coordinator_args);
  ASSERT_GT(run.coordinator.port, 0) << ReadText(dir / "state/coordinator.log");
  run.worker = StartWorker(run.coordinator.port, dir / worker_dir, worker_args);
  ASSERT_TRUE(WaitForText(dir / worker_dir / "worker.log", "worker_connected", run.worker));
  run.job_id = Client(run.coordinator.port).Submit(JobPath());
  v1::JobStatus s;
  for (int i = 0; i < 3000 && s.tasks_leased() == 0; ++i) {
    s = Client(run.coordinator.port).Status(run.job_id);
    if (s.tasks_leased() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_GT(s.tasks_leased(), 0);
}

// SIGTERM to a coordinator while a worker holds a lease: it stops handing
// out leases, waits for the running one (up to --drain-seconds), accepts
// its result and exits 0; started again (here with --fsync-commits, one
// WAL fsync per commit) it resumes the job, which ends with the in-process
// run's form.
TEST(OpsDrain, SigtermWaitsForRunningLeasesThenTheJobResumes) {
  fs::path dir = FreshDir("ops_drain");
  LeaseHeld run;
  ASSERT_NO_FATAL_FAILURE(
      StartUntilALeaseIsHeld(dir, {"--log-format", "json", "--drain-seconds", "120", "--lease-ms", "60000"}, "w",
                             {"--log-format", "json", "--connect-timeout", "120"}, run));
  CoordinatorProcess c = run.coordinator;
  const pid_t w = run.worker;
  const std::string id = run.job_id;
  // The worker holds a lease: freeze it there.
  ::kill(w, SIGSTOP);
  const std::int64_t done_before = Client(c.port).Status(id).tasks_done();
  ::kill(c.pid, SIGTERM);
  ASSERT_TRUE(WaitForText(dir / "state/coordinator.log", "drain_started", c.pid));
  // Draining: the coordinator is still there, waiting for the lease.
  EXPECT_EQ(WaitExit(c.pid, std::chrono::milliseconds(500)), -1);
  ::kill(w, SIGCONT);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(120)), 0);
  auto lines = JsonLines(dir / "state/coordinator.log");
  auto started = Events(lines, "drain_started");
  auto finished = Events(lines, "drain_finished");
  ASSERT_EQ(started.size(), 1u);
  ASSERT_EQ(finished.size(), 1u);
  EXPECT_GE(started[0]["active_leases"].get<int>(), 1);
  EXPECT_EQ(finished[0]["active_leases"], 0);
  {
    storage::JobStore store(dir / "state/state.db");
    EXPECT_EQ(store.ActiveLeases(), 0);
    EXPECT_GT(store.CountTasks(id).done, done_before);  // the drained lease's result was kept
    EXPECT_EQ(store.CheckConsistency(), std::vector<std::string>{});
  }
  // Started again, with --fsync-commits: the job resumes and finishes.
  c = StartCoordinator(dir / "state", 0, {"--log-format", "json", "--fsync-commits"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  ::kill(w, SIGTERM);  // it was pointed at the old port
  EXPECT_EQ(WaitExit(w, std::chrono::seconds(60)), 0) << ReadText(dir / "w/worker.log");
  pid_t w2 = StartWorker(c.port, dir / "w2", {"--log-format", "json"});
  v1::JobStatus s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  auto outputs = Client(c.port).Fetch(id);
  EXPECT_EQ(outputs["form.json"], InProcessForm(dir));
  auto resumed = Events(JsonLines(dir / "state/coordinator.log"), "coordinator_started");
  ASSERT_EQ(resumed.size(), 2u);
  EXPECT_EQ(resumed[1]["jobs_resumed"], 1);
  ::kill(w2, SIGTERM);
  EXPECT_EQ(WaitExit(w2, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  fs::remove_all(dir);
}

// --drain-seconds bounds the drain: a lease whose worker is frozen (SIGSTOP)
// cannot finish, so the coordinator stops waiting after the bound and exits
// 0 with the lease still on record (drain_finished says so). Started again,
// it carries that lease through its grace period, expires it, and another
// worker recomputes the task: the job ends with the in-process form, and
// the frozen worker's lease is the one that expired.
TEST(OpsDrain, DrainSecondsBoundsTheWaitAndAStuckLeaseIsRecomputedAfterRestart) {
  fs::path dir = FreshDir("ops_drain_bound");
  // Leases outlive the 1 s drain by far (10 s), so only the bound can end it.
  LeaseHeld run;
  ASSERT_NO_FATAL_FAILURE(
      StartUntilALeaseIsHeld(dir, {"--log-format", "json", "--drain-seconds", "1", "--lease-ms", "10000"}, "stuck",
                             {"--id", "stuck", "--log-format", "json"}, run));
  CoordinatorProcess c = run.coordinator;
  const pid_t stuck = run.worker;
  const std::string id = run.job_id;
  ::kill(stuck, SIGSTOP);
  ::kill(c.pid, SIGTERM);
  // The worker stays frozen: only the bound can end the drain.
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(60)), 0) << ReadText(dir / "state/coordinator.log");
  auto lines = JsonLines(dir / "state/coordinator.log");
  auto started = Events(lines, "drain_started");
  auto finished = Events(lines, "drain_finished");
  ASSERT_EQ(started.size(), 1u);
  ASSERT_EQ(finished.size(), 1u);
  EXPECT_EQ(started[0]["timeout_ms"], 1000);
  EXPECT_GE(finished[0]["active_leases"].get<int>(), 1) << finished[0];
  EXPECT_GE(finished[0]["waited_ms"].get<int>(), 1000) << finished[0];  // it did wait for the lease
  std::int64_t held = 0;
  {
    storage::JobStore store(dir / "state/state.db");
    held = store.ActiveLeases();
    EXPECT_GE(held, 1);
    EXPECT_EQ(store.CheckConsistency(), std::vector<std::string>{});
  }
  KillAndReap(stuck);

  c = StartCoordinator(dir / "state", 0, {"--log-format", "json", "--lease-ms", "1500", "--heartbeat-ms", "300"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  pid_t w = StartWorker(c.port, dir / "w", {"--id", "fresh", "--log-format", "json"});
  v1::JobStatus s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  auto restarted = Events(JsonLines(dir / "state/coordinator.log"), "coordinator_started");
  ASSERT_EQ(restarted.size(), 2u);
  EXPECT_EQ(restarted[1]["leases_in_grace"], held);
  EXPECT_EQ(restarted[1]["jobs_resumed"], 1);
  std::int64_t stuck_expired = 0;
  for (const auto& e : Events(JsonLines(dir / "state/coordinator.log"), "lease_expired"))
    stuck_expired += e["worker"] == "stuck";
  EXPECT_EQ(stuck_expired, held);
  auto outputs = Client(c.port).Fetch(id);
  EXPECT_EQ(outputs["form.json"], InProcessForm(dir));
  ::kill(w, SIGTERM);
  EXPECT_EQ(WaitExit(w, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  {
    storage::JobStore store(dir / "state/state.db");
    EXPECT_EQ(store.ActiveLeases(), 0);
    EXPECT_EQ(store.CheckConsistency(), std::vector<std::string>{});
    for (const auto& task : store.Tasks(id)) EXPECT_EQ(task.completions, 1) << task.key;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fabatlas::ops_test
