// Cache plans on real dependency graphs: samples a design with the local
// sampler (as `fabatlas sample` does), re-evaluates every valid sample without
// a subtree cache to record each subtree's key, children, root time and bytes
// (design::SampleResult::subtrees), then plans: no cache, H_TOP, H_rfree and
// NAIVE / OPT-AVE / OPT-MAX under a budget, plus the exact optimum (GLPK).
//
//   bench_cache_real_designs [--subdivisions 3] [--max-depth 1] [--max-samples 80]
//       [--threads 2] [--min-seconds 0.1] [--budget-fraction 0.5] [--costs measured|model]
//       [--records FILE.tsv] [--graphs DIR] DESIGN.yaml...
//   bench_cache_real_designs [options] --from DIR/NAME.graph...   (re-plan a saved graph)
//
// --graphs writes each design's graph as DIR/NAME.graph (lines "N key seconds
// bytes op child,child,..." and "S rootkey") so plans can be rerun without
// sampling again.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include "fabatlas/cache/cost_model.h"
#include "fabatlas/cache/dependency_graph.h"
#include "fabatlas/cache/exact_cache.h"
#include "fabatlas/cache/optimize_cache.h"
#include "fabatlas/cache/starting_points.h"
#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/precompute/design_evaluator.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "synthetic_graphs.h"

using namespace fabatlas;

namespace {
std::string Mb(std::uint64_t b) {
  char s[32];
  std::snprintf(s, sizeof s, "%.1f MB", static_cast<double>(b) / 1e6);
  return s;
}
}  // namespace

