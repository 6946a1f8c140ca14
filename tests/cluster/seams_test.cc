// The coordinator's and the worker's parts that need no process: lease
// affinity of a sample batch, the worker's shelf of root solids and a job
// as a worker loads it.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <future>
#include <map>
#include <set>
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/protocol/solid_blob.h"
#include "fabatlas/sampling/sample_evaluator.h"
#include "fabatlas/sha256.h"
#include "fabatlas/testing/paths.h"
#include "job_cache.h"
#include "remote_executor.h"
#include "solid_shelf.h"
#include "subtree_uploads.h"

namespace fabatlas {
namespace {

namespace fs = std::filesystem;

// Runs in proportion to slots: 10 tasks over a 1-slot and a 3-slot worker
// are cut at 10 * 1/4 = 2 (floor); three 1-slot workers over 7 tasks at
// floor(7/3) = 2 and floor(14/3) = 4. One worker: no preference.
TEST(SampleBatchAffinity, ContiguousRunsInProportionToSlots) {
  const auto two = coordinator::SampleBatchAffinity(10, {{"a", 1}, {"b", 3}});
  ASSERT_EQ(two.size(), 10u);
  for (std::size_t i = 0; i < 10; ++i) EXPECT_EQ(two[i], std::vector<std::string>{i < 2 ? "a" : "b"}) << i;
  const auto three = coordinator::SampleBatchAffinity(7, {{"a", 1}, {"b", 1}, {"c", 1}});
  const std::vector<std::string> expected = {"a", "a", "b", "b", "c", "c", "c"};
  for (std::size_t i = 0; i < 7; ++i) EXPECT_EQ(three[i], std::vector<std::string>{expected[i]}) << i;
  for (const auto& p : coordinator::SampleBatchAffinity(5, {{"a", 4}})) EXPECT_TRUE(p.empty());
}

// Least recently used out once over budget; a Get makes a blob recent; the
// latest blob stays even when it alone is over budget.
TEST(SolidShelf, DropsTheLeastRecentlyUsedOverBudget) {
  worker::SolidShelf shelf;
  shelf.SetBudget(30);
  shelf.Put({1}, std::string(10, 'a'));
  shelf.Put({2}, std::string(10, 'b'));
  shelf.Put({3}, std::string(10, 'c'));
  EXPECT_EQ(shelf.bytes(), 30u);
  ASSERT_TRUE(shelf.Get({1}));  // {2} is now the least recent
  shelf.Put({4}, std::string(10, 'd'));
  EXPECT_FALSE(shelf.Get({2}));
  EXPECT_EQ(*shelf.Get({1}), std::string(10, 'a'));
  EXPECT_EQ(shelf.bytes(), 30u);
  shelf.Put({5}, std::string(100, 'e'));
  EXPECT_EQ(shelf.bytes(), 100u);
  EXPECT_TRUE(shelf.Get({5}));
  EXPECT_FALSE(shelf.Get({1}));
}

// A job as a worker loads it from its bundle: the design evaluates, and with
// the job file's min_subtree_seconds at 0 a subtree's geometry is uploaded
// at its key's second use on the worker, once (tasks.proto "Geometry
// blobs"): the first evaluation of a point uploads nothing (each key used
// once), the second (every key a cache hit) uploads each key's level set,
// the third nothing more.
TEST(LoadJobContext, UploadsASubtreeAtItsSecondUseOnly) {
  const fs::path dir = fs::temp_directory_path() / ("fabatlas_seams_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const v1::JobBundle bundle = protocol::MakeJobBundle(testing::SourceDir() / "tests/cluster/data/tube_cache.yaml");
  std::map<std::string, std::string> uploaded;
  int uploads = 0;
  auto ctx = worker::LoadJobContext(bundle, dir, 256, [&](const std::string& bytes) {
    const std::string digest = Sha256Hex(bytes);
    uploaded[digest] = bytes;
    ++uploads;
    return digest;
  });
  ASSERT_TRUE(ctx->evaluator);
  EXPECT_EQ(ctx->min_subtree_seconds, 0.0);
  sampling::SamplePoint point;
  point.key = {0, 0};
  point.u.clear();
  for (const auto& p : ctx->evaluator->design().exposed) point.u.push_back(p.default_value);
  const design::SampleResult first = ctx->evaluator->Evaluate(point);
  ASSERT_FALSE(first.subtrees.empty());
  std::set<std::string> keys;
  for (const auto& s : first.subtrees) {
    EXPECT_FALSE(s.from_cache) << s.key;
    keys.insert(s.key);
  }
  ASSERT_EQ(keys.size(), first.subtrees.size());  // each key used once
  worker::UploadReusedSubtrees(*ctx, first.subtrees);
  EXPECT_EQ(uploads, 0);
  for (const auto& key : keys) EXPECT_EQ(ctx->subtree_uploads.DigestOf(key), "") << key;

  const design::SampleResult second = ctx->evaluator->Evaluate(point);
  worker::UploadReusedSubtrees(*ctx, second.subtrees);
  EXPECT_EQ(uploads, static_cast<int>(keys.size()));
  EXPECT_EQ(ctx->subtree_uploads.uploaded(), keys.size());
  for (const auto& key : keys) {
    const std::string digest = ctx->subtree_uploads.DigestOf(key);
    ASSERT_TRUE(uploaded.count(digest)) << key;
    EXPECT_GT(protocol::SolidOfBlob(uploaded[digest]).MemoryBytes(), 0u) << key;
  }
  EXPECT_EQ(ctx->subtree_uploads.waiting_bytes(), 0u);

  worker::UploadReusedSubtrees(*ctx, ctx->evaluator->Evaluate(point).subtrees);
  EXPECT_EQ(uploads, static_cast<int>(keys.size()));
  fs::remove_all(dir);
}

// Geometry waits for its key's second use within a budget, oldest dropped
// first: a key dropped before its second use is not uploaded then, and is
// once it is computed again and used again.
TEST(SubtreeUploads, WaitsForTheSecondUseWithinABudget) {
  const geometry::GridSpec grid;
  const geometry::Solid a = geometry::Sphere(grid, 2.0), b = geometry::Sphere(grid, 3.0);
  worker::SubtreeUploads uploads;
  uploads.SetBudget(a.MemoryBytes() + b.MemoryBytes() / 2);
  uploads.Computed("a", a);
  uploads.Computed("b", b);  // over budget: "a", the oldest, is dropped
  EXPECT_EQ(uploads.waiting_bytes(), b.MemoryBytes());
  EXPECT_TRUE(uploads.Used({"a", "b"}).empty());  // first uses
  auto reused = uploads.Used({"a", "b", "b"});
  ASSERT_EQ(reused.size(), 1u);
  EXPECT_EQ(reused[0].first, "b");
  uploads.Uploaded("b", "digest-b");
  uploads.Computed("b", b);  // uploaded: does not wait again
  EXPECT_EQ(uploads.waiting_bytes(), 0u);
  EXPECT_TRUE(uploads.Used({"b"}).empty());
  uploads.Computed("a", a);  // computed again after the drop
  reused = uploads.Used({"a"});
  ASSERT_EQ(reused.size(), 1u);
  uploads.Uploaded("a", "");  // a failed upload records nothing
  EXPECT_EQ(uploads.DigestOf("a"), "");
  EXPECT_EQ(uploads.DigestOf("b"), "digest-b");
  EXPECT_EQ(uploads.uploaded(), 1u);
}

// Bundle confinement on the worker (issue 31): a bundle that did not come
// through `fabatlas submit` (a client of its own) whose model imports a file
// outside the bundle by absolute path: the evaluation is refused with the
// model's file, line and statement before anything opens that file (a FIFO:
// opening it to read would block until the guard below writes to it).
TEST(LoadJobContext, AModelNamingAFileOutsideItsBundleIsRefusedBeforeItIsRead) {
  const fs::path dir = testing::FreshTempDir("confine_worker");
  fs::create_directories(dir / "job");
  std::ofstream(dir / "job/model.scad") << "size = 10;\ncube(size);\n";
  std::ofstream(dir / "job/design.yaml") << "name: hostile_model\nparameters:\n"
                                            "  size: {type: real, min: 5, max: 15, default: 10}\n"
                                            "tree: {op: openscad, file: model.scad, set: {size: size}}\n";
  std::ofstream(dir / "job/job.yaml") << "design: design.yaml\nsampling: {subdivisions: 2, max_depth: 0}\n";
  v1::JobBundle bundle = protocol::MakeJobBundle(dir / "job/job.yaml");
  const fs::path fifo = dir / "secret.stl";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string statement = "import(\"" + fifo.string() + "\")";
  ASSERT_EQ(bundle.files().count("model.scad"), 1u);
  (*bundle.mutable_files())["model.scad"] = "size = 10;\ncube(size);\n" + statement + ";\n";

  auto ctx =
      worker::LoadJobContext(bundle, dir / "cache", 256, [](const std::string& bytes) { return Sha256Hex(bytes); });
  ASSERT_TRUE(ctx->evaluator);
  sampling::SamplePoint point;
  point.key = {0};
  point.u = {10.0};
  auto evaluation = std::async(std::launch::async, [&]() -> std::string {
    try {
      ctx->evaluator->Evaluate(point);
      return "evaluated";
    } catch (const InputError& e) {
      return e.what();
    }
  });
  if (evaluation.wait_for(std::chrono::seconds(120)) != std::future_status::ready) {
    const int fd = ::open(fifo.c_str(), O_WRONLY | O_NONBLOCK);  // lets a blocked reader go on
    if (fd >= 0) ::close(fd);
    ADD_FAILURE() << "the evaluation opened " << fifo;
  }
  const std::string what = evaluation.get();
  EXPECT_NE(what.find("model.scad:3: " + statement + " names an absolute path"), std::string::npos) << what;
  EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace fabatlas
