// The durable job store and the blob store: leases, fencing, quarantine,
// durability across reopen, content addresses and resumable uploads.
#include <gtest/gtest.h>
#include <fcntl.h>
#include <sqlite3.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "fabatlas/error.h"
#include "fabatlas/sha256.h"
#include "fabatlas/storage/blob_store.h"
#include "fabatlas/storage/job_store.h"
#include "fabatlas/testing/small_filesystem.h"

namespace fs = std::filesystem;
using namespace fabatlas::storage;

namespace {

fs::path FreshDir(const std::string& name) {
  fs::path dir = fs::temp_directory_path() / ("fabatlas_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

std::string Key(int i) { return fabatlas::Sha256Hex("task" + std::to_string(i)); }

void AddRunningJob(JobStore& store, int tasks) {
  ASSERT_TRUE(store.CreateJob({"job1", std::string(64, 'a'), "d", JobState::kRunning, "", 1, 0}));
  std::vector<NewTask> batch;
  for (int i = 0; i < tasks; ++i) batch.push_back({Key(i), "job1", 1, "payload" + std::to_string(i)});
  EXPECT_TRUE(store.AddTasks(batch).empty());
}

}  // namespace

TEST(ClusterStorage, SHA256OfKnownVector) {
  // FIPS 180-2 test vector "abc".
  fs::path dir = FreshDir("sha");
  std::ofstream(dir / "abc") << "abc";
  EXPECT_EQ(Sha256OfFile(dir / "abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(ClusterStorage, LeaseCompleteDuplicateAndDurability) {
  fs::path dir = FreshDir("store1");
  {
    JobStore store(dir / "state.db");
    AddRunningJob(store, 5);
    // Adding the same tasks again inserts nothing.
    store.AddTasks({{Key(0), "job1", 1, "other"}});
    EXPECT_EQ(store.CountTasks("job1").total, 5);
    auto grants = store.GrantLeases("w1", 3, 1000, 500);
    ASSERT_EQ(grants.size(), 3u);
    EXPECT_EQ(grants[0].task_key, Key(0));  // oldest first
    EXPECT_EQ(grants[0].attempt, 1);
    EXPECT_EQ(grants[0].payload, "payload0");
    EXPECT_EQ(grants[0].deadline_ms, 1500);
    auto outcomes = store.Complete({{grants[0].lease_id, grants[0].task_key, 1, "r0", false, 1},
                                    {grants[0].lease_id, grants[0].task_key, 1, "r0b", false, 1}},
                                   1100, 100);
    EXPECT_EQ(outcomes[0], CompletionOutcome::kAccepted);
    EXPECT_EQ(outcomes[1], CompletionOutcome::kDuplicate);
    EXPECT_EQ(store.FindTask(Key(0))->result, "r0");  // first completion wins
    EXPECT_EQ(store.CountTasks("job1").leased, 2);
    EXPECT_TRUE(store.CheckConsistency().empty());
  }
  // Reopen: everything is still there, including the two active leases.
  JobStore store(dir / "state.db");
  TaskCounts c = store.CountTasks("job1");
  EXPECT_EQ(c.done, 1);
  EXPECT_EQ(c.leased, 2);
  EXPECT_EQ(c.queued, 2);
  EXPECT_EQ(c.samples_valid, 1);
  EXPECT_EQ(store.ActiveLeases(), 2);
  auto finished = store.AddTasks({{Key(0), "job1", 1, "payload0"}, {Key(1), "job1", 1, "payload1"}});
  ASSERT_EQ(finished.size(), 1u);
  EXPECT_EQ(finished[Key(0)], "r0");
}

TEST(ClusterStorage, ExpiryFencesLateResultsAndQuarantinesAfterThree) {
  fs::path dir = FreshDir("store2");
  JobStore store(dir / "state.db");
  AddRunningJob(store, 1);
  auto quarantine_result = [](int kind) { return "quarantined kind " + std::to_string(kind); };
  std::int64_t now = 0;
  std::vector<LeaseGrant> history;
  for (int attempt = 1; attempt <= 3; ++attempt) {
    auto g = store.GrantLeases("w" + std::to_string(attempt), 1, now, 100);
    ASSERT_EQ(g.size(), 1u) << "attempt " << attempt;
    EXPECT_EQ(g[0].attempt, attempt);
    history.push_back(g[0]);
    now += 101;  // past the deadline
    auto expired = store.ExpireLeases(now, 10, 3, quarantine_result);
    ASSERT_EQ(expired.size(), 1u);
    EXPECT_EQ(expired[0].quarantined, attempt == 3);
    // The backoff keeps the task back: 10 ms, then 20 ms.
    if (attempt < 3) {
      EXPECT_TRUE(store.GrantLeases("x", 1, now, 100).empty());
      now += 10 << (attempt - 1);
    }
  }
  // The first holder comes back late: fenced.
  auto late = store.Complete({{history[0].lease_id, history[0].task_key, 1, "late", false, 1}}, now, 0);
  EXPECT_EQ(late[0], CompletionOutcome::kDuplicate);  // already quarantined
  auto task = store.FindTask(Key(0));
  EXPECT_EQ(task->state, TaskState::kQuarantined);
  EXPECT_EQ(task->result, "quarantined kind 1");
  EXPECT_EQ(task->completions, 1);
  EXPECT_EQ(store.ActiveLeases(), 0);
  EXPECT_TRUE(store.CheckConsistency().empty());
  EXPECT_EQ(store.Events("job1").size(), 3u);
}

TEST(ClusterStorage, LateResultOfAnExpiredAttemptIsFenced) {
  fs::path dir = FreshDir("store3");
  JobStore store(dir / "state.db");
  AddRunningJob(store, 1);
  auto first = store.GrantLeases("w1", 1, 0, 100);
  store.ExpireLeases(200, 0, 3, [](int) { return std::string(); });
  auto second = store.GrantLeases("w2", 1, 200, 100);
  ASSERT_EQ(second[0].attempt, 2);
  auto out = store.Complete({{first[0].lease_id, first[0].task_key, 1, "old", false, 1},
                             {second[0].lease_id, second[0].task_key, 2, "new", false, 0}},
                            250, 0);
  EXPECT_EQ(out[0], CompletionOutcome::kFenced);
  EXPECT_EQ(out[1], CompletionOutcome::kAccepted);
  EXPECT_EQ(store.FindTask(Key(0))->result, "new");
  EXPECT_EQ(store.CountTasks("job1").fenced_results, 1);
  EXPECT_TRUE(store.CheckConsistency().empty());
}

TEST(ClusterStorage, LeasesUnknownToTheWorkerAreReturned) {
  fs::path dir = FreshDir("store4");
  JobStore store(dir / "state.db");
  AddRunningJob(store, 3);
  auto g = store.GrantLeases("w1", 3, 0, 1000);
  EXPECT_EQ(store.ReturnUnknownLeases("w1", {g[1].lease_id}), 2);
  EXPECT_EQ(store.CountTasks("job1").queued, 2);
  EXPECT_EQ(store.CountTasks("job1").lease_expiries, 0);
  auto revoked = store.ExtendLeases("w1", {g[0].lease_id, g[1].lease_id}, 5000);
  ASSERT_EQ(revoked.size(), 1u);
  EXPECT_EQ(revoked[0], g[0].lease_id);
  EXPECT_TRUE(store.CheckConsistency().empty());
}

// SyncWorker is Complete, ReturnUnknownLeases, ExtendLeases and GrantLeases
// in that order, in one transaction: the same outcome as the four calls on
// a twin store, and when one completion cannot be stored (here its
// quarantine result throws) nothing of the Sync is (no result, no returned
// lease, no grant).
TEST(ClusterStorage, SyncWorkerIsTheFourCallsInOneTransaction) {
  fs::path dir = FreshDir("store_sync");
  JobStore calls(dir / "calls.db"), sync(dir / "sync.db");
  WorkerSync in;
  in.worker_id = "w1";
  in.lease_ms = 1000;
  in.want = 2;
  in.retry_backoff_ms = 10;
  for (JobStore* store : {&calls, &sync}) {
    AddRunningJob(*store, 6);
    auto g = store->GrantLeases("w1", 3, 0, 1000);  // deadlines 1000
    ASSERT_EQ(g.size(), 3u);
    in.completions = {{g[0].lease_id, g[0].task_key, 1, "r0", false, 1}};
    in.in_flight = {g[1].lease_id, "gone.1"};  // g[2] unknown to the worker: returned
  }
  in.now_ms = 700;  // g[1] has 300 ms left, under half a lease: topped up to 1700
  auto outcomes = calls.Complete(in.completions, in.now_ms, in.retry_backoff_ms);
  const int returned = calls.ReturnUnknownLeases("w1", {in.in_flight[0], in.in_flight[1], in.completions[0].lease_id});
  auto revoked = calls.ExtendLeases("w1", in.in_flight, in.now_ms + in.lease_ms, in.lease_ms / 2);
  auto grants = calls.GrantLeases("w1", in.want, in.now_ms, in.lease_ms);

  // A completion whose storing throws rolls the whole Sync back.
  WorkerSync failing = in;
  failing.completions.push_back({in.in_flight[0], Key(1), 1, "", true, -1});
  failing.quarantine_after = 1;
  failing.quarantine_result = [](int) -> std::string { throw fabatlas::ResourceError("disk full"); };
  EXPECT_THROW(sync.SyncWorker(failing), fabatlas::ResourceError);
  EXPECT_EQ(sync.CountTasks("job1").done, 0);
  EXPECT_EQ(sync.CountTasks("job1").leased, 3);
  EXPECT_EQ(sync.ActiveLeases(), 3);
  EXPECT_TRUE(sync.CheckConsistency().empty());

  WorkerSyncOutcome out = sync.SyncWorker(in);
  EXPECT_EQ(out.outcomes, outcomes);
  EXPECT_EQ(out.outcomes, std::vector<CompletionOutcome>{CompletionOutcome::kAccepted});
  EXPECT_EQ(out.returned, returned);
  EXPECT_EQ(out.returned, 1);
  EXPECT_EQ(out.revoked, revoked);
  EXPECT_EQ(out.revoked, std::vector<std::string>{"gone.1"});
  ASSERT_EQ(out.grants.size(), grants.size());
  ASSERT_EQ(out.grants.size(), 2u);
  for (std::size_t i = 0; i < grants.size(); ++i) {
    EXPECT_EQ(out.grants[i].lease_id, grants[i].lease_id);
    EXPECT_EQ(out.grants[i].deadline_ms, 1700);
  }
  for (JobStore* store : {&calls, &sync}) {
    EXPECT_TRUE(store->CheckConsistency().empty());
    const TaskCounts c = store->CountTasks("job1");
    EXPECT_EQ(c.done, 1);
    EXPECT_EQ(c.leased, 3);  // g[1] and the two new grants
    EXPECT_EQ(c.queued, 2);
    EXPECT_EQ(store->ExtendLeases("w1", {in.in_flight[0]}, 1700).size(), 0u);  // g[1] still active
  }
  EXPECT_EQ(calls.Tasks("job1")[1].attempt, sync.Tasks("job1")[1].attempt);
}

TEST(ClusterStorage, CancelledJobsAreNotLeased) {
  fs::path dir = FreshDir("store5");
  JobStore store(dir / "state.db");
  AddRunningJob(store, 2);
  store.SetJobState("job1", JobState::kCancelled, "", 5);
  EXPECT_TRUE(store.GrantLeases("w1", 2, 0, 1000).empty());
}

TEST(ClusterStorage, UnwritableDatabaseIsAOneLineResourceError) {
  try {
    JobStore store("/proc/fabatlas/state.db");
    FAIL() << "expected ResourceError";
  } catch (const fabatlas::ResourceError& e) {
    std::string what = e.what();
    EXPECT_NE(what.find("/proc/fabatlas/state.db"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
}

TEST(ClusterStorage, BlobsAreContentAddressedAndResumable) {
  fs::path dir = FreshDir("blobs");
  BlobStore blobs(dir);
  std::string data(3 * 1000 + 7, 'x');
  for (std::size_t i = 0; i < data.size(); ++i) data[i] = static_cast<char>(i * 31 + 7);
  std::string digest = fabatlas::Sha256Hex(data);
  EXPECT_EQ(blobs.Append(digest, 0, data.substr(0, 1000)), 1000);
  // Interrupted upload: the store reports where to resume.
  BlobStore reopened(dir);
  EXPECT_EQ(reopened.CommittedSize(digest), 1000);
  EXPECT_FALSE(reopened.Contains(digest));
  EXPECT_THROW(reopened.Append(digest, 2000, data.substr(2000)), fabatlas::InputError);
  EXPECT_EQ(reopened.Append(digest, 0, data.substr(0, 1000)), 1000);  // repeated chunk ignored
  EXPECT_EQ(reopened.Append(digest, 1000, data.substr(1000)), static_cast<std::int64_t>(data.size()));
  reopened.Finish(digest);
  EXPECT_TRUE(reopened.Contains(digest));
  EXPECT_TRUE(reopened.Verify(digest));
  EXPECT_EQ(reopened.Read(digest), data);
  EXPECT_EQ(reopened.Read(digest, 3000, 5), data.substr(3000, 5));
  EXPECT_EQ(reopened.List(), std::vector<std::string>{digest});
  EXPECT_EQ(reopened.Put(data), digest);
}

TEST(ClusterStorage, CorruptUploadIsRejectedAndCorruptBlobFailsVerify) {
  fs::path dir = FreshDir("blobs2");
  BlobStore blobs(dir);
  std::string digest = fabatlas::Sha256Hex("hello");
  blobs.Append(digest, 0, "jello");
  EXPECT_THROW(blobs.Finish(digest), fabatlas::InputError);
  EXPECT_FALSE(blobs.Contains(digest));
  EXPECT_EQ(blobs.CommittedSize(digest), 0);  // partial discarded
  EXPECT_EQ(blobs.Put("hello"), digest);
  std::ofstream(blobs.PathOf(digest), std::ios::trunc) << "hellO";
  EXPECT_FALSE(blobs.Verify(digest));
  EXPECT_THROW(blobs.Append("not-a-digest", 0, "x"), fabatlas::InputError);
}

TEST(ClusterStorage, SubtreeRecordsOfAcceptedSamplesOnly) {
  fs::path dir = FreshDir("subtrees");
  auto use = [](const std::string& key, double seconds, bool measured, std::vector<std::string> children,
                const std::string& digest) {
    SubtreeUse u;
    u.key = key;
    u.topology = "t" + key;
    u.op = children.empty() ? "sphere" : "union";
    u.seconds = seconds;
    u.measured = measured;
    u.bytes = 1000;
    u.children = std::move(children);
    u.blob_digest = digest;
    return u;
  };
  {
    JobStore store(dir / "state.db");
    AddRunningJob(store, 3);
    auto grants = store.GrantLeases("w1", 3, 1000, 500);
    ASSERT_EQ(grants.size(), 3u);
    // Sample 0 computes leaf "a" (0.5 s, uploaded) and root "r0" over it.
    Completion c0{grants[0].lease_id, grants[0].task_key, 1, "r0", false, 1};
    c0.point_key = "0,0";
    c0.subtrees = {use("a", 0.5, true, {}, "dA"), use("r0", 0.25, true, {"a"}, "")};
    // Sample 1 finds "a" in its cache (carried 0.5 s, not a measurement).
    Completion c1{grants[1].lease_id, grants[1].task_key, 1, "r1", false, 1};
    c1.point_key = "0,1";
    c1.subtrees = {use("a", 0.5, false, {}, "dA"), use("r1", 0.125, true, {"a"}, "dR1")};
    // A duplicate of sample 0 and a fenced result of sample 2 add nothing.
    Completion dup = c0;
    dup.subtrees = {use("a", 9.0, true, {}, "other"), use("x", 1.0, true, {}, "")};
    Completion fenced{grants[2].lease_id, grants[2].task_key, 7, "r2", false, 1};
    fenced.point_key = "1,1";
    fenced.subtrees = {use("y", 1.0, true, {}, "")};
    auto outcomes = store.Complete({c0, c1, dup, fenced}, 1100, 100);
    EXPECT_EQ(outcomes[0], CompletionOutcome::kAccepted);
    EXPECT_EQ(outcomes[1], CompletionOutcome::kAccepted);
    EXPECT_EQ(outcomes[2], CompletionOutcome::kDuplicate);
    EXPECT_EQ(outcomes[3], CompletionOutcome::kFenced);
  }
  JobStore store(dir / "state.db");  // durable across reopen
  auto rows = store.Subtrees("job1");
  ASSERT_EQ(rows.size(), 3u);  // a, r0, r1 (ordered by key)
  EXPECT_EQ(rows[0].key, "a");
  EXPECT_EQ(rows[0].uses, 2);
  EXPECT_EQ(rows[0].seconds_count, 1);  // the cache hit is no measurement
  EXPECT_DOUBLE_EQ(rows[0].seconds_sum, 0.5);
  EXPECT_DOUBLE_EQ(rows[0].seconds(), 0.5);
  EXPECT_EQ(rows[0].blob_digest, "dA");
  EXPECT_TRUE(rows[0].children.empty());
  EXPECT_EQ(rows[1].key, "r0");
  EXPECT_EQ(rows[1].children, std::vector<std::string>{"a"});
  EXPECT_EQ(rows[1].blob_digest, "");
  EXPECT_EQ(rows[2].blob_digest, "dR1");
  EXPECT_DOUBLE_EQ(rows[2].seconds(), 0.125);
  auto samples = store.SampleSubtreeKeys("job1");
  ASSERT_EQ(samples.size(), 2u);
  EXPECT_EQ(samples[0].point_key, "0,0");
  EXPECT_EQ(samples[0].subtree_keys, (std::vector<std::string>{"a", "r0"}));
  EXPECT_EQ(samples[1].point_key, "0,1");
  EXPECT_EQ(samples[1].subtree_keys, (std::vector<std::string>{"a", "r1"}));
  EXPECT_TRUE(store.Subtrees("other-job").empty());
}

// Lease affinity (worker.proto): a worker gets the tasks preferring it alone,
// then those it shares, then tasks preferring nobody (oldest first), then
// other workers' tasks from the newest; a granted task loses its preference,
// and forgetting a worker makes its tasks nobody's.
TEST(ClusterStorage, LeaseAffinityOrderAndForgetting) {
  fs::path dir = FreshDir("affinity");
  JobStore store(dir / "state.db");
  ASSERT_TRUE(store.CreateJob({"job1", std::string(64, 'a'), "d", JobState::kRunning, "", 1, 0}));
  std::vector<NewTask> batch;
  auto add = [&](int i, std::vector<std::string> preferred) {
    batch.push_back({Key(i), "job1", 2, "p" + std::to_string(i), std::move(preferred)});
  };
  add(0, {});            // nobody's
  add(1, {"w2"});        // w2's alone
  add(2, {"w1", "w2"});  // shared
  add(3, {"w1"});        // w1's alone
  add(4, {});            // nobody's
  add(5, {"w2"});        // w2's alone
  add(6, {"gone"});      // a worker that will leave
  store.AddTasks(batch);
  // w1: its own task, the shared one, then the nobody's in order, then the
  // newest task of another worker.
  auto grants = store.GrantLeases("w1", 5, 1000, 500);
  std::vector<std::string> got;
  for (const auto& g : grants) got.push_back(g.task_key);
  EXPECT_EQ(got, (std::vector<std::string>{Key(3), Key(2), Key(0), Key(4), Key(6)}));
  // w2 gets its own two, oldest first.
  grants = store.GrantLeases("w2", 5, 1000, 500);
  got.clear();
  for (const auto& g : grants) got.push_back(g.task_key);
  EXPECT_EQ(got, (std::vector<std::string>{Key(1), Key(5)}));
  EXPECT_TRUE(store.CheckConsistency().empty());

  // A requeued task prefers nobody; forgetting a worker frees its tasks.
  store.AddTasks({{Key(7), "job1", 2, "p7", {"w3"}}, {Key(8), "job1", 2, "p8", {"w3", "w4"}}});
  EXPECT_EQ(store.ForgetAffinity("w3"), 1);  // task 8 still prefers w4
  grants = store.GrantLeases("w5", 1, 1000, 500);
  ASSERT_EQ(grants.size(), 1u);
  EXPECT_EQ(grants[0].task_key, Key(7));  // nobody's now, before w4's task 8
  store.ClearAffinity();
  grants = store.GrantLeases("w5", 1, 1000, 500);
  ASSERT_EQ(grants.size(), 1u);
  EXPECT_EQ(grants[0].task_key, Key(8));
}

// Leases taken in advance are never stolen (worker.proto, idle_slots): a
// worker asking for eight with one idle slot gets the unclaimed task and at
// most one of another worker's, the newest; with no idle slot, none of
// them; a Sync caps its grants the same way.
TEST(ClusterStorage, StealingIsCappedAtTheIdleSlots) {
  fs::path dir = FreshDir("steal");
  JobStore store(dir / "state.db");
  ASSERT_TRUE(store.CreateJob({"job1", std::string(64, 'a'), "d", JobState::kRunning, "", 1, 0}));
  std::vector<NewTask> batch;
  for (int i = 0; i < 6; ++i)
    batch.push_back({Key(i), "job1", 2, "p" + std::to_string(i),
                     i == 0 ? std::vector<std::string>{} : std::vector<std::string>{"w2"}});
  store.AddTasks(batch);
  auto keys = [](const std::vector<LeaseGrant>& grants) {
    std::vector<std::string> got;
    for (const auto& g : grants) got.push_back(g.task_key);
    return got;
  };
  EXPECT_EQ(keys(store.GrantLeases("w1", 8, 1000, 500, 1)), (std::vector<std::string>{Key(0), Key(5)}));
  EXPECT_TRUE(store.GrantLeases("w1", 8, 1000, 500, 0).empty());
  WorkerSync sync;
  sync.worker_id = "w3";
  sync.now_ms = 1000;
  sync.lease_ms = 500;
  sync.want = 8;
  sync.steal = 2;
  EXPECT_EQ(keys(store.SyncWorker(sync).grants), (std::vector<std::string>{Key(4), Key(3)}));
  // Uncapped (a worker that does not say): all that are left, newest first.
  EXPECT_EQ(keys(store.GrantLeases("w1", 8, 1000, 500)), (std::vector<std::string>{Key(2), Key(1)}));
  EXPECT_TRUE(store.CheckConsistency().empty());
}

// A store written before lease affinity (no tasks.affine column) opens and
// schedules.
TEST(ClusterStorage, StoreWithoutAffinityColumnIsMigrated) {
  fs::path dir = FreshDir("migrate");
  {
    JobStore store(dir / "state.db");
    AddRunningJob(store, 2);
  }
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "state.db").string().c_str(), &db), SQLITE_OK);
    EXPECT_EQ(
        sqlite3_exec(db, "DROP INDEX tasks_queued; ALTER TABLE tasks DROP COLUMN affine;", nullptr, nullptr, nullptr),
        SQLITE_OK);
    sqlite3_close(db);
  }
  JobStore store(dir / "state.db");
  auto grants = store.GrantLeases("w1", 5, 1000, 500);
  EXPECT_EQ(grants.size(), 2u);
}

// A store written before the partial indexes and the ordered lease ids
// (tasks_job, tasks_neutral, leases_active, leases_worker; lease ids from
// the task key) opens with the new indexes only, and its active leases,
// ids of the old form included, complete, expire and are found as before.
TEST(ClusterStorage, StoreWithTheEarlierIndexesAndLeaseIdsIsMigrated) {
  fs::path dir = FreshDir("migrate_indexes");
  std::vector<LeaseGrant> grants;
  {
    JobStore store(dir / "state.db");
    AddRunningJob(store, 4);
    grants = store.GrantLeases("w1", 2, 1000, 500);
    ASSERT_EQ(grants.size(), 2u);
  }
  auto exec = [&](const std::string& sql) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "state.db").string().c_str(), &db), SQLITE_OK);
    EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
    sqlite3_close(db);
  };
  auto indexes = [&] {
    std::vector<std::string> names;
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open((dir / "state.db").string().c_str(), &db), SQLITE_OK);
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db,
                       "SELECT name FROM sqlite_schema WHERE type = 'index' AND name NOT LIKE 'sqlite_%' "
                       "AND (tbl_name = 'tasks' OR tbl_name = 'leases') ORDER BY name",
                       -1, &s, nullptr);
    while (sqlite3_step(s) == SQLITE_ROW) names.push_back(reinterpret_cast<const char*>(sqlite3_column_text(s, 0)));
    sqlite3_finalize(s);
    sqlite3_close(db);
    return names;
  };
  EXPECT_EQ(indexes(), (std::vector<std::string>{"leases_due", "leases_of_worker", "tasks_of_job", "tasks_queued"}));
  // As the previous version wrote it: its indexes, and the first lease's id
  // from its task key.
  const std::string old_id = grants[0].task_key.substr(0, 16) + ".1";
  exec(
      "DROP INDEX tasks_of_job; DROP INDEX tasks_queued; DROP INDEX leases_due; DROP INDEX leases_of_worker; "
      "CREATE INDEX tasks_job ON tasks (job_id, state); CREATE INDEX tasks_neutral ON tasks (state, affine, seq); "
      "CREATE INDEX leases_active ON leases (state, deadline_ms); "
      "CREATE INDEX leases_worker ON leases (worker_id, state); "
      "UPDATE leases SET lease_id = '" +
      old_id + "' WHERE lease_id = '" + grants[0].lease_id + "'");
  JobStore store(dir / "state.db");
  EXPECT_EQ(indexes(), (std::vector<std::string>{"leases_due", "leases_of_worker", "tasks_of_job", "tasks_queued"}));
  EXPECT_EQ(store.ActiveLeases(), 2);
  EXPECT_TRUE(store.ExtendLeases("w1", {old_id, grants[1].lease_id}, 1400).empty());
  auto outcomes = store.Complete({{old_id, grants[0].task_key, 1, "r0", false, 1}}, 1100, 0);
  EXPECT_EQ(outcomes, (std::vector<CompletionOutcome>{CompletionOutcome::kAccepted}));
  auto expired = store.ExpireLeases(2000, 10, 3, [](int) { return std::string(); });
  ASSERT_EQ(expired.size(), 1u);
  EXPECT_EQ(expired[0].lease_id, grants[1].lease_id);
  auto more = store.GrantLeases("w2", 5, 1000000, 500);
  EXPECT_EQ(more.size(), 3u);  // the expired one again and the two never leased
  EXPECT_TRUE(store.CheckConsistency().empty());
  const TaskCounts c = store.CountTasks("job1");
  EXPECT_EQ(c.done, 1);
  EXPECT_EQ(c.leased, 3);
}

