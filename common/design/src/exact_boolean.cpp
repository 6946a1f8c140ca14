#include "exact_boolean.h"

#include <map>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include "operations.h"

namespace fabatlas::design {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

SurfaceMesh ToSurfaceMesh(const mesh::TriangleMesh& m, std::size_t index) {
  std::vector<Kernel::Point_3> points;
  for (const auto& v : m.vertices) points.emplace_back(v[0], v[1], v[2]);
  std::vector<std::vector<std::size_t>> faces;
  for (const auto& t : m.triangles) faces.push_back({std::size_t(t[0]), std::size_t(t[1]), std::size_t(t[2])});
  SurfaceMesh out;
  if (!PMP::is_polygon_soup_a_polygon_mesh(faces))
    throw SampleFailure("no_geometry", "exact boolean operand " + std::to_string(index) + " is not a manifold mesh");
  PMP::polygon_soup_to_polygon_mesh(points, faces, out);
  if (!CGAL::is_closed(out))
    throw SampleFailure("no_geometry", "exact boolean operand " + std::to_string(index) + " is not closed");
  if (PMP::does_self_intersect(out))
    throw SampleFailure("no_geometry", "exact boolean operand " + std::to_string(index) + " intersects itself");
  return out;
}

mesh::TriangleMesh FromSurfaceMesh(const SurfaceMesh& m) {
  mesh::TriangleMesh out;
  std::map<SurfaceMesh::Vertex_index, std::int32_t> index;
  for (auto v : m.vertices()) {
    index[v] = static_cast<std::int32_t>(out.vertices.size());
    const auto& p = m.point(v);
    out.vertices.push_back({p.x(), p.y(), p.z()});
  }
  for (auto f : m.faces()) {
    std::array<std::int32_t, 3> tri{};
    int i = 0;
    for (auto v : CGAL::vertices_around_face(m.halfedge(f), m)) {
      if (i < 3) tri[i] = index[v];
      ++i;
    }
    if (i == 3) out.triangles.push_back(tri);
  }
  return out;
}

}  // namespace

mesh::TriangleMesh ExactMeshBoolean(const std::string& op, const std::vector<mesh::TriangleMesh>& operands) {
  SurfaceMesh acc = ToSurfaceMesh(operands.at(0), 0);
  for (std::size_t i = 1; i < operands.size(); ++i) {
    SurfaceMesh other = ToSurfaceMesh(operands[i], i);
    SurfaceMesh result;
    bool ok = false;
    try {
      ok = op == "union"        ? PMP::corefine_and_compute_union(acc, other, result)
           : op == "difference" ? PMP::corefine_and_compute_difference(acc, other, result)
                                : PMP::corefine_and_compute_intersection(acc, other, result);
    } catch (const std::exception& e) {  // CGAL's own checks (degenerate or inconsistent input)
      throw SampleFailure("no_geometry", "exact " + op + " with operand " + std::to_string(i) + " failed: " + e.what());
    }
    if (!ok) throw SampleFailure("no_geometry", "exact " + op + " with operand " + std::to_string(i) + " has no manifold result");
    acc = std::move(result);
  }
  return FromSurfaceMesh(acc);
}

namespace {

// The closed shells of a mesh: triangles connected through shared vertices.
std::vector<mesh::TriangleMesh> Shells(const mesh::TriangleMesh& m) {
  std::vector<std::int32_t> parent(m.vertices.size());
  for (std::size_t i = 0; i < parent.size(); ++i) parent[i] = static_cast<std::int32_t>(i);
  auto find = [&](std::int32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : m.triangles) {
    parent[find(t[1])] = find(t[0]);
    parent[find(t[2])] = find(t[0]);
  }
  std::map<std::int32_t, mesh::TriangleMesh> shells;
  std::map<std::pair<std::int32_t, std::int32_t>, std::int32_t> local;  // (shell, vertex) -> index
  for (const auto& t : m.triangles) {
    std::int32_t root = find(t[0]);
    mesh::TriangleMesh& shell = shells[root];
    std::array<std::int32_t, 3> tri{};
    for (int k = 0; k < 3; ++k) {
      auto [it, added] = local.try_emplace({root, t[k]}, static_cast<std::int32_t>(shell.vertices.size()));
      if (added) shell.vertices.push_back(m.vertices[t[k]]);
      tri[k] = it->second;
    }
    shell.triangles.push_back(tri);
  }
  std::vector<mesh::TriangleMesh> out;
  for (auto& [_, shell] : shells) out.push_back(std::move(shell));
  return out;
}

double SignedVolume(const mesh::TriangleMesh& m) {
  double v = 0;
  for (const auto& t : m.triangles) {
    const auto &a = m.vertices[t[0]], &b = m.vertices[t[1]], &c = m.vertices[t[2]];
    v += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6;
  }
  return v;
}

}  // namespace

geometry::Solid ExactBoolean(const std::string& op, const std::vector<geometry::Solid>& children,
                             const geometry::GridSpec& grid) {
  std::vector<mesh::TriangleMesh> meshes;
  for (const auto& c : children) meshes.push_back(c.ToMesh());
  return SolidOfExactResult(ExactMeshBoolean(op, meshes), grid);
}

geometry::Solid SolidOfExactResult(const mesh::TriangleMesh& result, const geometry::GridSpec& grid) {
  if (result.triangles.empty()) return geometry::Solid();
  // OpenVDB signs a mesh's level set by flood fill from outside, so a cavity
  // (an inward-facing inner shell, as a difference leaves) would be filled.
  // Convert shell by shell instead: outward shells are material, inward
  // shells are cavities subtracted from it. (An island inside a cavity is not
  // represented; no operation of ours creates one from closed operands.)
  geometry::Solid material, cavities;
  for (const mesh::TriangleMesh& shell : Shells(result)) {
    geometry::Solid s = geometry::FromMesh(grid, shell);
    if (SignedVolume(shell) >= 0) material = material.empty() ? s : geometry::Union(material, s);
    else cavities = cavities.empty() ? s : geometry::Union(cavities, s);
  }
  return cavities.empty() ? material : geometry::Difference(material, cavities);
}

}  // namespace fabatlas::design
