// InspectMesh and ShapeDiameter on the npm bunny (3,674 triangles) and on the
// largest FabHacks mesh, doublehookmedium.off (104,824 triangles). Counters
// report the results so a run also shows what was measured. CPU time is the
// whole process (ShapeDiameter traces on all TBB threads).
#include <benchmark/benchmark.h>

#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/mesh/shape_diameter.h"
#include "js_mesh.h"
#include "test_paths.h"

namespace fabatlas::mesh {
namespace {

const TriangleMesh& Bunny() {
  static const TriangleMesh m = testing::LoadJsMesh(testing::SourceDir() / "node_modules/bunny/index.js");
  return m;
}

const TriangleMesh& DoubleHook() {
  static const TriangleMesh m = ReadMesh(testing::SharedDir() / "data/fabhacks/meshes/doublehookmedium.off");
  return m;
}

void Inspect(benchmark::State& state, const TriangleMesh& (*mesh)()) {
  const TriangleMesh& m = mesh();
  MeshReport r;
  for (auto _ : state) {
    r = InspectMesh(m);  // opaque library call, result read after the loop
  }
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  state.counters["closed"] = r.closed;
  state.counters["manifold"] = r.manifold;
  state.counters["self_isect"] = r.self_intersecting;
  state.counters["volume_mm3"] = r.volume;
}

void Sdf(benchmark::State& state, const TriangleMesh& (*mesh)()) {
  const TriangleMesh& m = mesh();
  ShapeDiameterSummary s;
  for (auto _ : state) {
    s = ShapeDiameter(m, {});  // opaque library call, result read after the loop
  }
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  state.counters["rays_per_s"] =
      benchmark::Counter(static_cast<double>(m.triangles.size()) * 30, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["sdf_min"] = s.min;
  state.counters["sdf_p5"] = s.percentile_5;
  state.counters["sdf_median"] = s.median;
}

BENCHMARK_CAPTURE(Inspect, bunny, &Bunny)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK_CAPTURE(Inspect, doublehookmedium, &DoubleHook)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();
BENCHMARK_CAPTURE(Sdf, bunny, &Bunny)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();
BENCHMARK_CAPTURE(Sdf, doublehookmedium, &DoubleHook)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

}  // namespace
}  // namespace fabatlas::mesh

BENCHMARK_MAIN();
