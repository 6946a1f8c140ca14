// Spacetime collision broad phase: our 4D proxy hierarchy against Embree's
// rtcCollide (proxies flattened to 3D slabs per time interval) and against
// testing every pair of proxies, on a scene of many small moving parts (same
// result, compared side by side in one run; medians of whole DetectCollisions
// calls and of the broad phase alone).
// Usage: bench_collision [--parts 80] [--steps 101] [--repeats 5] [--no-all-pairs]
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <vector>

#include "../../tests/swept/test_shapes.h"
#include "fabatlas/swept/spacetime_collision.h"

using namespace fabatlas::swept;

// Process CPU seconds so far (user + system, all threads).
static double CpuSeconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_stime.tv_sec + 1e-6 * (u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

int main(int argc, char** argv) {
  int parts_n = 80, steps = 101, repeats = 5;
  bool all_pairs = true;
  for (int i = 1; i < argc; i += 2) {
    if (!std::strcmp(argv[i], "--no-all-pairs")) {
      all_pairs = false;
      --i;
    } else if (i + 1 >= argc)
      return std::fprintf(stderr, "usage: bench_collision [--parts N] [--steps N] [--repeats N] [--no-all-pairs]\n"), 2;
    else if (!std::strcmp(argv[i], "--parts"))
      parts_n = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--steps"))
      steps = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--repeats"))
      repeats = std::atoi(argv[i + 1]);
    else
      return std::fprintf(stderr, "usage: bench_collision [--parts N] [--steps N] [--repeats N]\n"), 2;
  }
  // Unit cubes on straight lines between random points of a 60 mm cube (fixed seed).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 60);
  std::vector<MovingPart> parts(parts_n);
  for (auto& p : parts) {
    p.mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
    p.motion = RigidMotion::Line({u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)});
  }
  auto median = [](std::vector<double> t) {
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
  };
  struct Timing {
    double total = 0, broad = 0, cpu = 0;
  };
  auto run = [&](SpacetimeOptions::BroadPhase b, CollisionReport* out) {
    SpacetimeOptions o;
    o.time_steps = steps;
    o.broad_phase = b;
    std::vector<double> t, bt, ct;
    for (int r = 0; r < repeats; ++r) {
      const double c0 = CpuSeconds();
      const auto t0 = std::chrono::steady_clock::now();
      *out = DetectCollisions(parts, o);
      t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      ct.push_back(CpuSeconds() - c0);
      bt.push_back(out->broad_phase_seconds);
    }
    return Timing{median(t), median(bt), median(ct)};
  };
  auto same = [](const CollisionReport& x, const CollisionReport& y) {
    if (x.intervals.size() != y.intervals.size() || x.candidate_pairs != y.candidate_pairs) return false;
    for (std::size_t i = 0; i < x.intervals.size(); ++i) {
      const auto &a = x.intervals[i], &b = y.intervals[i];
      if (a.t_begin != b.t_begin || a.t_end != b.t_end || a.part_a != b.part_a || a.part_b != b.part_b) return false;
    }
    return true;
  };
  CollisionReport h, e, a;
  const Timing th = run(SpacetimeOptions::BroadPhase::kHierarchy, &h);
  const Timing te = run(SpacetimeOptions::BroadPhase::kEmbree, &e);
  std::printf("%d parts, %d steps, %zu proxies, %zu candidate proxy pairs, %zu exact tests, %zu intervals\n", parts_n,
              steps, h.proxies, h.candidate_pairs, h.exact_tests, h.intervals.size());
  std::printf("4D hierarchy: median %.4f s wall, %.4f s CPU (broad phase %.5f s wall)\n", th.total, th.cpu, th.broad);
  std::printf("Embree rtcCollide: median %.4f s wall, %.4f s CPU (broad phase %.5f s wall); same intervals: %s\n",
              te.total, te.cpu, te.broad, same(h, e) ? "yes" : "NO");
  std::printf("ratio Embree / hierarchy: %.2f whole, %.2f broad phase\n", te.total / th.total, te.broad / th.broad);
  if (all_pairs) {
    const Timing ta = run(SpacetimeOptions::BroadPhase::kAllPairs, &a);
    std::printf("all pairs: median %.4f s wall, %.4f s CPU (broad phase %.5f s wall); same intervals: %s\n", ta.total,
                ta.cpu, ta.broad, same(h, a) ? "yes" : "NO");
    std::printf("ratio all pairs / hierarchy: %.1f whole, %.1f broad phase\n", ta.total / th.total,
                ta.broad / th.broad);
  }
  return 0;
}
