// Power loss and I/O faults under a real coordinator (issue 31): a
// fabatlas-coordinator process runs with power_loss_shim.cc preloaded over
// its state directory, one fabatlas-worker process works over gRPC, and the
// job is tests/cluster/data/tube_power.yaml.
//
// Power loss. At a crash point chosen from a seed (the k-th write, sync,
// truncation, rename or unlink under the state directory, k uniform over an
// undisturbed run's count) the shim drops every write not yet fsynced (or, in
// torn mode, a random half of its 4 KiB blocks) and SIGKILLs the coordinator.
// Then, before anything restarts: `PRAGMA integrity_check` is ok; a job whose
// Submit was answered exists; every finished blob hashes to its name; and
// every result the worker saw acknowledged (its results_acknowledged debug
// lines) is done in the store when --fsync-commits is on (without it, the
// lost ones are counted). A coordinator started again on the same directory
// finishes the job with an artifact byte-identical to the in-process run.
// Each point prints its seed; FABATLAS_POWER_SEED=S runs that point alone.
//
// I/O faults. The shim fails the k-th write of the job store (state.db and
// its WAL) or of the blob store, and every s-th after it, with EIO or ENOSPC
// for 300 ms each: the coordinator logs state_write_failed, stalls, and once
// the fault clears finishes the job with the same artifact, every task
// completed once.
//
// CI runs a few points (seconds each); FABATLAS_POWER_POINTS=N runs N points
// per durability mode and FABATLAS_FAULT_STRIDE=s every offset 1..s of the
// fault loops (bench/power_loss.sh; docs/testing.md, "Power loss and I/O
// faults", has the figures).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <sqlite3.h>

#include <cstdlib>
#include <iostream>
#include <random>
#include <set>
#include <sstream>

#include "cluster_job.h"
#include "cluster_process.h"
#include "fabatlas/coordinator/coordinator.h"
#include "in_process_job.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"

using namespace fabatlas;
using namespace fabatlas::cluster_test;

