// Spacetime collision broad phase: the 4D proxy hierarchy against testing
// every pair of proxies, on a scene of many small moving parts (same result,
// compared side by side). Usage: bench_collision [--parts 80] [--steps 101] [--repeats 5]
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

int main(int argc, char** argv) {
  int parts_n = 80, steps = 101, repeats = 5;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--parts")) parts_n = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--steps")) steps = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--repeats")) repeats = std::atoi(argv[i + 1]);
    else return std::fprintf(stderr, "usage: bench_collision [--parts N] [--steps N] [--repeats N]\n"), 2;
  }
  // Unit cubes on straight lines between random points of a 60 mm cube (fixed seed).
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 60);
  std::vector<MovingPart> parts(parts_n);
  for (auto& p : parts) {
    p.mesh = testing::BoxMesh({0, 0, 0}, {1, 1, 1});
    p.motion = RigidMotion::Line({u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)});
  }
  auto run = [&](SpacetimeOptions::BroadPhase b, CollisionReport* out) {
    SpacetimeOptions o;
    o.time_steps = steps;
    o.broad_phase = b;
    std::vector<double> t;
    for (int r = 0; r < repeats; ++r) {
      const auto t0 = std::chrono::steady_clock::now();
      *out = DetectCollisions(parts, o);
      t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
  };
  CollisionReport h, a;
  const double th = run(SpacetimeOptions::BroadPhase::kHierarchy, &h);
  const double ta = run(SpacetimeOptions::BroadPhase::kAllPairs, &a);
  std::printf("%d parts, %d steps, %zu proxies, %zu candidate proxy pairs, %zu exact tests, %zu intervals\n",
              parts_n, steps, h.proxies, h.candidate_pairs, h.exact_tests, h.intervals.size());
  std::printf("hierarchy: median %.4f s; all pairs: median %.4f s; ratio %.1fx (same intervals: %s)\n", th, ta,
              ta / th, h.intervals.size() == a.intervals.size() ? "yes" : "NO");
  return 0;
}
