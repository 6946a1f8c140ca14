// Vertex normals split at creases (see crease_normals.h).
#include "fabatlas/mesh/crease_normals.h"

#include <cmath>
#include <cstdint>
#include <numbers>

namespace fabatlas::mesh {

CreasedMesh CreaseNormals(const TriangleMesh& m, double crease_degrees) {
  using V = std::array<double, 3>;
  const double cos_crease = std::cos(crease_degrees * std::numbers::pi / 180);
  std::vector<V> face(m.triangles.size());  // area-weighted normals (twice the area)
  for (std::size_t f = 0; f < m.triangles.size(); ++f) {
    const V& a = m.vertices[m.triangles[f][0]];
    const V& b = m.vertices[m.triangles[f][1]];
    const V& c = m.vertices[m.triangles[f][2]];
    const V u{b[0] - a[0], b[1] - a[1], b[2] - a[2]}, w{c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    face[f] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  }
  auto length = [](const V& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
  // Faces around each vertex, in triangle order (CSR).
  std::vector<std::uint32_t> start(m.vertices.size() + 1, 0);
  for (const auto& t : m.triangles)
    for (std::int32_t v : t) ++start[v + 1];
  for (std::size_t i = 0; i < m.vertices.size(); ++i) start[i + 1] += start[i];
  std::vector<std::uint32_t> around(start.back()), fill(start.begin(), start.end() - 1);
  for (std::size_t f = 0; f < m.triangles.size(); ++f)
    for (std::int32_t v : m.triangles[f]) around[fill[v]++] = static_cast<std::uint32_t>(f);

  CreasedMesh out;
  out.mesh.triangles = m.triangles;
  for (std::size_t v = 0; v < m.vertices.size(); ++v) {
    std::vector<std::uint32_t> seeds;  // a group's first face
    std::vector<V> sums;
    std::vector<std::int32_t> ids;
    for (std::uint32_t k = start[v]; k < start[v + 1]; ++k) {
      const std::uint32_t f = around[k];
      const double lf = length(face[f]);
      std::size_t g = 0;
      for (; g < seeds.size() && lf > 0; ++g) {
        const V& s = face[seeds[g]];
        const double ls = length(s);
        if (ls == 0 || (s[0] * face[f][0] + s[1] * face[f][1] + s[2] * face[f][2]) >= cos_crease * ls * lf) break;
      }
      if (lf == 0 && !seeds.empty()) g = 0;
      if (g == seeds.size()) {
        seeds.push_back(f);
        sums.push_back({0, 0, 0});
        ids.push_back(static_cast<std::int32_t>(out.mesh.vertices.size()));
        out.mesh.vertices.push_back(m.vertices[v]);
      }
      for (int i = 0; i < 3; ++i) sums[g][i] += face[f][i];
      for (int i = 0; i < 3; ++i)
        if (m.triangles[f][i] == static_cast<std::int32_t>(v)) out.mesh.triangles[f][i] = ids[g];
    }
    for (const V& s : sums) {
      const double l = length(s);
      out.normals.push_back(l > 0 ? std::array<float, 3>{float(s[0] / l), float(s[1] / l), float(s[2] / l)}
                                  : std::array<float, 3>{0, 0, 1});
    }
  }
  return out;
}

}  // namespace fabatlas::mesh