namespace {

fs::path JobPath() { return SourceDir() / "tests/cluster/data/tube_power.yaml"; }
const char* const kArtifactName = "tube_wall_2d.fabatlas";
fs::path ShimPath() { return BinDir() / "libfabatlas_power_loss_shim.so"; }

const std::vector<std::string> kFastLeases = {"--lease-ms",         "1500", "--heartbeat-ms",     "300",
                                              "--retry-backoff-ms", "50",   "--quarantine-after", "1000"};

const std::string& ReferenceArtifact() {
  static const std::string bytes = [] {
    const fs::path d = FreshDir("power_reference");
    EXPECT_EQ(RunInProcess(JobPath(), d).artifact_file, kArtifactName);
    return ReadText(d / kArtifactName);
  }();
  return bytes;
}

std::int64_t EnvInt(const char* name, std::int64_t fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::atoll(v) : fallback;
}

// splitmix64: a seed's crash point and torn flag, the same on every machine.
std::uint64_t Mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

std::vector<std::string> ShimEnv(const fs::path& state, const std::vector<std::string>& more) {
  std::vector<std::string> env = {"LD_PRELOAD=" + ShimPath().string(), "FABATLAS_SHIM_ROOT=" + state.string()};
  env.insert(env.end(), more.begin(), more.end());
  return env;
}

std::map<std::string, std::int64_t> ReadCounts(const fs::path& file) {
  std::map<std::string, std::int64_t> counts;
  std::istringstream in(ReadText(file));
  std::string name;
  std::int64_t value = 0;
  while (in >> name >> value) counts[name] = value;
  return counts;
}

// Lease ids the worker saw acknowledged (results_acknowledged lines).
std::vector<std::string> AcknowledgedLeases(const fs::path& worker_log) {
  std::vector<std::string> ids;
  std::istringstream in(ReadText(worker_log));
  std::string line;
  while (std::getline(in, line)) {
    if (line.find("results_acknowledged") == std::string::npos) continue;
    auto j = nlohmann::json::parse(line, nullptr, false);
    if (j.is_discarded() || !j.contains("leases")) continue;
    std::istringstream list(j["leases"].get<std::string>());
    std::string id;
    while (std::getline(list, id, ',')) ids.push_back(id);
  }
  return ids;
}

std::vector<std::string> WorkerArgs() { return {"--slots", "2", "--log-level", "debug", "--log-format", "json"}; }

// What the store holds right after a cut, read as the next coordinator
// would read it (SQLite recovers the WAL on open).
struct AfterCut {
  std::string integrity;  // "ok" or SQLite's report
  bool job_exists = false;
  std::int64_t acknowledged = 0;  // results the worker saw acknowledged
  std::int64_t lost = 0;          // of them, not done in the store
  std::int64_t bad_blobs = 0;     // finished blobs that do not hash to their name
};

AfterCut ReadAfterCut(const fs::path& state, const std::string& job_id, const std::vector<std::string>& acked) {
  AfterCut a;
  if (!fs::exists(state / "state.db")) {  // the cut came before the store was created: a fresh start
    a.integrity = "ok";
    return a;
  }
  sqlite3* db = nullptr;
  if (sqlite3_open_v2((state / "state.db").c_str(), &db, SQLITE_OPEN_READWRITE, nullptr) != SQLITE_OK) {
    a.integrity = std::string("cannot open: ") + sqlite3_errmsg(db);
    sqlite3_close(db);
    return a;
  }
  auto query = [&](const std::string& sql, const std::vector<std::string>& args, auto row) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, sql.c_str(), -1, &s, nullptr) != SQLITE_OK) {
      a.integrity = sql + ": " + sqlite3_errmsg(db);
      return;
    }
    for (std::size_t i = 0; i < args.size(); ++i)
      sqlite3_bind_text(s, static_cast<int>(i + 1), args[i].c_str(), -1, SQLITE_TRANSIENT);
    while (sqlite3_step(s) == SQLITE_ROW) row(s);
    sqlite3_finalize(s);
  };
  query("PRAGMA integrity_check", {},
        [&](sqlite3_stmt* s) { a.integrity += reinterpret_cast<const char*>(sqlite3_column_text(s, 0)); });
  if (!job_id.empty()) query("SELECT 1 FROM jobs WHERE id = ?", {job_id}, [&](sqlite3_stmt*) { a.job_exists = true; });
  for (const auto& id : acked) {
    ++a.acknowledged;
    bool done = false;
    query("SELECT t.state, t.completions FROM leases l JOIN tasks t ON t.key = l.task_key WHERE l.lease_id = ?", {id},
          [&](sqlite3_stmt* s) { done = sqlite3_column_int(s, 0) >= 2 && sqlite3_column_int(s, 1) == 1; });
    if (!done) ++a.lost;
  }
  sqlite3_close(db);
  if (fs::exists(state / "blobs")) {
    storage::BlobStore blobs(state / "blobs");
    for (const auto& d : blobs.List())
      if (!blobs.Verify(d)) ++a.bad_blobs;
  }
  return a;
}

// Stops the coordinator and checks the store: consistent, every task done once.
void StopAndCheck(const CoordinatorProcess& c, const fs::path& state, const std::string& id, const std::string& what) {
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0) << what;
  storage::JobStore store(state / "state.db");
  EXPECT_EQ(store.CheckConsistency(), std::vector<std::string>{}) << what;
  const storage::TaskCounts counts = store.CountTasks(id);
  EXPECT_EQ(counts.done, counts.total) << what;
  for (const auto& task : store.Tasks(id)) EXPECT_EQ(task.completions, 1) << what << " " << task.key;
  storage::BlobStore blobs(state / "blobs");
  for (const auto& d : blobs.List()) EXPECT_TRUE(blobs.Verify(d)) << what << " blob " << d;
}