int main(int argc, char** argv) {
  int subdivisions = 3, max_depth = 1, threads = 2;
  long max_samples = 80;
  double min_seconds = 0.1, budget_fraction = 0.5;
  std::string costs = "measured", records_path, graphs_dir;
  std::vector<std::string> designs, saved;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--subdivisions")
      subdivisions = std::stoi(next());
    else if (a == "--max-depth")
      max_depth = std::stoi(next());
    else if (a == "--max-samples")
      max_samples = std::stol(next());
    else if (a == "--threads")
      threads = std::stoi(next());
    else if (a == "--min-seconds")
      min_seconds = std::stod(next());
    else if (a == "--budget-fraction")
      budget_fraction = std::stod(next());
    else if (a == "--costs")
      costs = next();
    else if (a == "--records")
      records_path = next();
    else if (a == "--graphs")
      graphs_dir = next();
    else if (a == "--from")
      saved.push_back(next());
    else
      designs.push_back(a);
  }
  std::ofstream records;
  if (!records_path.empty()) {
    records.open(records_path);
    records << "design\top\toutput_bytes\tinput_bytes\tseconds\n";
  }
  auto plan_and_print = [&](const std::string& name, const std::vector<cache::SubtreeNode>& nodes,
                            const std::vector<cache::SampleTree>& samples) {
    cache::DependencyGraph g = cache::BuildDependencyGraph(nodes, samples);
    cache::CacheOptions o;
    o.min_seconds = min_seconds;
    o.record_curve = false;
    cache::CacheReport report = cache::PlanCache(g, o);
    std::printf("   %s: %lld samples, %lld subtrees\n", name.c_str(), static_cast<long long>(g.sample_count()),
                static_cast<long long>(g.node_count()));
    std::printf(
        "   H_TOP %s (%lld)  H_rfree %s (%lld)  ratio %.2f\n", Mb(report.top.bytes).c_str(),
        static_cast<long long>(report.top.entries), Mb(report.rfree.bytes).c_str(),
        static_cast<long long>(report.rfree.entries),
        report.rfree.bytes ? static_cast<double>(report.top.bytes) / static_cast<double>(report.rfree.bytes) : 0.0);
    std::printf("   predicted preview mean/worst: none %.3f/%.3f s  rfree %.3f/%.3f s\n", report.none.mean_seconds,
                report.none.worst_seconds, report.rfree.mean_seconds, report.rfree.worst_seconds);
    o.budget_bytes = static_cast<std::uint64_t>(budget_fraction * static_cast<double>(report.rfree.bytes));
    std::printf("   budget %s (%.0f%% of H_rfree):\n", Mb(o.budget_bytes).c_str(), budget_fraction * 100);
    for (cache::Strategy s : {cache::Strategy::kNaive, cache::Strategy::kOptAve, cache::Strategy::kOptMax}) {
      o.strategy = s;
      cache::CachePlan p = cache::OptimizeCache(g, o);
      std::printf("     %-8s %s (%lld)  mean %.3f s  worst %.3f s\n", cache::StrategyName(s), Mb(p.cost.bytes).c_str(),
                  static_cast<long long>(p.cost.entries), p.cost.mean_seconds, p.cost.worst_seconds);
    }
    // Equal budgets from 10 % to 100 % of H_rfree: OPT-MAX against OPT-AVE.
    int worse = 0, better = 0;
    double worst_mean_ratio = 0;
    for (int k = 1; k <= 10; ++k) {
      cache::CacheOptions q = o;
      q.budget_bytes = static_cast<std::uint64_t>(0.1 * k * static_cast<double>(report.rfree.bytes));
      q.strategy = cache::Strategy::kOptAve;
      cache::CacheCost ave = cache::OptimizeCache(g, q).cost;
      q.strategy = cache::Strategy::kOptMax;
      cache::CacheCost max = cache::OptimizeCache(g, q).cost;
      if (max.worst_seconds > ave.worst_seconds + 1e-12) ++worse;
      if (max.worst_seconds < ave.worst_seconds - 1e-12) ++better;
      if (ave.mean_seconds > 0) worst_mean_ratio = std::max(worst_mean_ratio, max.mean_seconds / ave.mean_seconds);
    }
    std::printf(
        "   budgets 10..100%% of H_rfree: OPT-MAX worst lower in %d, higher in %d of 10; mean at most %.3fx "
        "OPT-AVE's\n",
        better, worse, worst_mean_ratio);
    cache::ExactCacheOptions eo;
    eo.budget_bytes = o.budget_bytes;
    eo.min_seconds = min_seconds;
    eo.time_limit_seconds = 30;
    o.strategy = cache::Strategy::kOptMax;
    eo.start = cache::OptimizeCache(g, o).cache;
    cache::ExactCacheSummary ex = cache::SolveExactCache(g, eo);
    if (ex.solved)
      std::printf("     exact    %s (%lld)  mean %.3f s  worst %.3f s  (%s, %lld variables)\n",
                  Mb(ex.cost.bytes).c_str(), static_cast<long long>(ex.cost.entries), ex.cost.mean_seconds,
                  ex.cost.worst_seconds, ex.optimal ? "optimal" : "not proven optimal",
                  static_cast<long long>(ex.variables));
    else
      std::printf("     exact    not solved: %s\n", ex.message.c_str());
  };
  for (const std::string& path : saved) {
    auto read = cache::testing::ReadGraphFile(path);
    if (costs == "model") {
      std::map<std::string, std::uint64_t> bytes_of;
      for (const auto& n : read.nodes) bytes_of[n.key] = n.bytes;
      for (std::size_t i = 0; i < read.nodes.size(); ++i) {
        std::uint64_t input = 0;
        for (const auto& c : read.nodes[i].children) input += bytes_of[c];
        read.nodes[i].seconds = cache::ModelSubtreeSeconds(read.ops[i], read.nodes[i].bytes, input);
      }
    }
    std::printf("== %s\n", path.c_str());
    plan_and_print(path, read.nodes, read.samples);
  }
  for (const std::string& path : designs) {
    design::Design d = design::LoadDesign(path);
    sampling::DesignSpace space = precompute::DesignSpaceOf(d, subdivisions);
    precompute::DesignSampleEvaluator evaluator(d);
    sampling::ThreadPoolExecutor executor(threads);
    sampling::SamplingOptions so;
    so.max_depth = max_depth;
    so.max_samples = max_samples;
    auto t0 = std::chrono::steady_clock::now();
    sampling::SamplingSummary summary = sampling::SampleDesignSpace(space, evaluator, executor, so);
    double sample_wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::vector<std::int64_t> valid;
    for (std::size_t i = 0; i < summary.form.samples.size(); ++i)
      if (summary.form.samples[i].outcome.valid) valid.push_back(static_cast<std::int64_t>(i));
    // Re-evaluate the valid samples with no subtree cache: every record timed.
    std::vector<design::SampleResult> results(valid.size());
    std::atomic<std::size_t> at{0};
    std::vector<std::thread> pool;
    for (int t = 0; t < threads; ++t)
      pool.emplace_back([&] {
        for (std::size_t i; (i = at++) < valid.size();) {
          design::EvaluateOptions eo;
          eo.keep_solid = false;
          results[i] = design::EvaluateSample(
              d, precompute::DesignPointOf(d, summary.form.samples[static_cast<std::size_t>(valid[i])].u), eo);
        }
      });
    for (auto& t : pool) t.join();
    std::vector<cache::SubtreeNode> nodes;
    std::vector<cache::SampleTree> samples;
    for (const auto& r : results) {
      if (r.subtrees.empty()) continue;
      std::map<std::string, std::uint64_t> bytes_of;
      for (const auto& s : r.subtrees) bytes_of[s.key] = s.bytes;
      for (const auto& s : r.subtrees) {
        std::uint64_t input = 0;
        for (const auto& c : s.children) input += bytes_of[c];
        double seconds = costs == "model" ? cache::ModelSubtreeSeconds(s.op, s.bytes, input) : s.seconds;
        nodes.push_back({s.key, s.children, seconds, s.bytes, true});
        if (records.is_open())
          records << d.name << "\t" << s.op << "\t" << s.bytes << "\t" << input << "\t" << s.seconds << "\n";
      }
      samples.push_back({r.subtrees.back().key});
    }
    if (!graphs_dir.empty()) {
      std::ofstream out(graphs_dir + "/" + d.name + ".graph");
      out.precision(17);
      for (const auto& r : results)
        for (const auto& st : r.subtrees) {
          out << "N " << st.key << " " << st.seconds << " " << st.bytes << " " << st.op << " ";
          for (std::size_t c = 0; c < st.children.size(); ++c) out << (c ? "," : "") << st.children[c];
          out << (st.children.empty() ? "-" : "") << "\n";
        }
      for (const auto& smp : samples) out << "S " << smp.root << "\n";
    }
    std::printf("== %s: %zu samples (%zu valid), sampling %.1f s\n", d.name.c_str(), summary.form.samples.size(),
                valid.size(), sample_wall);
    plan_and_print(d.name, nodes, samples);
    auto starts = cache::ChooseStartingPoints(summary.form);
    std::printf("   starting points: %zu\n", starts.size());
    std::fflush(stdout);
  }
  return 0;
}