// The schema version: an unversioned store (user_version 0) is stamped with
// the current version on open; a store of a newer version is refused with
// one line naming the file, and is left as it was.
TEST(ClusterStorage, SchemaVersionIsStampedAndANewerStoreIsRefused) {
  fs::path dir = FreshDir("version");
  auto user_version = [&] {
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open((dir / "state.db").string().c_str(), &db), SQLITE_OK);
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db, "PRAGMA user_version", -1, &s, nullptr);
    int v = sqlite3_step(s) == SQLITE_ROW ? sqlite3_column_int(s, 0) : -1;
    sqlite3_finalize(s);
    sqlite3_close(db);
    return v;
  };
  auto set_user_version = [&](int v) {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open((dir / "state.db").string().c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db, ("PRAGMA user_version = " + std::to_string(v)).c_str(), nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_close(db);
  };
  {
    JobStore store(dir / "state.db");
    AddRunningJob(store, 2);
  }
  EXPECT_EQ(user_version(), kJobStoreSchemaVersion);
  set_user_version(0);  // as written before versions existed
  { JobStore store(dir / "state.db"); }
  EXPECT_EQ(user_version(), kJobStoreSchemaVersion);

  set_user_version(kJobStoreSchemaVersion + 1);
  try {
    JobStore store(dir / "state.db");
    FAIL() << "a newer store opened";
  } catch (const fabatlas::InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what, (dir / "state.db").string() + ": job store written by a newer fabatlas (schema version " +
                        std::to_string(kJobStoreSchemaVersion + 1) + "; this coordinator knows versions up to " +
                        std::to_string(kJobStoreSchemaVersion) + ")");
  }
  EXPECT_EQ(user_version(), kJobStoreSchemaVersion + 1);
  set_user_version(kJobStoreSchemaVersion);
  JobStore store(dir / "state.db");
  EXPECT_EQ(store.GrantLeases("w1", 5, 1000, 500).size(), 2u);
}

