// bench_viewer_runtime ARTIFACT [POINTS=200] [SEED=1] — the viewer's runtime
// costs on a published artifact, by the method of Fab Forms Fig. 14: POINTS
// random valid points (precompute::RandomValidPoints, uniform in the space,
// kept when valid), and at each
//   * lookup: IsValid + the stretches along every dimension (what
//     /api/intervals computes), wall time;
//   * snap: the ΔG-weighted snap;
//   * preview: EvaluateSample of the snapped sample without checks (what
//     /api/preview.glb evaluates), with no cache, with the artifact's H_opt
//     and H_rfree when it has a cache, and with "H_all": every subtree of
//     every valid sample held in memory (computed here; an upper bound on
//     what any cache can give, H_TOP included);
//   * mesh+glb: meshing the preview and writing the glTF binary.
// Prints p50 / p99 / max in ms. Single-threaded.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/precompute/preview_times.h"
#include "fabatlas/viewer/customiser.h"
#include "fabatlas/artifact/glb.h"

using namespace fabatlas;
using Clock = std::chrono::steady_clock;

namespace {

double Ms(Clock::duration d) { return std::chrono::duration<double, std::milli>(d).count(); }

struct Quantiles {
  double p50, p99, max, mean;
};
Quantiles Of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))]; };
  double sum = 0;
  for (double x : v) sum += x;
  return {at(0.5), at(0.99), v.back(), sum / v.size()};
}
void Print(const char* what, const std::vector<double>& ms) {
  const Quantiles q = Of(ms);
  std::printf("%-28s n=%3zu  p50 %9.3f ms  p99 %9.3f ms  max %9.3f ms  mean %9.3f ms\n", what, ms.size(), q.p50, q.p99,
              q.max, q.mean);
}

// Records every subtree evaluation offers (for H_all).
class RecordingCache final : public design::SubtreeCache {
 public:
  std::optional<design::CachedSubtree> Find(const std::string& key) override {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = entries.find(key);
    if (it == entries.end()) return std::nullopt;
    return design::CachedSubtree{it->second.first};
  }
  void Offer(const std::string& key, const design::CachedSubtree& subtree, double seconds) override {
    std::lock_guard<std::mutex> lock(mutex_);
    entries.emplace(key, std::make_pair(subtree.solid, seconds));
  }
  std::map<std::string, std::pair<geometry::Solid, double>> entries;

 private:
  std::mutex mutex_;
};

std::vector<double> PreviewTimes(const viewer::Customiser& c, const std::vector<std::int64_t>& samples, bool cache,
                                 std::vector<double>* mesh_ms = nullptr, int* hits = nullptr, int* subtrees = nullptr) {
  std::vector<double> ms;
  for (std::int64_t s : samples) {
    const viewer::PreviewResult p = c.Preview(s, cache);
    ms.push_back(p.seconds * 1000);
    if (hits) *hits += p.cache_hits;
    if (subtrees) *subtrees += p.subtrees;
    if (mesh_ms) {
      const auto t0 = Clock::now();
      const std::string glb = artifact::MeshToGlb(p.solid.ToMesh());
      mesh_ms->push_back(Ms(Clock::now() - t0));
    }
  }
  return ms;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_viewer_runtime ARTIFACT [POINTS=200] [SEED=1]\n");
    return 2;
  }
  const int count = argc > 2 ? std::atoi(argv[2]) : 200;
  const std::uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  try {
    viewer::Customiser opt(viewer::LoadArtifact(argv[1], viewer::CacheChoice::kOpt));
    const auto& form = opt.form();
    const auto points = precompute::RandomValidPoints(form, count, seed);
    std::printf("artifact %s: design %s, %zu samples, %zu random valid points (seed %llu), cache %s (%zu entries)\n",
                argv[1], opt.source().name.c_str(), form.samples.size(), points.size(),
                static_cast<unsigned long long>(seed), opt.source().cache_name.c_str(), opt.source().cache.size());

    // Lookups: warm once, then time each point.
    std::vector<double> lookup_ms, snap_ms;
    std::vector<std::int64_t> snapped;
    for (const auto& u : points)
      for (int d = 0; d < opt.dimension_count(); ++d) (void)opt.Stretches(u, d);
    for (const auto& u : points) {
      const auto t0 = Clock::now();
      bool valid = opt.IsValid(u);
      size_t stretches = 0;
      for (int d = 0; d < opt.dimension_count(); ++d) stretches += opt.Stretches(u, d).size();
      const auto t1 = Clock::now();
      const auto snap = opt.SnapTo(u);
      const auto t2 = Clock::now();
      if (!valid || stretches == 0 || !snap) {
        std::fprintf(stderr, "a random valid point was not valid in the runtime\n");
        return 1;
      }
      lookup_ms.push_back(Ms(t1 - t0));
      snap_ms.push_back(Ms(t2 - t1));
      snapped.push_back(snap->sample);
    }
    Print("lookup (valid + intervals)", lookup_ms);
    Print("snap", snap_ms);

    std::vector<double> mesh_ms;
    Print("preview, no cache", PreviewTimes(opt, snapped, false, &mesh_ms));
    Print("mesh + glb", mesh_ms);
    if (opt.source().cache_name != "none") {
      int hits = 0, subtrees = 0;
      Print("preview, H_opt", PreviewTimes(opt, snapped, true, nullptr, &hits, &subtrees));
      std::printf("  H_opt cache hits %d of %d subtree lookups\n", hits, subtrees);
      viewer::Customiser rfree(viewer::LoadArtifact(argv[1], viewer::CacheChoice::kRfree));
      hits = subtrees = 0;
      Print("preview, H_rfree", PreviewTimes(rfree, snapped, true, nullptr, &hits, &subtrees));
      std::printf("  H_rfree cache hits %d of %d subtree lookups\n", hits, subtrees);
    } else {
      std::printf("preview, H_opt / H_rfree: the artifact has no geometry cache\n");
    }

    // H_all: every subtree of every valid sample, evaluated here.
    viewer::CustomiserSource all = viewer::LoadArtifact(argv[1], viewer::CacheChoice::kNone);
    RecordingCache recorder;
    const auto t0 = Clock::now();
    for (const auto& s : all.form.samples) {
      if (!s.outcome.valid) continue;
      design::EvaluateOptions o;
      o.cache = &recorder;
      o.run_checks = false;
      (void)design::EvaluateSample(*all.design, precompute::DesignPointOf(*all.design, s.u), o);
    }
    std::printf("H_all: %zu subtrees from every valid sample in %.1f s\n", recorder.entries.size(),
                std::chrono::duration<double>(Clock::now() - t0).count());
    all.cache = std::move(recorder.entries);
    all.cache_name = "H_all";
    viewer::Customiser with_all(std::move(all));
    int hits = 0, subtrees = 0;
    Print("preview, H_all", PreviewTimes(with_all, snapped, true, nullptr, &hits, &subtrees));
    std::printf("  H_all cache hits %d of %d subtree lookups\n", hits, subtrees);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_viewer_runtime: %s\n", e.what());
    return 2;
  }
  return 0;
}
