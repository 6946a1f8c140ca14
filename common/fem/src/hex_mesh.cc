#include "fabatlas/fem/hex_mesh.h"

#include <algorithm>
#include <string>
#include <utility>

#include "fabatlas/error.h"

namespace fabatlas::fem {

HexMesh HexMeshFromVoxels(const VoxelSolid& s) {
  if (!(s.voxel_size > 0)) {
    throw InputError("VoxelSolid: voxel_size must be > 0, got " + std::to_string(s.voxel_size));
  }
  for (int d = 0; d < 3; ++d) {
    if (s.dims[d] < 0) throw InputError("VoxelSolid: negative dimension");
  }
  const std::size_t nvox = static_cast<std::size_t>(s.dims[0]) * s.dims[1] * s.dims[2];
  if (s.occupied.size() != nvox) {
    throw InputError("VoxelSolid: occupied has " + std::to_string(s.occupied.size()) + " entries, dims give " +
                     std::to_string(nvox));
  }
  HexMesh mesh;
  const std::size_t lx = s.dims[0] + 1, ly = s.dims[1] + 1, lz = s.dims[2] + 1;
  std::vector<int> node_of_lattice(lx * ly * lz, -1);
  auto lattice = [&](std::size_t i, std::size_t j, std::size_t k) { return i + lx * (j + ly * k); };
  // Mark lattice points used by occupied voxels.
  for (int k = 0; k < s.dims[2]; ++k)
    for (int j = 0; j < s.dims[1]; ++j)
      for (int i = 0; i < s.dims[0]; ++i) {
        if (!s.occupied[s.Index(i, j, k)]) continue;
        for (int c = 0; c < 8; ++c) {
          node_of_lattice[lattice(i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1))] = 0;
        }
      }
  // Number them in lattice order.
  for (std::size_t k = 0; k < lz; ++k)
    for (std::size_t j = 0; j < ly; ++j)
      for (std::size_t i = 0; i < lx; ++i) {
        int& n = node_of_lattice[lattice(i, j, k)];
        if (n < 0) continue;
        n = static_cast<int>(mesh.nodes.size());
        mesh.nodes.push_back(
            {s.origin[0] + s.voxel_size * i, s.origin[1] + s.voxel_size * j, s.origin[2] + s.voxel_size * k});
      }
  // Corner offsets in the standard Q1 order.
  static constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                        {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (int k = 0; k < s.dims[2]; ++k)
    for (int j = 0; j < s.dims[1]; ++j)
      for (int i = 0; i < s.dims[0]; ++i) {
        if (!s.occupied[s.Index(i, j, k)]) continue;
        std::array<int, 8> e;
        for (int c = 0; c < 8; ++c) {
          e[c] = node_of_lattice[lattice(i + kCorner[c][0], j + kCorner[c][1], k + kCorner[c][2])];
        }
        mesh.elements.push_back(e);
      }
  return mesh;
}

HexMesh HexMeshFromQuadPatch(const std::array<Vec2, 4>& c, int nu, int nv, double thickness, int layers) {
  if (nu < 1 || nv < 1 || layers < 1 || !(thickness > 0)) {
    throw InputError("HexMeshFromQuadPatch: need nu, nv, layers >= 1 and thickness > 0");
  }
  HexMesh mesh;
  for (int k = 0; k <= layers; ++k)
    for (int j = 0; j <= nv; ++j)
      for (int i = 0; i <= nu; ++i) {
        const double s = static_cast<double>(i) / nu, t = static_cast<double>(j) / nv;
        const double w0 = (1 - s) * (1 - t), w1 = s * (1 - t), w2 = s * t, w3 = (1 - s) * t;
        mesh.nodes.push_back({w0 * c[0][0] + w1 * c[1][0] + w2 * c[2][0] + w3 * c[3][0],
                              w0 * c[0][1] + w1 * c[1][1] + w2 * c[2][1] + w3 * c[3][1], thickness * k / layers});
      }
  auto id = [&](int i, int j, int k) { return i + (nu + 1) * (j + (nv + 1) * k); };
  for (int k = 0; k < layers; ++k)
    for (int j = 0; j < nv; ++j)
      for (int i = 0; i < nu; ++i) {
        mesh.elements.push_back({id(i, j, k), id(i + 1, j, k), id(i + 1, j + 1, k), id(i, j + 1, k), id(i, j, k + 1),
                                 id(i + 1, j, k + 1), id(i + 1, j + 1, k + 1), id(i, j + 1, k + 1)});
      }
  return mesh;
}

std::vector<std::array<int, 4>> BoundaryFaces(const HexMesh& mesh) {
  // Local faces with outward normals (right-hand rule).
  static constexpr int kFace[6][4] = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4},
                                      {1, 2, 6, 5}, {2, 3, 7, 6}, {0, 4, 7, 3}};
  std::vector<std::pair<std::array<int, 4>, std::array<int, 4>>> keyed;
  keyed.reserve(mesh.elements.size() * 6);
  for (const auto& e : mesh.elements) {
    for (const auto& f : kFace) {
      std::array<int, 4> face{e[f[0]], e[f[1]], e[f[2]], e[f[3]]};
      std::array<int, 4> key = face;
      std::sort(key.begin(), key.end());
      keyed.emplace_back(key, face);
    }
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::array<int, 4>> out;
  for (std::size_t a = 0; a < keyed.size();) {
    std::size_t b = a + 1;
    while (b < keyed.size() && keyed[b].first == keyed[a].first) ++b;
    if (b - a == 1) out.push_back(keyed[a].second);
    a = b;
  }
  return out;
}

}  // namespace fabatlas::fem