// A task that fails (the worker reports an error instead of a result) is
// retried with a growing backoff while one worker fails it again and again,
// and quarantined once quarantine_after different workers have failed it.
TEST(ClusterStorage, FailuresBackOffAndQuarantineAfterThreeWorkers) {
  fs::path dir = FreshDir("failures");
  JobStore store(dir / "state.db");
  AddRunningJob(store, 1);
  auto quarantine = [](int kind) { return "quarantined kind " + std::to_string(kind); };
  std::int64_t now = 1000;
  auto fail_once = [&](const std::string& worker) {
    auto grants = store.GrantLeases(worker, 1, now, 500);
    EXPECT_EQ(grants.size(), 1u);
    if (grants.empty()) return CompletionOutcome::kUnknown;
    Completion c{grants[0].lease_id, grants[0].task_key, grants[0].attempt, "", true, -1};
    c.error = "cannot load the design";
    return store.Complete({c}, now, 100, 3, quarantine)[0];
  };
  // One worker failing four times: requeued each time, backoff 100, 200, 400, 800 ms.
  for (std::int64_t backoff : {100, 200, 400, 800}) {
    EXPECT_EQ(fail_once("w1"), CompletionOutcome::kRequeued);
    EXPECT_TRUE(store.GrantLeases("w1", 1, now + backoff - 1, 500).empty()) << backoff;
    now += backoff;
  }
  EXPECT_EQ(store.CountTasks("job1").queued, 1);
  EXPECT_EQ(fail_once("w2"), CompletionOutcome::kRequeued);
  now += 30000;
  EXPECT_EQ(fail_once("w3"), CompletionOutcome::kQuarantined);  // the third different worker
  EXPECT_EQ(store.CountTasks("job1").quarantined, 1);
  EXPECT_EQ(store.FindTask(Key(0))->result, "quarantined kind 1");
  EXPECT_TRUE(store.CheckConsistency().empty());
}

