// bench_artifact_scale — results at scale: a 10^5-sample artifact, and what
// opening and querying it costs.
//
//   bench_artifact_scale write JOB OUT.fabatlas
//     Samples JOB's design adaptively (Fab Forms Sec. 5, SampleDesignSpace with
//     the job's sampling settings) with a closed-form evaluator of
//     configs/designs/tube_wall_3d.yaml (valid iff bore = radius - wall >= 2
//     and wall >= 1 + 0.01 radius^2 + 0.0005 height^2, "unsat_constraints"
//     otherwise; property volume = pi (radius^2 - bore^2) height; ΔG the
//     hollow cylinders' symmetric-difference ratio), and publishes it as the
//     cluster would (pipeline::ArtifactOf: manifest, form, starting points,
//     the job bundle with the real design). Prints samples, times, file size
//     and the size form.json would have (built in memory, not written).
//   bench_artifact_scale lookups ART [POINTS=10000] [SEED=1]
//     Loads ART as `fabatlas serve` does (viewer::LoadArtifact) and times, at
//     POINTS uniform random points, what /api/intervals computes (IsValid +
//     the stretches along every dimension). Prints the load time, the
//     process's peak resident memory (VmHWM) and p50 / p99 / max per lookup.
// Single-threaded.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>

#include "fabatlas/pipeline/artifact_of.h"
#include "fabatlas/protocol/job_bundle.h"
#include "fabatlas/sampling/adaptive_sampler.h"
#include "fabatlas/sampling/executor.h"
#include "fabatlas/sampling/form_json.h"
#include "fabatlas/sampling/job_file.h"
#include "fabatlas/artifact/artifact.h"
#include "fabatlas/viewer/customiser.h"

using namespace fabatlas;
using Clock = std::chrono::steady_clock;

namespace {

double Seconds(Clock::time_point since) { return std::chrono::duration<double>(Clock::now() - since).count(); }

std::string ProcStatus(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(field, 0) == 0) return line.substr(std::string(field).size() + 1);
  return "?";
}

// configs/designs/tube_wall_3d.yaml in closed form: u = (radius, wall, height).
class TubeWall3D final : public sampling::SampleEvaluator {
 public:
  static double Volume(const std::vector<double>& u) {
    const double bore = u[0] - u[1];
    return std::numbers::pi * (u[0] * u[0] - bore * bore) * u[2];
  }
  sampling::SampleOutcome EvaluateSample(const sampling::SamplePoint& p) override {
    const auto& u = p.u;
    sampling::SampleOutcome o;
    o.valid = u[0] - u[1] >= 2 && u[1] >= 1 + 0.01 * u[0] * u[0] + 0.0005 * u[2] * u[2];
    if (!o.valid)
      o.failure_type = "unsat_constraints";
    else
      o.properties["volume"] = Volume(u);
    return o;
  }
  double GeometryChange(const sampling::SamplePoint& a, const sampling::SamplePoint& b) override {
    // |A xor B| / |A or B| of two coaxial hollow cylinders standing on z = 0.
    const double va = Volume(a.u), vb = Volume(b.u);
    const double lo = std::max(a.u[0] - a.u[1], b.u[0] - b.u[1]), hi = std::min(a.u[0], b.u[0]);
    const double inter = hi > lo ? std::numbers::pi * (hi * hi - lo * lo) * std::min(a.u[2], b.u[2]) : 0.0;
    const double uni = va + vb - inter;
    return uni > 0 ? (uni - inter) / uni : 0.0;
  }
};

