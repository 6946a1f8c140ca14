// bench_geometry — cost of the level-set kernel at ~64 and ~128 voxels across
// the object (argument = voxels across a 20 mm object): each primitive, a CSG
// union of two spheres, DeltaG of two overlapping spheres, ToMesh.
#include <benchmark/benchmark.h>

#include "fabatlas/geometry/solid.h"
#include "fabatlas/geometry/solid_nodes.h"

namespace fg = fabatlas::geometry;

namespace {

constexpr double kSize = 20.0;  // mm across every benchmarked object

fg::GridSpec Spec(const benchmark::State& st) {
  fg::GridSpec g;
  g.voxel_size = kSize / static_cast<double>(st.range(0));
  return g;
}

void BM_Sphere(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Sphere(g, kSize / 2));
}
void BM_Box(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Box(g, {kSize, kSize * 0.8, kSize * 0.6}));
}
void BM_Cylinder(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Cylinder(g, kSize / 2, kSize));
}
void BM_Cone(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Cone(g, kSize / 2, kSize / 4, kSize));
}
void BM_Torus(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Torus(g, kSize * 0.35, kSize * 0.15));
}
void BM_Capsule(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Capsule(g, {-5, -5, -5}, {5, 5, 5}, 4));
}
void BM_Extrude(benchmark::State& st) {
  const auto g = Spec(st);
  const std::vector<fg::Vec2> l = {{-10, -10}, {10, -10}, {10, 0}, {0, 0}, {0, 10}, {-10, 10}};
  for (auto _ : st) benchmark::DoNotOptimize(fg::Extrude(g, l, kSize));
}
const std::vector<fg::Vec2> kVaseProfile = {{0, 0}, {8, 0}, {10, 8}, {6, 16}, {7, 20}, {0, 20}};
void BM_RevolveSmooth(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Revolve(g, kVaseProfile, 0));
}
void BM_Revolve7Sides(benchmark::State& st) {
  const auto g = Spec(st);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Revolve(g, kVaseProfile, 7));
}
void BM_UnionTwoSpheres(benchmark::State& st) {
  const auto g = Spec(st);
  const fg::Solid a = fg::Sphere(g, kSize / 2);
  const fg::Solid b = fg::Translate(fg::Sphere(g, kSize / 2), {kSize / 4, 0, 0});
  for (auto _ : st) benchmark::DoNotOptimize(fg::Union(a, b));
}
void BM_DeltaG(benchmark::State& st) {
  const auto g = Spec(st);
  const fg::Solid a = fg::Sphere(g, kSize / 2);
  const fg::Solid b = fg::Translate(fg::Sphere(g, kSize / 2), {kSize / 4, 0, 0});
  for (auto _ : st) benchmark::DoNotOptimize(fg::DeltaG(a, b));
}
void BM_Volume(benchmark::State& st) {
  const fg::Solid a = fg::Sphere(Spec(st), kSize / 2);
  for (auto _ : st) benchmark::DoNotOptimize(a.Volume());
}
void BM_ToMesh(benchmark::State& st) {
  const fg::Solid a = fg::Sphere(Spec(st), kSize / 2);
  for (auto _ : st) benchmark::DoNotOptimize(a.ToMesh());
}
void BM_Rotate(benchmark::State& st) {
  const fg::Solid a = fg::Box(Spec(st), {kSize, kSize * 0.8, kSize * 0.6});
  for (auto _ : st) benchmark::DoNotOptimize(fg::Rotate(a, {10, 20, 30}));
}
void BM_Offset(benchmark::State& st) {
  const fg::Solid a = fg::Sphere(Spec(st), kSize / 2);
  for (auto _ : st) benchmark::DoNotOptimize(fg::Offset(a, 1.0));
}
void BM_Serialize(benchmark::State& st) {
  const fg::Solid a = fg::Sphere(Spec(st), kSize / 2);
  for (auto _ : st) benchmark::DoNotOptimize(a.Serialize());
}

// The tube of bench/scale/tube_coarse.yaml at its defaults on its 2 mm voxel
// (radius 15, wall 6, height 20 mm, centred on the origin: 8 top-level
// nodes), a root solid a worker of the Scale jobs ships: OpenVDB's stream
// against the node encoding (geometry/solid_nodes.h), each way; counter
// "bytes" is the encoding's size before zstd.
fg::Solid Tube() {
  fg::GridSpec g;
  g.voxel_size = 2.0;
  return fg::Difference(fg::Cylinder(g, 15, 20), fg::Cylinder(g, 9, 22));
}
void BM_TubeSerialize(benchmark::State& st) {
  const fg::Solid a = Tube();
  for (auto _ : st) benchmark::DoNotOptimize(a.Serialize());
  st.counters["bytes"] = static_cast<double>(a.Serialize().size());
}
void BM_TubeDeserialize(benchmark::State& st) {
  const std::string bytes = Tube().Serialize();
  for (auto _ : st) benchmark::DoNotOptimize(fg::Solid::Deserialize(bytes));
}
void BM_TubeNodeBytes(benchmark::State& st) {
  const fg::Solid a = Tube();
  for (auto _ : st) benchmark::DoNotOptimize(fg::SolidNodeBytes(a));
  st.counters["bytes"] = static_cast<double>(fg::SolidNodeBytes(a)->size());
}
void BM_TubeOfNodeBytes(benchmark::State& st) {
  const std::string bytes = *fg::SolidNodeBytes(Tube());
  for (auto _ : st) benchmark::DoNotOptimize(fg::SolidOfNodeBytes(bytes));
}

}  // namespace

#define FABATLAS_GEOMETRY_BENCH(fn) BENCHMARK(fn)->Arg(64)->Arg(128)->Unit(benchmark::kMillisecond)->UseRealTime()
FABATLAS_GEOMETRY_BENCH(BM_Sphere);
FABATLAS_GEOMETRY_BENCH(BM_Box);
FABATLAS_GEOMETRY_BENCH(BM_Cylinder);
FABATLAS_GEOMETRY_BENCH(BM_Cone);
FABATLAS_GEOMETRY_BENCH(BM_Torus);
FABATLAS_GEOMETRY_BENCH(BM_Capsule);
FABATLAS_GEOMETRY_BENCH(BM_Extrude);
FABATLAS_GEOMETRY_BENCH(BM_RevolveSmooth);
FABATLAS_GEOMETRY_BENCH(BM_Revolve7Sides);
FABATLAS_GEOMETRY_BENCH(BM_UnionTwoSpheres);
FABATLAS_GEOMETRY_BENCH(BM_DeltaG);
FABATLAS_GEOMETRY_BENCH(BM_Volume);
FABATLAS_GEOMETRY_BENCH(BM_ToMesh);
FABATLAS_GEOMETRY_BENCH(BM_Rotate);
FABATLAS_GEOMETRY_BENCH(BM_Offset);
FABATLAS_GEOMETRY_BENCH(BM_Serialize);
BENCHMARK(BM_TubeSerialize)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TubeDeserialize)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TubeNodeBytes)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TubeOfNodeBytes)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