// A job's task counts are kept in memory once asked for (CountTasks) and
// moved by every change: after each kind of change they equal a scan of the
// tasks (CheckConsistency compares them) and, at the end, a store opened
// afresh on the same file, which scans.
TEST(ClusterStorage, TaskCountsKeptInMemoryEqualAScan) {
  fs::path dir = FreshDir("counts");
  JobStore store(dir / "state.db");
  auto quarantine = [](int kind) { return "quarantined kind " + std::to_string(kind); };
  auto consistent = [&](const std::string& step) {
    std::vector<std::string> problems = store.CheckConsistency();
    EXPECT_TRUE(problems.empty()) << step << ": " << (problems.empty() ? "" : problems[0]);
  };
  EXPECT_EQ(store.CountTasks("job1").total, 0);  // kept from before the job exists
  AddRunningJob(store, 8);
  store.AddTasks({{Key(0), "job1", 1, "again"}, {Key(8), "job1", 2, "geometry change"}});  // one new
  consistent("added");
  auto g = store.GrantLeases("w1", 7, 1000, 500);
  ASSERT_EQ(g.size(), 7u);
  consistent("granted");
  Completion failed{g[4].lease_id, g[4].task_key, g[4].attempt, "", true, -1};
  failed.error = "cannot load";
  Completion failed_twice{g[5].lease_id, g[5].task_key, g[5].attempt, "", true, -1};
  failed_twice.error = "cannot load";
  auto outcomes = store.Complete({{g[0].lease_id, g[0].task_key, 1, "valid", false, 1},
                                  {g[1].lease_id, g[1].task_key, 1, "invalid", false, 0},
                                  {g[1].lease_id, g[1].task_key, 1, "again", false, 0},
                                  failed},
                                 1100, 10, 1, quarantine);
  EXPECT_EQ(outcomes, (std::vector<CompletionOutcome>{CompletionOutcome::kAccepted, CompletionOutcome::kAccepted,
                                                      CompletionOutcome::kDuplicate, CompletionOutcome::kQuarantined}));
  consistent("completed");
  EXPECT_EQ(store.Complete({failed_twice}, 1100, 10)[0], CompletionOutcome::kRequeued);
  consistent("requeued");
  EXPECT_EQ(store.ReturnUnknownLeases("w1", {g[2].lease_id, g[3].lease_id}), 1);  // g[6] returned
  consistent("returned");
  EXPECT_EQ(store.ExpireLeases(1600, 0, 2, quarantine).size(), 2u);  // g[2], g[3]: requeued
  consistent("expired");
  EXPECT_EQ(store.Complete({{g[2].lease_id, g[2].task_key, 1, "late", false, 1}}, 1600, 10)[0],
            CompletionOutcome::kFenced);
  consistent("fenced");
  auto again = store.GrantLeases("w2", 1, 1600, 100);
  ASSERT_EQ(again.size(), 1u);
  EXPECT_EQ(store.ExpireLeases(1800, 0, 1, quarantine).size(), 1u);  // quarantined
  consistent("quarantined on expiry");
  const TaskCounts c = store.CountTasks("job1");
  // 9 tasks: 2 done (g0 valid, g1 invalid), 2 quarantined (g4 on failure,
  // the expired regrant), 5 queued (2 never leased, g5 requeued, g6
  // returned, one of g2/g3 back after its expiry).
  EXPECT_EQ(c.total, 9);
  EXPECT_EQ(c.done, 2);
  EXPECT_EQ(c.quarantined, 2);
  EXPECT_EQ(c.queued, 5);
  EXPECT_EQ(c.leased, 0);
  EXPECT_EQ(c.samples_done, 4);
  EXPECT_EQ(c.samples_valid, 1);
  EXPECT_EQ(c.lease_expiries, 3);
  EXPECT_EQ(c.fenced_results, 1);
  JobStore scanned(dir / "state.db");
  const TaskCounts s = scanned.CountTasks("job1");
  EXPECT_EQ(std::make_tuple(s.total, s.queued, s.leased, s.done, s.quarantined, s.samples_done, s.samples_valid,
                            s.lease_expiries, s.fenced_results),
            std::make_tuple(c.total, c.queued, c.leased, c.done, c.quarantined, c.samples_done, c.samples_valid,
                            c.lease_expiries, c.fenced_results));
}

