// narrow_band.h — building level sets for the operations (internal):
// empty grids, rebuilds through a mesh of the zero level set, and narrow
// bands assembled leaf by leaf. Shared by operations.cc and transforms.cc.
#pragma once

#include <openvdb/tools/SignedFloodFill.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <memory>
#include <vector>

#include "solid_impl.h"

namespace fabatlas::geometry::internal {

// An empty level set on spec's canonical transform (background: the band
// half width, mm).
openvdb::FloatGrid::Ptr EmptyGrid(const GridSpec& spec);
// An empty solid on s's grid spec.
Solid EmptyLike(const Solid& s);
// The active voxels of s's level set.
double ActiveVoxels(const Solid& s);
// Rebuild the zero level set of `src` (whose transform may be any affine map)
// as a narrow band on the canonical transform of `spec` (OpenVDB's
// levelSetRebuild: through a mesh of the zero level set).
Solid Rebuild(const openvdb::FloatGrid& src, const GridSpec& spec);

// Builds a narrow-band level set leaf by leaf, in parallel over leaves (TBB):
// `fill(i, emit)` visits the candidate voxels of the leaf at origins[i] and
// calls emit(pos, v, candidate). A voxel becomes active with value v when it
// is a candidate and |v| is inside the band half width `bg` (world units);
// every other visited voxel is stored inactive at +bg or -bg by the sign of
// v. Leaves with no active voxel are dropped; the result is sign-flooded.
// `fill` runs concurrently for different i and must be thread-safe.
template <class Fill>
Solid AssembleNarrowBand(const GridSpec& spec, double bg, const std::vector<openvdb::Coord>& origins, Fill fill) {
  std::vector<openvdb::FloatTree::LeafNodeType*> out_leaves(origins.size(), nullptr);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, origins.size()), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) {
      auto leaf = std::make_unique<openvdb::FloatTree::LeafNodeType>(origins[i], static_cast<float>(bg), false);
      bool any = false;
      fill(i, [&](openvdb::Index pos, double v, bool candidate) {
        if (candidate && std::abs(v) < bg) {
          leaf->setValueOn(pos, static_cast<float>(v));
          any = true;
        } else {
          leaf->setValueOff(pos, static_cast<float>(v > 0 ? bg : -bg));
        }
      });
      if (any) out_leaves[i] = leaf.release();
    }
  });
  openvdb::FloatGrid::Ptr out = EmptyGrid(spec);
  for (openvdb::FloatTree::LeafNodeType* leaf : out_leaves)
    if (leaf) out->tree().addLeaf(leaf);
  openvdb::tools::signedFloodFill(out->tree());
  return MakeSolid(out, spec);
}

}  // namespace fabatlas::geometry::internal
