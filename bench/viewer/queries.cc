// bench_viewer_queries ARTIFACT [QUERIES=200] [SEED=1] — what objective and
// trade-off answers cost (docs/viewer.md "Objectives and trade-offs"): the
// artifact loaded as `fabatlas serve` loads it (viewer::LoadArtifact, no
// geometry cache), then QUERIES answers of each kind through the API handler
// (HandleApiRequest: parsing, the query, the JSON), wall time per answer:
//   * optimise, free: min or max (alternating) of the first recorded
//     property, nothing held (a scan of the valid samples);
//   * optimise, held: the same with one parameter (in turn) held at a
//     uniformly random value of its range (the slice's leaves);
//   * pareto: the first property (min) against a parameter (max, in turn),
//     with up to 400 dominated samples, as the page asks.
// One warm-up answer of each kind first. Prints p50 / p99 / max in ms, the
// answer sizes and the front's length. Single-threaded.
#include <algorithm>
#include <cmath>
#include <map>
#include <stdexcept>
#include <chrono>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "fabatlas/viewer/customiser.h"
#include "fabatlas/viewer/http_api.h"

using namespace fabatlas;
using Clock = std::chrono::steady_clock;

namespace {

void Print(const char* what, std::vector<double> ms, std::size_t bytes) {
  std::sort(ms.begin(), ms.end());
  const auto at = [&](double q) {
    return ms[std::min(ms.size() - 1, static_cast<std::size_t>(q * (ms.size() - 1) + 0.5))];
  };
  std::printf("%-16s n=%4zu  p50 %8.3f ms  p99 %8.3f ms  max %8.3f ms  answer %zu B\n", what, ms.size(), at(0.5),
              at(0.99), ms.back(), bytes);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_viewer_queries ARTIFACT [QUERIES=200] [SEED=1]\n");
    return 2;
  }
  const int count = argc > 2 ? std::atoi(argv[2]) : 200;
  const std::uint64_t seed = argc > 3 ? std::strtoull(argv[3], nullptr, 10) : 1;
  try {
    const auto t_load = Clock::now();
    const viewer::Customiser c(viewer::LoadArtifact(argv[1], viewer::CacheChoice::kNone));
    const double load_s = std::chrono::duration<double>(Clock::now() - t_load).count();
    std::string property;
    for (const auto& s : c.form().samples)
      if (s.outcome.valid && !s.outcome.properties.empty()) {
        property = s.outcome.properties.begin()->first;
        break;
      }
    if (property.empty()) throw std::runtime_error("no valid sample records a property");
    std::printf(
        "artifact %s: design %s, %zu samples, %zu leaves, loaded in %.2f s; objective '%s', %d queries, seed %llu\n",
        argv[1], c.source().name.c_str(), c.form().samples.size(), c.corners().leaves(), load_s, property.c_str(),
        count, static_cast<unsigned long long>(seed));
    std::mt19937_64 rng(seed);
    const int n = c.dimension_count();
    const auto answer = [&](const std::string& path, const std::map<std::string, std::string>& query, double* ms) {
      const auto t0 = Clock::now();
      viewer::ApiResponse r = viewer::HandleApiRequest(c, path, query);
      *ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
      if (r.status != 200) throw std::runtime_error(path + ": " + r.body);
      return r.body;
    };
    const auto free_query = [&](int k) {
      return std::map<std::string, std::string>{{k % 2 ? "max" : "min", property}};
    };
    const auto held_query = [&](int k) {
      const int d = k % n;
      const auto& space = c.space();
      const double lo = space.value(d, space.key_lo(d)), hi = space.value(d, space.key_hi(d));
      double v = std::uniform_real_distribution<double>(lo, hi)(rng);
      if (space.is_discrete(d)) v = std::round(v);
      char text[64];
      std::snprintf(text, sizeof text, "%.17g", v);
      auto q = free_query(k);
      q["hold"] = space.dimension(d).name + "=" + text;
      return q;
    };
    const auto pareto_query = [&](int k) {
      return std::map<std::string, std::string>{{"axes", property + ",max:" + c.space().dimension(k % n).name},
                                                {"dominated", "400"}};
    };
    double ms = 0;
    std::vector<double> free_ms, held_ms, pareto_ms;
    std::size_t free_bytes = 0, held_bytes = 0, pareto_bytes = 0, front = 0;
    (void)answer("/api/optimise", free_query(0), &ms);
    (void)answer("/api/optimise", held_query(0), &ms);
    (void)answer("/api/pareto", pareto_query(0), &ms);
    for (int k = 0; k < count; ++k) {
      free_bytes = answer("/api/optimise", free_query(k), &ms).size();
      free_ms.push_back(ms);
      held_bytes = answer("/api/optimise", held_query(k), &ms).size();
      held_ms.push_back(ms);
      const std::string body = answer("/api/pareto", pareto_query(k), &ms);
      pareto_bytes = body.size();
      pareto_ms.push_back(ms);
      if (k == 0) front = static_cast<std::size_t>(std::count(body.begin(), body.end(), '{'));
    }
    Print("optimise, free", free_ms, free_bytes);
    Print("optimise, held", held_ms, held_bytes);
    Print("pareto", pareto_ms, pareto_bytes);
    std::printf("first pareto answer: %zu JSON objects (front points and dominated samples)\n", front);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_viewer_queries: %s\n", e.what());
    return 2;
  }
  return 0;
}