// Blob lifecycle (docs/protocol.md "Blob lifecycle"): the store references a
// job's bundle and outputs always, its subtree geometry and job blobs only
// until the job ends; Collect removes what nothing references once it is
// older than the cutoff, and keeps newer blobs (an upload whose result is
// not reported yet).
TEST(ClusterStorage, ReferencedBlobsAndCollection) {
  fs::path dir = FreshDir("collect");
  JobStore store(dir / "state.db");
  BlobStore blobs(dir / "blobs");
  const std::string bundle = blobs.Put("bundle"), output = blobs.Put("form"), subtree = blobs.Put("subtree"),
                    plan = blobs.Put("plan input"), stray = blobs.Put("stray");
  ASSERT_TRUE(store.CreateJob({"j", bundle, "d", JobState::kRunning, "", 1, 0}));
  store.AddTasks({{"k1", "j", 1, "p", {}}});
  auto grants = store.GrantLeases("w", 1, 1000, 5000);
  ASSERT_EQ(grants.size(), 1u);
  EXPECT_EQ(store.OldestActiveLeaseMs(), 1000);
  Completion c;
  c.lease_id = grants[0].lease_id;
  c.task_key = "k1";
  c.attempt = grants[0].attempt;
  c.sample_valid = 1;
  c.point_key = "0,0";
  c.subtrees.push_back({"s1", "t", "union", 1.0, true, 10, {}, subtree});
  store.Complete({c}, 2000, 100);
  EXPECT_EQ(store.OldestActiveLeaseMs(), -1);
  store.AddJobBlob("j", plan);
  store.PutJobOutput("j", "form.json", output);
  std::vector<std::string> running = {bundle, output, subtree, plan};
  std::sort(running.begin(), running.end());
  EXPECT_EQ(store.ReferencedBlobs(), running);

  // A cutoff before every blob's mtime: nothing goes, not even the stray.
  auto kept = blobs.Collect(store.ReferencedBlobs(), 0);
  EXPECT_EQ(kept.blobs_removed, 0);
  EXPECT_TRUE(blobs.Contains(stray));
  // A cutoff after them: only the stray goes while the job runs.
  const std::int64_t later =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count() +
      60000;
  auto swept = blobs.Collect(store.ReferencedBlobs(), later);
  EXPECT_EQ(swept.blobs_removed, 1);
  EXPECT_FALSE(blobs.Contains(stray));
  EXPECT_TRUE(blobs.Contains(subtree));
  // The job ended: its geometry and plan blobs go, bundle and outputs stay.
  store.SetJobState("j", JobState::kSucceeded, "", 3000);
  std::vector<std::string> ended = {bundle, output};
  std::sort(ended.begin(), ended.end());
  EXPECT_EQ(store.ReferencedBlobs(), ended);
  auto after = blobs.Collect(store.ReferencedBlobs(), later);
  EXPECT_EQ(after.blobs_removed, 2);
  EXPECT_FALSE(blobs.Contains(subtree));
  EXPECT_FALSE(blobs.Contains(plan));
  EXPECT_TRUE(blobs.Verify(bundle));
  EXPECT_TRUE(blobs.Verify(output));
  // Collecting again finds nothing (idempotent: a crash part-way is finished
  // by the next pass).
  EXPECT_EQ(blobs.Collect(store.ReferencedBlobs(), later).blobs_removed, 0);
  // Touch makes an old blob new again.
  EXPECT_TRUE(blobs.Touch(bundle));
  EXPECT_FALSE(blobs.Touch(stray));
}