// The undisturbed job under the shim (nothing injected): its watched events
// and store and blob writes, and the artifact it publishes.
std::map<std::string, std::int64_t> CountEvents(bool fsync_commits) {
  const fs::path dir = FreshDir(std::string("power_count_") + (fsync_commits ? "fsync" : "nofsync"));
  const fs::path state = dir / "state";
  std::vector<std::string> args = kFastLeases;
  if (fsync_commits) args.push_back("--fsync-commits");
  CoordinatorProcess c =
      StartCoordinator(state, 0, args, ShimEnv(state, {"FABATLAS_SHIM_EVENTS=" + (dir / "events").string()}));
  EXPECT_GT(c.port, 0) << ReadText(state / "coordinator.log");
  pid_t worker = StartWorker(c.port, dir / "w", WorkerArgs());
  const std::string id = Client(c.port).Submit(JobPath());
  const v1::JobStatus s = WaitForJob([&] { return c.port; }, id, std::chrono::seconds(120));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << s.error();
  EXPECT_TRUE(Client(c.port).Fetch(id)[kArtifactName] == ReferenceArtifact());
  ::kill(worker, SIGTERM);
  WaitExit(worker, std::chrono::seconds(30));
  ::kill(c.pid, SIGTERM);
  EXPECT_EQ(WaitExit(c.pid, std::chrono::seconds(30)), 0);
  return ReadCounts(dir / "events");
}

std::int64_t EventsOfRun(bool fsync_commits) {
  static std::map<bool, std::int64_t> events;
  if (!events.count(fsync_commits)) {
    const auto counts = CountEvents(fsync_commits);
    events[fsync_commits] = counts.at("events");
    std::cerr << "undisturbed job" << (fsync_commits ? " with --fsync-commits" : "") << ": " << counts.at("events")
              << " watched events, " << counts.at("store_writes") << " job store writes, " << counts.at("blob_writes")
              << " blob store writes\n";
  }
  return events[fsync_commits];
}

// Failures recorded so far in the running test (a point failed when it grew).
int FailuresSoFar() {
  const ::testing::TestResult* r = ::testing::UnitTest::GetInstance()->current_test_info()->result();
  int n = 0;
  for (int i = 0; i < r->total_part_count(); ++i) n += r->GetTestPartResult(i).failed();
  return n;
}

struct PointOutcome {
  bool cut = false;  // the coordinator died at its crash point
  std::int64_t acknowledged = 0, lost = 0;
  double cut_seconds = 0, total_seconds = 0;  // from the point's start
  bool failed = false;
};

