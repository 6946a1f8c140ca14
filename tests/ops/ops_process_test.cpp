// Operations as an operator meets them (issue 16): real coordinator and
// worker processes on loopback, their JSON log lines, SIGTERM, and the CLI
// with paths typed the way users type them.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "../cluster/cluster_process.h"
#include "fabatlas/coordinator/job_client.h"
#include "fabatlas/error.h"

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

std::vector<nlohmann::json> Events(const std::vector<nlohmann::json>& lines, const std::string& event) {
  std::vector<nlohmann::json> out;
  for (const auto& j : lines)
    if (j.value("event", "") == event) out.push_back(j);
  return out;
}

// Runs a shell command line in `dir`; exit status and stdout+stderr.
std::pair<int, std::string> Shell(const fs::path& dir, const std::string& command) {
  std::string cmd = "cd '" + dir.string() + "' && " + command + " 2>&1";
  FILE* pipe = ::popen(cmd.c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  std::size_t n;
  while ((n = std::fread(buf.data(), 1, buf.size(), pipe)) > 0) out.append(buf.data(), n);
  int status = ::pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(OpsLogs, JsonLinesTellTheStoryOfAJobWithAKilledWorker) {
  fs::path dir = FreshDir("ops_logs");
  CoordinatorProcess c = StartCoordinator(dir / "state", 0,
                                          {"--lease-ms", "1500", "--retry-backoff-ms", "50", "--log-format", "json"});
  ASSERT_GT(c.port, 0) << ReadText(dir / "state/coordinator.log");
  // w1 SIGKILLs itself when it starts a task whose key begins with "0"
  // (about one task in 16): it dies holding that lease.
  ::setenv("FABATLAS_WORKER_CRASH_KEY_PREFIX", "0", 1);
  pid_t w1 = StartWorker(c.port, dir / "w1", {"--id", "w1", "--log-format", "json"});
  ::unsetenv("FABATLAS_WORKER_CRASH_KEY_PREFIX");
  ASSERT_TRUE(WaitForText(dir / "w1/worker.log", "worker_connected", w1)) << ReadText(dir / "w1/worker.log");
  std::string id = Client(c.port).Submit(JobPath());
  EXPECT_EQ(WaitExit(w1, std::chrono::seconds(120)), 128 + SIGKILL);
  pid_t w2 = StartWorker(c.port, dir / "w2", {"--id", "w2", "--log-format", "json"});
  v1::JobStatus s = WaitForJob(c.port, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  ::kill(w2, SIGTERM);
  EXPECT_EQ(WaitExit(w2, std::chrono::seconds(30)), 0);
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);

  auto coordinator = JsonLines(dir / "state/coordinator.log");
  for (const char* event : {"coordinator_started", "job_submitted", "job_started", "round_started", "worker_joined",
                            "lease_expired", "job_succeeded", "signal_received", "drain_started", "drain_finished",
                            "coordinator_stopped"})
    EXPECT_FALSE(Events(coordinator, event).empty()) << "coordinator logged no " << event;
  // The expiry names the task, the worker that died and the attempt.
  auto expired = Events(coordinator, "lease_expired");
  ASSERT_FALSE(expired.empty());
  EXPECT_EQ(expired[0]["worker"], "w1");
  EXPECT_EQ(expired[0]["task"].get<std::string>().substr(0, 1), "0");
  EXPECT_EQ(expired[0]["attempt"], 1);
  EXPECT_EQ(expired[0]["job"], id);
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
  auto [full_status, full_out] = Shell(dir, bin + " sample " + (dir / "job.yaml").string() + " --out " +
                                                (dir / "full").string());
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