// The partial-upload grace of Collect (blob_store.h): a partial upload is
// kept while it was touched within a day of the cutoff, whatever `keep`
// says, so an upload paused by a worker's restart or a partition can resume;
// past the day it goes, and so does an unreferenced finished blob as old.
// Ages are set on the files (utimensat) one hour either side of the day.
TEST(ClusterStorage, CollectKeepsAPartialUploadForADayThenRemovesIt) {
  fs::path dir = FreshDir("collect_grace");
  BlobStore blobs(dir / "blobs");
  const std::string data = "bytes of an upload that paused half way";
  const std::string digest = fabatlas::Sha256Hex(data);
  ASSERT_EQ(blobs.Append(digest, 0, data.substr(0, 10)), 10);
  const std::string finished = blobs.Put("an unreferenced finished blob");
  const fs::path partial = dir / "blobs/partial" / digest;
  ASSERT_TRUE(fs::exists(partial));
  const std::int64_t now_ms =
      std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  const std::int64_t day_ms = 86400000, hour_ms = 3600000;
  const auto set_age = [&](const fs::path& file, std::int64_t modified_ms) {
    timespec times[2];
    times[0].tv_sec = times[1].tv_sec = modified_ms / 1000;
    times[0].tv_nsec = times[1].tv_nsec = (modified_ms % 1000) * 1000000;
    ASSERT_EQ(::utimensat(AT_FDCWD, file.c_str(), times, 0), 0) << file;
  };
  // 23 hours before the cutoff: the partial upload stays, the finished
  // blob (older than the cutoff, referenced by nothing) goes.
  const std::int64_t cutoff = now_ms;
  set_age(partial, cutoff - day_ms + hour_ms);
  set_age(blobs.PathOf(finished), cutoff - day_ms + hour_ms);
  BlobStore::Collection c = blobs.Collect({}, cutoff);
  EXPECT_EQ(c.blobs_removed, 1);
  EXPECT_EQ(c.blobs_kept, 1);
  EXPECT_FALSE(blobs.Contains(finished));
  EXPECT_TRUE(fs::exists(partial));
  EXPECT_EQ(blobs.CommittedSize(digest), 10);
  // It resumes where it stopped and is published whole.
  EXPECT_EQ(blobs.Append(digest, 10, data.substr(10)), static_cast<std::int64_t>(data.size()));
  // A second upload paused 25 hours before the cutoff: removed, and its
  // upload starts again from 0.
  const std::string other = "another upload, abandoned";
  const std::string other_digest = fabatlas::Sha256Hex(other);
  ASSERT_EQ(blobs.Append(other_digest, 0, other.substr(0, 7)), 7);
  set_age(dir / "blobs/partial" / other_digest, cutoff - day_ms - hour_ms);
  c = blobs.Collect({}, cutoff);
  EXPECT_EQ(c.blobs_removed, 1);
  EXPECT_EQ(c.bytes_removed, 7);
  EXPECT_FALSE(fs::exists(dir / "blobs/partial" / other_digest));
  EXPECT_EQ(blobs.CommittedSize(other_digest), 0);
  // The first one, touched just now by its last chunk, is still there.
  EXPECT_EQ(blobs.CommittedSize(digest), static_cast<std::int64_t>(data.size()));
  blobs.Finish(digest);
  EXPECT_TRUE(blobs.Verify(digest));
}

