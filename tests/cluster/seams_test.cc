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
#include <string>

#include "fabatlas/error.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/sampling/sample_evaluator.h"
#include "fabatlas/sha256.h"
#include "fabatlas/testing/paths.h"
#include "job_cache.h"
#include "remote_executor.h"
#include "solid_shelf.h"

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
// the job file's min_subtree_seconds at 0 every subtree the evaluator
// computes is uploaded once and recorded under its key (tasks.proto
// "Geometry blobs"); a second evaluation of the same point computes nothing
// new and uploads nothing.
TEST(LoadJobContext, EvaluatesAndUploadsEverySubtreeOnce) {
  const fs::path dir = fs::temp_directory_path() / ("fabatlas_seams_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  const v1::JobBundle bundle = protocol::MakeJobBundle(testing::SourceDir() / "tests/cluster/data/tube_cache.yaml");
  std::map<std::string, std::string> uploaded;
  auto ctx = worker::LoadJobContext(bundle, dir, 256, [&](const std::string& bytes) {
    const std::string digest = Sha256Hex(bytes);
    uploaded[digest] = bytes;
    return digest;
  });
  ASSERT_TRUE(ctx->evaluator);
  EXPECT_EQ(ctx->min_subtree_seconds, 0.0);
  sampling::SamplePoint point;
  point.key = {0, 0};
  point.u.clear();
  for (const auto& p : ctx->evaluator->design().exposed) point.u.push_back(p.default_value);
  const design::SampleResult r = ctx->evaluator->Evaluate(point);
  ASSERT_FALSE(r.subtrees.empty());
  EXPECT_EQ(ctx->subtree_blobs.size(), r.subtrees.size());
  EXPECT_EQ(uploaded.size(), r.subtrees.size());
  for (const auto& s : r.subtrees) EXPECT_EQ(ctx->subtree_blobs.count(s.key), 1u) << s.key;
  ctx->evaluator->Evaluate(point);
  EXPECT_EQ(uploaded.size(), r.subtrees.size());
  fs::remove_all(dir);
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