// One seeded crash point: the job under the shim until the cut, the checks
// after it, then a coordinator without the shim finishes the job.
PointOutcome RunPoint(std::uint64_t seed, bool fsync_commits) {
  const std::int64_t events = EventsOfRun(fsync_commits);
  const std::uint64_t r = Mix(seed);
  const std::int64_t crash_at =
      1 + static_cast<std::int64_t>(r % static_cast<std::uint64_t>(std::max<std::int64_t>(events, 1)));
  const bool torn = (Mix(r) & 3) == 0;  // a quarter of the points tear and reorder blocks
  const std::string what = "seed " + std::to_string(seed) + (fsync_commits ? " --fsync-commits" : "") +
                           " (crash at event " + std::to_string(crash_at) + " of " + std::to_string(events) +
                           (torn ? ", torn" : "") + "; rerun: FABATLAS_POWER_SEED=" + std::to_string(seed) + ")";
  SCOPED_TRACE(what);
  const int failures_before = FailuresSoFar();
  const auto started = std::chrono::steady_clock::now();
  const auto since = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(); };
  const fs::path dir = FreshDir("power_" + std::to_string(seed) + (fsync_commits ? "_fsync" : ""));
  const fs::path state = dir / "state";
  std::vector<std::string> args = kFastLeases;
  if (fsync_commits) args.push_back("--fsync-commits");
  const int port = FreePort();
  std::vector<std::string> shim = {"FABATLAS_CRASH_AT=" + std::to_string(crash_at)};
  if (torn) shim.push_back("FABATLAS_CRASH_TORN=" + std::to_string(seed | 1));
  CoordinatorProcess c = StartCoordinator(state, port, args, ShimEnv(state, shim));
  pid_t worker = StartWorker(port, dir / "w", WorkerArgs());
  std::string id;
  if (c.port > 0) {
    try {
      id = Client(port).Submit(JobPath());
    } catch (const InputError&) {  // the cut came during Submit: not acknowledged
    }
  }
  PointOutcome out;
  v1::JobStatus s;
  // StartCoordinator reaped a coordinator that died before it listened.
  bool gone = c.port == 0;
  struct Gone {};
  if (!gone && !id.empty()) {
    try {
      s = WaitForJob([&] { return port; }, id, std::chrono::seconds(120),
                     [&](const v1::JobStatus&) {
                       if (WaitExit(c.pid, std::chrono::milliseconds(0)) == -1) return;
                       gone = true;
                       throw Gone{};
                     });
    } catch (const Gone&) {
    }
  }
  // The job finished before the crash point: the shutdown may still reach it.
  if (!gone) ::kill(c.pid, SIGTERM);
  if (!gone) {
    EXPECT_NE(WaitExit(c.pid, std::chrono::seconds(60)), -1) << what;
  }
  out.cut = ReadText(state / "coordinator.log").find("power_loss_shim: power cut") != std::string::npos;
  if (!out.cut) {
    EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << what << ReadText(state / "coordinator.log");
    ::kill(worker, SIGTERM);
    WaitExit(worker, std::chrono::seconds(30));
    out.failed = FailuresSoFar() > failures_before;
    if (!out.failed && !std::getenv("FABATLAS_POWER_KEEP")) fs::remove_all(dir);
    return out;
  }
  out.cut_seconds = since();
  const AfterCut after = ReadAfterCut(state, id, AcknowledgedLeases(dir / "w/worker.log"));
  out.acknowledged = after.acknowledged;
  out.lost = after.lost;
  EXPECT_EQ(after.integrity, "ok") << what;
  if (!id.empty()) {
    EXPECT_TRUE(after.job_exists) << what << ": an acknowledged Submit was lost";
  }
  EXPECT_EQ(after.bad_blobs, 0) << what;
  if (fsync_commits) {
    EXPECT_EQ(after.lost, 0) << what << ": acknowledged results lost";
  }
  // Power back: the machine's processes start again, a coordinator without
  // the shim on the same directory and the worker on its cache directory
  // (a worker left running reconnects too, after gRPC's reconnect backoff
  // of up to 10 s: ClusterFaults.CoordinatorKilledThreeTimesResumesByReplay).
  KillAndReap(worker);
  c = StartCoordinator(state, port, kFastLeases);
  worker = StartWorker(port, dir / "w", WorkerArgs());
  EXPECT_EQ(c.port, port) << what << ReadText(state / "coordinator.log");
  if (c.port != port) {
    KillAndReap(worker);
    out.failed = true;
    return out;
  }
  id = Client(port).Submit(JobPath());  // what a client told nothing does; a no-op for a stored job
  s = WaitForJob([&] { return port; }, id, std::chrono::seconds(180));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << what << " " << s.error();
  EXPECT_TRUE(Client(port).Fetch(id)[kArtifactName] == ReferenceArtifact())
      << what << ": the artifact differs from the undisturbed run";
  ::kill(worker, SIGTERM);
  WaitExit(worker, std::chrono::seconds(30));
  StopAndCheck(c, state, id, what);
  out.total_seconds = since();
  out.failed = FailuresSoFar() > failures_before;
  if (!out.failed && !std::getenv("FABATLAS_POWER_KEEP")) fs::remove_all(dir);
  return out;
}

