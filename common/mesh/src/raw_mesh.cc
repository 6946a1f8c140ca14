// A triangle mesh as plain bytes (see raw_mesh.h).
#include "fabatlas/mesh/raw_mesh.h"

#include <cstring>

#include "fabatlas/error.h"

namespace fabatlas::mesh {

static_assert(sizeof(double) == 8 && sizeof(std::int32_t) == 4);

std::string RawMeshBytes(const TriangleMesh& mesh) {
  std::string bytes;
  bytes.resize(24 * mesh.vertices.size() + 12 * mesh.triangles.size());
  if (!mesh.vertices.empty()) std::memcpy(bytes.data(), mesh.vertices.data(), 24 * mesh.vertices.size());
  if (!mesh.triangles.empty())
    std::memcpy(bytes.data() + 24 * mesh.vertices.size(), mesh.triangles.data(), 12 * mesh.triangles.size());
  return bytes;
}

TriangleMesh MeshOfRawBytes(std::string_view bytes, std::size_t triangles) {
  if (bytes.size() < 12 * triangles || (bytes.size() - 12 * triangles) % 24 != 0)
    throw InputError("raw mesh: " + std::to_string(bytes.size()) + " bytes do not hold " + std::to_string(triangles) +
                     " triangles and whole vertices");
  TriangleMesh m;
  m.vertices.resize((bytes.size() - 12 * triangles) / 24);
  m.triangles.resize(triangles);
  if (!m.vertices.empty()) std::memcpy(m.vertices.data(), bytes.data(), 24 * m.vertices.size());
  if (triangles > 0) std::memcpy(m.triangles.data(), bytes.data() + 24 * m.vertices.size(), 12 * triangles);
  for (const auto& t : m.triangles)
    for (std::int32_t i : t)
      if (i < 0 || static_cast<std::size_t>(i) >= m.vertices.size())
        throw InputError("raw mesh: triangle index " + std::to_string(i) + " out of range (" +
                         std::to_string(m.vertices.size()) + " vertices)");
  return m;
}

}  // namespace fabatlas::mesh
