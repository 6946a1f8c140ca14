#include "exact_boolean.h"

#include <map>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/exact_boolean.h"
#include "operations.h"

namespace fabatlas::design {

mesh::TriangleMesh ExactMeshBoolean(const std::string& op, const std::vector<mesh::TriangleMesh>& operands) {
  const mesh::BooleanOp o = op == "union"        ? mesh::BooleanOp::kUnion
                            : op == "difference" ? mesh::BooleanOp::kDifference
                                                 : mesh::BooleanOp::kIntersection;
  try {
    return mesh::ExactBoolean(o, operands);
  } catch (const InputError& e) {  // bad geometry of this sample, not bad input
    throw SampleFailure("no_geometry", e.what());
  }
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
    if (mesh::EnclosedVolume(shell) >= 0)
      material = material.empty() ? s : geometry::Union(material, s);
    else
      cavities = cavities.empty() ? s : geometry::Union(cavities, s);
  }
  return cavities.empty() ? material : geometry::Difference(material, cavities);
}

}  // namespace fabatlas::design