int Write(const std::string& job_path, const std::filesystem::path& out) {
  const sampling::JobFile job = sampling::ReadJobFile(job_path);
  const v1::JobBundle bundle = protocol::MakeJobBundle(job_path);
  const sampling::DesignSpace space({{"radius", sampling::DimensionKind::kReal, 5, 30, {}},
                                     {"wall", sampling::DimensionKind::kReal, 0.5, 12, {}},
                                     {"height", sampling::DimensionKind::kReal, 10, 60, {}}},
                                    job.subdivisions);
  TubeWall3D evaluator;
  sampling::ThreadPoolExecutor executor(1);
  auto start = Clock::now();
  const sampling::SamplingSummary summary = sampling::SampleDesignSpace(space, evaluator, executor, job.sampling);
  const double sample_s = Seconds(start);
  start = Clock::now();
  const artifact::Artifact artifact = pipeline::ArtifactOf(bundle, "tube_wall_3d", job, summary.form);
  const double assemble_s = Seconds(start);
  start = Clock::now();
  artifact::WriteArtifact(artifact, out);
  const double write_s = Seconds(start);
  std::printf("samples %zu (valid %lld), leaves %lld, ΔG values %zu\n", summary.form.samples.size(),
              static_cast<long long>(summary.statistics.valid_samples),
              static_cast<long long>(summary.statistics.leaves), summary.form.geometry_changes.size());
  std::printf("sampling %.2f s, artifact assembly (starting points) %.2f s, write %.2f s\n", sample_s, assemble_s,
              write_s);
  start = Clock::now();
  const std::size_t json_bytes = sampling::FormToJson(summary.form).size();
  std::printf("form.json would be %zu bytes (%.0f per sample), built in %.2f s\n", json_bytes,
              static_cast<double>(json_bytes) / static_cast<double>(summary.form.samples.size()), Seconds(start));
  std::printf("artifact %s: %ju bytes; peak resident %s\n", out.string().c_str(),
              static_cast<std::uintmax_t>(std::filesystem::file_size(out)), ProcStatus("VmHWM:").c_str());
  return 0;
}

int Lookups(const std::filesystem::path& art, int points, std::uint64_t seed) {
  auto start = Clock::now();
  viewer::Customiser c(viewer::LoadArtifact(art));
  const double load_s = Seconds(start);
  std::printf("loaded %zu samples in %.2f s; peak resident after load %s\n", c.form().samples.size(), load_s,
              ProcStatus("VmHWM:").c_str());
  std::printf(
      "leaf corner table: %zu leaves, %zu bytes (%.1f per leaf)\n", c.corners().leaves(), c.corners().bytes(),
      static_cast<double>(c.corners().bytes()) / static_cast<double>(std::max<std::size_t>(c.corners().leaves(), 1)));
  std::mt19937_64 rng(seed);
  std::vector<double> ms, cpu_ms;
  const auto thread_cpu_ms = [] {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
  };
  int valid = 0;
  std::size_t stretches = 0;
  for (int i = 0; i < points; ++i) {
    std::vector<double> u;
    for (const auto& d : c.form().dimensions) u.push_back(std::uniform_real_distribution<double>(d.lo, d.hi)(rng));
    const auto t0 = Clock::now();
    const double c0 = thread_cpu_ms();
    valid += c.IsValid(u);
    for (int d = 0; d < c.dimension_count(); ++d) stretches += c.Stretches(u, d).size();
    cpu_ms.push_back(thread_cpu_ms() - c0);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  const auto print = [&](const char* what, std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const auto at = [&](double q) { return v[std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5))]; };
    std::printf("lookups %s n=%d (valid %d, %zu stretches): p50 %.4f ms  p99 %.4f ms  max %.4f ms\n", what, points,
                valid, stretches, at(0.5), at(0.99), v.back());
  };
  print("wall", ms);
  print("thread CPU", cpu_ms);
  std::printf("peak resident %s\n", ProcStatus("VmHWM:").c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const std::string mode = argc > 1 ? argv[1] : "";
    if (mode == "write" && argc == 4) return Write(argv[2], argv[3]);
    if (mode == "lookups" && argc >= 3)
      return Lookups(argv[2], argc > 3 ? std::stoi(argv[3]) : 10000, argc > 4 ? std::stoull(argv[4]) : 1);
    std::fprintf(stderr, "usage: bench_artifact_scale write JOB OUT.fabatlas | lookups ART [POINTS] [SEED]\n");
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_artifact_scale: %s\n", e.what());
    return 2;
  }
}