void RunPoints(bool fsync_commits, std::int64_t default_points) {
  ASSERT_TRUE(fs::exists(ShimPath())) << ShimPath();
  ASSERT_FALSE(ReferenceArtifact().empty());
  std::vector<std::uint64_t> seeds;
  if (const std::int64_t one = EnvInt("FABATLAS_POWER_SEED", 0); one > 0) {
    seeds.push_back(static_cast<std::uint64_t>(one));
  } else {
    const std::int64_t first = EnvInt("FABATLAS_POWER_FIRST_SEED", 1);
    for (std::int64_t i = 0; i < EnvInt("FABATLAS_POWER_POINTS", default_points); ++i)
      seeds.push_back(static_cast<std::uint64_t>(first + i));
  }
  std::int64_t points = 0, cuts = 0, acknowledged = 0, lost = 0;
  const auto started = std::chrono::steady_clock::now();
  // FABATLAS_POWER_MINUTES=m: no point starts after m minutes (a long run
  // that must end by a given time; the seeds run are the ones printed).
  const std::int64_t minutes = EnvInt("FABATLAS_POWER_MINUTES", 0);
  for (std::uint64_t seed : seeds) {
    if (minutes > 0 && std::chrono::steady_clock::now() - started > std::chrono::minutes(minutes)) break;
    PointOutcome o;
    try {
      o = RunPoint(seed, fsync_commits);
    } catch (const std::exception& e) {  // one point's error must not end the run
      ADD_FAILURE() << "seed " << seed << (fsync_commits ? " --fsync-commits" : "") << ": " << e.what();
      o.failed = true;
    }
    ++points;
    cuts += o.cut;
    acknowledged += o.acknowledged;
    lost += o.lost;
    std::cerr << "power point seed " << seed << (fsync_commits ? " fsync" : " nofsync") << ": "
              << (o.cut ? "cut" : "no cut (job finished first)") << ", acknowledged " << o.acknowledged << ", lost "
              << o.lost << ", " << o.cut_seconds << " s to the cut, " << o.total_seconds << " s in all"
              << (o.failed ? "  FAILED" : "") << "\n";
  }
  std::cerr << "power loss " << (fsync_commits ? "with" : "without") << " --fsync-commits: " << points << " points, "
            << cuts << " cuts, " << acknowledged << " acknowledged results before the cuts, " << lost
            << " of them lost, " << std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count()
            << " s\n";
  EXPECT_GT(cuts, 0);
}

TEST(PowerLoss, WithFsyncCommitsEveryAcknowledgedResultSurvivesAndTheArtifactIsTheSame) { RunPoints(true, 5); }

TEST(PowerLoss, WithoutFsyncCommitsLostWorkIsRedoneAndTheArtifactIsTheSame) { RunPoints(false, 5); }