// A full disk under the blob store (a 2 MiB tmpfs, filled): a Put fails with
// one line naming the file and the reason, the blob is not in the store
// (not listed, not readable), the blobs stored before still verify, and
// once space is back the same Put succeeds and verifies.
TEST(ClusterStorage, FullDiskPutFailsCleanlyAndSucceedsOnceSpaceIsBack) {
  if (!fabatlas::testing::SmallFileSystem::Possible()) GTEST_SKIP() << "mounting a small tmpfs needs root";
  fs::path dir = FreshDir("blobs_full");
  fabatlas::testing::SmallFileSystem disk(dir / "mnt", 2);
  ASSERT_TRUE(disk.mounted()) << disk.error();
  BlobStore blobs(disk.dir() / "blobs");
  const std::string before = blobs.Put("stored before the disk filled");
  disk.Fill();
  const std::string data(256 << 10, 'b');
  const std::string digest = fabatlas::Sha256Hex(data);
  try {
    blobs.Put(data);
    ADD_FAILURE() << "a Put succeeded on a full disk";
  } catch (const fabatlas::ResourceError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find((disk.dir() / "blobs").string()), std::string::npos) << what;
    EXPECT_NE(what.find("No space left on device"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  EXPECT_FALSE(blobs.Contains(digest));
  auto listed = blobs.List();
  EXPECT_EQ(listed, std::vector<std::string>{before});
  EXPECT_THROW(blobs.Read(digest), fabatlas::InputError);
  EXPECT_TRUE(blobs.Verify(before));
  disk.Free();
  EXPECT_EQ(blobs.Put(data), digest);
  EXPECT_TRUE(blobs.Verify(digest));
  EXPECT_EQ(blobs.Read(digest), data);
  EXPECT_TRUE(blobs.Verify(before));
}
