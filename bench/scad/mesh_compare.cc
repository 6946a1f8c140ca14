// bench_mesh_compare — the enclosed volume of closed meshes and the surface
// distance between two, for the coverage of OpenSCAD's corpus
// (bench/scad/corpus.py, docs/openscad.md).
//
//   bench_mesh_compare A.stl [B.stl] [--samples N] [--seed S]
//
// Prints one JSON object:
//   {"meshes": [{"path", "triangles", "volume" (mm^3, enclosed_volume.h about
//                the box centre), "area" (mm^2), "size" ([dx, dy, dz] mm of
//                the bounding box)}, ...],
//    "samples": N, "seed": S,
//    "distance": {"a_to_b": {"p50", "p95", "max"}, "b_to_a": {...}}}   (two meshes)
// where a_to_b are the distances (mm) from N points drawn on A's surface,
// uniformly by area (a triangle with probability area / total area, then a
// point uniform in it), to the nearest point of B's triangles: the exact
// point-to-triangle distance, through a CGAL AABB tree of B's triangles.
// Percentiles are nearest-rank over the N distances (p95: the
// ceil(0.95 N)-th smallest). The points come from a 64-bit Mersenne twister
// seeded with S (A's stream with S, B's with S + 1), turned into doubles
// with 53 bits, so the figures do not depend on the standard library.
// Triangles of zero area carry no points and are left out of the tree.
// Single-threaded. Meshes are read by fabatlas_mesh's ReadMesh (STL, OBJ,
// OFF, PLY); a bad file is one line on stderr and exit status 2.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/read_mesh.h"

namespace {

using fabatlas::mesh::TriangleMesh;
using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

std::vector<Triangle> TrianglesOf(const TriangleMesh& m) {
  std::vector<Triangle> out;
  out.reserve(m.triangles.size());
  for (const auto& t : m.triangles) {
    const auto& a = m.vertices[t[0]];
    const auto& b = m.vertices[t[1]];
    const auto& c = m.vertices[t[2]];
    Triangle tri(Point(a[0], a[1], a[2]), Point(b[0], b[1], b[2]), Point(c[0], c[1], c[2]));
    if (tri.squared_area() > 0) out.push_back(tri);
  }
  return out;
}

// A double uniform in [0, 1) from the generator's top 53 bits.
double Unit(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }

// `n` points on `tris`, uniform by area.
std::vector<Point> SurfacePoints(const std::vector<Triangle>& tris, int n, std::uint64_t seed) {
  std::vector<double> cumulative(tris.size());
  double total = 0;
  for (std::size_t i = 0; i < tris.size(); ++i) cumulative[i] = total += std::sqrt(tris[i].squared_area());
  std::mt19937_64 rng(seed);
  std::vector<Point> out;
  out.reserve(n);
  for (int k = 0; k < n; ++k) {
    const double r = Unit(rng) * total;
    std::size_t i = std::upper_bound(cumulative.begin(), cumulative.end(), r) - cumulative.begin();
    i = std::min(i, tris.size() - 1);
    // Uniform in the triangle: a + s (b - a) + t (c - a) with the square-root map.
    const double s1 = std::sqrt(Unit(rng)), r2 = Unit(rng);
    const Point& a = tris[i].vertex(0);
    const Point& b = tris[i].vertex(1);
    const Point& c = tris[i].vertex(2);
    const double wa = 1 - s1, wb = s1 * (1 - r2), wc = s1 * r2;
    out.emplace_back(wa * a.x() + wb * b.x() + wc * c.x(), wa * a.y() + wb * b.y() + wc * c.y(),
                     wa * a.z() + wb * b.z() + wc * c.z());
  }
  return out;
}

// Nearest-rank percentiles and the maximum of the distances from `points` to `to`.
nlohmann::json Distances(const std::vector<Point>& points, const std::vector<Triangle>& to) {
  Tree tree(to.begin(), to.end());
  tree.accelerate_distance_queries();
  std::vector<double> d;
  d.reserve(points.size());
  for (const Point& p : points) d.push_back(std::sqrt(tree.squared_distance(p)));
  std::sort(d.begin(), d.end());
  auto rank = [&](double q) { return d[std::max<std::size_t>(1, std::ceil(q * d.size())) - 1]; };
  return {{"p50", rank(0.5)}, {"p95", rank(0.95)}, {"max", d.back()}};
}

int Main(int argc, char** argv) {
  std::vector<std::string> paths;
  int samples = 20000;
  std::uint64_t seed = 1;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if ((arg == "--samples" || arg == "--seed") && i + 1 < argc) {
      const std::string value = argv[++i];
      try {
        if (arg == "--samples")
          samples = std::stoi(value);
        else
          seed = std::stoull(value);
      } catch (const std::exception&) {
        throw fabatlas::InputError(arg + " " + value + ": not a whole number");
      }
      if (samples < 1) throw fabatlas::InputError("--samples must be at least 1");
    } else if (!arg.empty() && arg[0] == '-') {
      throw fabatlas::InputError("unknown option " + arg +
                                 " (bench_mesh_compare A.stl [B.stl] [--samples N] [--seed S])");
    } else {
      paths.push_back(arg);
    }
  }
  if (paths.empty() || paths.size() > 2)
    throw fabatlas::InputError("bench_mesh_compare A.stl [B.stl] [--samples N] [--seed S]: one or two meshes");

  nlohmann::json out{{"samples", samples}, {"seed", seed}, {"meshes", nlohmann::json::array()}};
  std::vector<std::vector<Triangle>> tris;
  for (const auto& path : paths) {
    const TriangleMesh m = fabatlas::mesh::ReadMesh(path);
    std::array<double, 3> lo{HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (const auto& v : m.vertices)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
    const std::array<double, 3> centre{(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2};
    tris.push_back(TrianglesOf(m));
    double area = 0;
    for (const auto& t : tris.back()) area += std::sqrt(t.squared_area());
    out["meshes"].push_back({{"path", path},
                             {"triangles", m.triangles.size()},
                             {"volume", fabatlas::mesh::EnclosedVolume(m, centre)},
                             {"area", area},
                             {"size", {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]}}});
    if (tris.back().empty()) throw fabatlas::InputError(path + ": every triangle has zero area");
  }
  if (tris.size() == 2) {
    const auto pa = SurfacePoints(tris[0], samples, seed);
    const auto pb = SurfacePoints(tris[1], samples, seed + 1);
    out["distance"] = {{"a_to_b", Distances(pa, tris[1])}, {"b_to_a", Distances(pb, tris[0])}};
  }
  std::cout << out.dump(1) << "\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const fabatlas::InputError& e) {
    std::cerr << "bench_mesh_compare: " << e.what() << "\n";
    return fabatlas::kExitBadInput;
  }
}