// One fault loop: faults of `error` on every `stride`-th write of the files
// matching `match`, from write `first`, each for 300 ms.
void RunFaultLoop(const std::string& match, const std::string& error, std::int64_t first, std::int64_t stride) {
  const std::string what =
      error + " on write " + std::to_string(first) + " + n*" + std::to_string(stride) + " of '" + match + "'";
  SCOPED_TRACE(what);
  const int failures_before = FailuresSoFar();
  const auto started = std::chrono::steady_clock::now();
  const fs::path dir =
      FreshDir("fault_" + std::to_string(first) + "_" + error + (match == "state.db" ? "_store" : "_blobs"));
  const fs::path state = dir / "state";
  CoordinatorProcess c;
  // A fault while the store opens ends the start with one line and exit
  // status 75 (EX_TEMPFAIL: it may pass); a supervisor starts it again (the
  // systemd unit does), here with the next fault one stride on (the shim
  // counts from the new start).
  for (std::int64_t at = first; c.port == 0 && at < first + 5 * stride; at += stride) {
    const std::size_t log_size = ReadText(state / "coordinator.log").size();
    c = StartCoordinator(state, 0, kFastLeases,
                         ShimEnv(state, {"FABATLAS_FAULT_MATCH=" + match, "FABATLAS_FAULT_ERRNO=" + error,
                                         "FABATLAS_FAULT_AT=" + std::to_string(at),
                                         "FABATLAS_FAULT_EVERY=" + std::to_string(stride), "FABATLAS_FAULT_MS=300"}));
    if (c.port > 0) break;
    EXPECT_EQ(c.exit_status, coordinator::kExitStateUnavailable) << what << ": a start that met an I/O error";
    const std::string said = ReadText(state / "coordinator.log").substr(log_size);
    const std::string last = said.substr(said.rfind('\n', said.size() - 2) + 1);
    EXPECT_EQ(last.rfind("fabatlas-coordinator: " + (state / "state.db").string() + ": ", 0), 0u) << what << said;
  }
  ASSERT_GT(c.port, 0) << what << ReadText(state / "coordinator.log");
  pid_t worker = StartWorker(c.port, dir / "w", WorkerArgs());
  std::string id;
  // A fault during Submit is answered with the error: the client tries again.
  for (int i = 0; i < 50 && id.empty(); ++i) {
    try {
      id = Client(c.port).Submit(JobPath());
    } catch (const InputError&) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
  ASSERT_FALSE(id.empty()) << what;
  const v1::JobStatus s = WaitForJob([&] { return c.port; }, id, std::chrono::seconds(240));
  EXPECT_EQ(s.state(), v1::JOB_STATE_SUCCEEDED) << what << " " << s.error();
  EXPECT_TRUE(Client(c.port).Fetch(id)[kArtifactName] == ReferenceArtifact()) << what << ": the artifact differs";
  ::kill(worker, SIGTERM);
  WaitExit(worker, std::chrono::seconds(30));
  const std::string log = ReadText(state / "coordinator.log");
  const std::int64_t faults = [&] {
    std::int64_t n = 0;
    for (auto at = log.find("power_loss_shim: " + error); at != std::string::npos;
         at = log.find("power_loss_shim: " + error, at + 1))
      ++n;
    return n;
  }();
  EXPECT_GT(faults, 0) << what << ": no fault was injected";
  EXPECT_NE(log.find("state_write_failed"), std::string::npos) << what << ": no state_write_failed line\n" << log;
  StopAndCheck(c, state, id, what);
  const bool failed = FailuresSoFar() > failures_before;
  std::cerr << "fault loop " << what << ": " << faults << " faults, "
            << (s.state() == v1::JOB_STATE_SUCCEEDED ? "job succeeded" : "job did not succeed") << ", "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count() << " s"
            << (failed ? "  FAILED" : "") << "\n";
  if (!failed) fs::remove_all(dir);
}

// A fault every `stride` writes: more than the writes of the largest commit
// (a sampling round's tasks: about 60 WAL frames here), else no transaction
// could commit between two faults and the job would wait for ever, as on a
// disk that never recovers. The job store takes about 1,070 writes on this
// job, the blob store 33. CI runs one loop per error; FABATLAS_FAULT_STRIDE=s
// runs every offset 1..s, so every write k of the job meets a fault.
void RunFaultLoops(const std::string& match, std::int64_t stride) {
  ASSERT_TRUE(fs::exists(ShimPath())) << ShimPath();
  ASSERT_FALSE(ReferenceArtifact().empty());
  const std::int64_t all = EnvInt(match == "state.db" ? "FABATLAS_FAULT_STRIDE" : "FABATLAS_BLOB_FAULT_STRIDE", 0);
  // FABATLAS_FAULT_FROM / _TO: only the offsets from..to (a long run split
  // over processes); FABATLAS_FAULT_ERROR: only EIO or only ENOSPC.
  const std::int64_t from = EnvInt("FABATLAS_FAULT_FROM", 1), to = EnvInt("FABATLAS_FAULT_TO", all);
  const char* only = std::getenv("FABATLAS_FAULT_ERROR");
  for (const std::string error : {"EIO", "ENOSPC"}) {
    if (only && *only && error != only) continue;
    if (all > 0) {
      for (std::int64_t first = from; first <= std::min(all, to); ++first) RunFaultLoop(match, error, first, all);
    } else {
      RunFaultLoop(match, error, error == "EIO" ? 3 : stride / 2, stride);
    }
  }
}

TEST(IoFaults, EioAndEnospcOnJobStoreWritesStallThenRecoverWithNothingLost) { RunFaultLoops("state.db", 100); }

TEST(IoFaults, EioAndEnospcOnBlobStoreWritesStallThenRecoverWithNothingLost) { RunFaultLoops("/blobs/", 8); }

}  // namespace
