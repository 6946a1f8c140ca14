// Static solves running at the same time in one process (the in-process
// road's sample threads, a worker's slots) give the same bits as a solve run
// alone, whatever the TBB arena they run in: the form and the artifact of a
// job must not depend on which samples happened to overlap (issue 13, the
// sandal's roads test). What used to differ: CHOLMOD's nested-dissection
// ordering (METIS) draws from a random generator held in process-global
// state, so two orderings at once interleaved their draws and returned
// different permutations, hence different roundings (docs/fem.md).
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include <cstring>
#include <latch>
#include <thread>
#include <vector>

#include "cantilever.h"
#include "fabatlas/fem/static_solve.h"

namespace fabatlas::fem {
namespace {

// Bit-for-bit equality of two solutions (memcmp: -0.0 and NaN compare too).
bool SameBits(const StaticSolveSummary& a, const StaticSolveSummary& b) {
  return a.displacements.size() == b.displacements.size() &&
         std::memcmp(a.displacements.data(), b.displacements.data(), a.displacements.size() * sizeof(Vec3)) == 0 &&
         std::memcmp(&a.max_principal_strain, &b.max_principal_strain, sizeof(double)) == 0 &&
         a.newton_iterations == b.newton_iterations && a.factorizations == b.factorizations;
}

TEST(FemConcurrentSolves, GiveTheBitsOfASolveAlone) {
  // A 12 mm cube of 1 mm voxels clamped at x = 0 and sheared at x = 12: the
  // smallest such block whose ordering CHOLMOD takes from METIS rather than
  // AMD (fewer factor flops; smaller blocks keep AMD's), about 1 s of CPU a
  // solve (one load step, three Newton iterations).
  const Cantilever c = MakeCantilever(12, 12, 1.0, 1.0);
  const Material material = Material::FromYoungPoisson(100, 0.3);
  StaticSolveOptions options;
  options.load_steps = 1;
  const StaticSolveSummary alone = SolveStatic(c.mesh, material, c.bc, options);
  ASSERT_TRUE(alone.converged) << alone.message;
  constexpr int kThreads = 3, kRounds = 2;
  tbb::global_control parallelism(tbb::global_control::max_allowed_parallelism, kThreads);
  int differing = 0;
  for (int round = 0; round < kRounds; ++round) {
    std::vector<StaticSolveSummary> out(kThreads);
    std::latch start(kThreads);
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
      threads.emplace_back([&, t] {
        // Arenas of 1, 2 and 3 threads: the split of the element loops
        // changes too.
        tbb::task_arena arena(1 + t);
        start.arrive_and_wait();
        arena.execute([&] { out[t] = SolveStatic(c.mesh, material, c.bc, options); });
      });
    for (auto& t : threads) t.join();
    for (int t = 0; t < kThreads; ++t)
      if (!SameBits(out[t], alone)) ++differing;
  }
  EXPECT_EQ(differing, 0) << "of " << kThreads * kRounds << " concurrent solves";
}

}  // namespace
}  // namespace fabatlas::fem
