// Folds of an extracted surface (fabatlas/geometry/folded_triangles.h).
#include "fabatlas/geometry/folded_triangles.h"

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tree/ValueAccessor.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "solid_impl.h"

namespace fabatlas::geometry {
namespace {

using Accessor = openvdb::tree::ValueAccessor<const openvdb::FloatTree, /*IsSafe=*/false>;
using LeafT = openvdb::FloatTree::LeafNodeType;

// The eight voxel values of the cell with minimum corner o, v[i][j][l] at
// o + (i, j, l): read from o's leaf when the cell lies inside it (most
// cells), else leaf by leaf through the cache; the same values either way.
void CellValues(Accessor& acc, internal::LeafCache<Accessor>& leaves, const openvdb::Coord& o, double v[2][2][2]) {
  constexpr int kLast = static_cast<int>(LeafT::DIM) - 1;
  if ((o.x() & kLast) != kLast && (o.y() & kLast) != kLast && (o.z() & kLast) != kLast) {
    if (const LeafT* leaf = acc.probeConstLeaf(o)) {
      const float* data = leaf->buffer().data();
      const openvdb::Index n = LeafT::coordToOffset(o);
      constexpr openvdb::Index dx = 1u << (2 * LeafT::LOG2DIM), dy = 1u << LeafT::LOG2DIM;
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j)
          for (int l = 0; l < 2; ++l) v[i][j][l] = data[n + i * dx + j * dy + l];
      return;
    }
  }
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      for (int l = 0; l < 2; ++l) v[i][j][l] = leaves.Value(acc, o.offsetBy(i, j, l));
}

}  // namespace

FoldedTriangles FindFoldedTriangles(const Solid& s, const mesh::TriangleMesh& mesh) {
  FoldedTriangles out;
  if (!s.impl()) return out;
  const openvdb::FloatGrid& grid = *s.impl()->Grid();
  const openvdb::math::Transform& transform = grid.transform();
  const double vs = s.impl()->spec.voxel_size;
  const double iso = kMeshIso * vs;
  // The folded triangles of each chunk of kChunk triangles, chunks in
  // parallel (each reads the grid through its own accessor).
  struct Fold {
    double centroid[3];
    double area;
  };
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (mesh.triangles.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<Fold>> folds(chunks);
  tbb::parallel_for(std::size_t{0}, chunks, [&](std::size_t chunk) {
    Accessor acc(grid.tree());
    internal::LeafCache<Accessor> leaves;
    const std::size_t end = std::min(mesh.triangles.size(), (chunk + 1) * kChunk);
    for (std::size_t n = chunk * kChunk; n != end; ++n) {
      const auto& t = mesh.triangles[n];
      const auto& a = mesh.vertices[t[0]];
      const auto& b = mesh.vertices[t[1]];
      const auto& c = mesh.vertices[t[2]];
      double centroid[3], e1[3], e2[3];
      for (int k = 0; k < 3; ++k) {
        centroid[k] = (a[k] + b[k] + c[k]) / 3;
        e1[k] = b[k] - a[k];
        e2[k] = c[k] - a[k];
      }
      const double normal[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                                e1[0] * e2[1] - e1[1] * e2[0]};
      // The gradient of the trilinear interpolant of the voxel values in the
      // cell holding the centroid (the cell the surface was extracted from).
      double f[3];
      openvdb::Coord o;
      for (int k = 0; k < 3; ++k) {
        const double x = centroid[k] / vs;
        o[k] = static_cast<int>(std::floor(x));
        f[k] = x - o[k];
      }
      double v[2][2][2];
      CellValues(acc, leaves, o, v);
      const auto w = [&f](int k, int side) { return side ? f[k] : 1 - f[k]; };
      double g[3] = {0, 0, 0};
      for (int j = 0; j < 2; ++j)
        for (int l = 0; l < 2; ++l) {
          g[0] += w(1, j) * w(2, l) * (v[1][j][l] - v[0][j][l]);
          g[1] += w(0, j) * w(2, l) * (v[j][1][l] - v[j][0][l]);
          g[2] += w(0, j) * w(1, l) * (v[j][l][1] - v[j][l][0]);
        }
      if (normal[0] * g[0] + normal[1] * g[1] + normal[2] * g[2] >= 0) continue;
      // Facing inward: a fold when the material behind it ends within a voxel
      // (outside again one voxel inward along the gradient).
      const double length = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
      if (!(length > 0)) continue;
      const openvdb::Vec3d inward(centroid[0] - g[0] / length * vs, centroid[1] - g[1] / length * vs,
                                  centroid[2] - g[2] / length * vs);
      float value = 0;
      openvdb::tools::BoxSampler::sample(acc, transform.worldToIndex(inward), value);
      if (value <= iso) continue;
      folds[chunk].push_back({{centroid[0], centroid[1], centroid[2]},
                              0.5 * std::sqrt(normal[0] * normal[0] + normal[1] * normal[1] + normal[2] * normal[2])});
    }
  });
  // Count, area and first in mesh order: the same bits for any schedule.
  for (const auto& chunk : folds)
    for (const Fold& fold : chunk) {
      if (out.count == 0) out.first = {fold.centroid[0], fold.centroid[1], fold.centroid[2]};
      ++out.count;
      out.area += fold.area;
    }
  return out;
}

}  // namespace fabatlas::geometry
