// The node encoding of solids (geometry/solid_nodes.h): every decoded tree
// equals its original node for node and bit for bit, and gives the same
// Solid::Serialize() bytes (OpenVDB's own stream, the artifact's format);
// bad bytes are an InputError, never a crash.
#include "fabatlas/geometry/solid_nodes.h"

#include <gtest/gtest.h>

#include <bit>
#include <random>
#include <vector>

#include "fabatlas/error.h"
#include "fabatlas/geometry/solid.h"
#include "solid_impl.h"

namespace fg = fabatlas::geometry;
using fabatlas::InputError;

namespace {

using openvdb::FloatGrid;
using Root = openvdb::FloatTree::RootNodeType;
using Upper = Root::ChildNodeType;
using Lower = Upper::ChildNodeType;
using Leaf = Lower::ChildNodeType;

fg::GridSpec Spec(double vs) {
  fg::GridSpec g;
  g.voxel_size = vs;
  return g;
}

// The tube of bench/scale/tube_coarse.yaml at its default parameters (radius
// 15, wall 6, height 20 mm) on its 2 mm voxel: centred on the origin, so its
// level set spans the 8 top-level nodes around it.
fg::Solid Tube() {
  const fg::GridSpec g = Spec(2.0);
  return fg::Difference(fg::Cylinder(g, 15, 20), fg::Cylinder(g, 9, 22));
}

template <typename Node>
void ExpectSameInternalNodes(const openvdb::FloatTree& a, const openvdb::FloatTree& b) {
  std::vector<const Node*> na, nb;
  a.getNodes(na);
  b.getNodes(nb);
  ASSERT_EQ(na.size(), nb.size());
  for (std::size_t i = 0; i < na.size(); ++i) {
    ASSERT_EQ(na[i]->origin(), nb[i]->origin());
    ASSERT_TRUE(na[i]->getChildMask() == nb[i]->getChildMask());
    ASSERT_TRUE(na[i]->getValueMask() == nb[i]->getValueMask());
    for (openvdb::Index n = 0; n < Node::NUM_VALUES; ++n) {
      if (na[i]->isChildMaskOn(n)) continue;
      ASSERT_EQ(std::bit_cast<std::uint32_t>(na[i]->getTable()[n].getValue()),
                std::bit_cast<std::uint32_t>(nb[i]->getTable()[n].getValue()))
          << "tile " << n << " of node at " << na[i]->origin();
    }
  }
}

// Both trees, node for node: the root's tiles and children, every internal
// node's masks and tile values, every leaf's mask and 512 values (bitwise);
// then the transform, class, background and Serialize() bytes.
void ExpectSameSolid(const fg::Solid& a, const fg::Solid& b) {
  EXPECT_EQ(a.Serialize(), b.Serialize());
  ASSERT_EQ(a.impl() == nullptr, b.impl() == nullptr);
  if (!a.impl()) return;
  const FloatGrid& ga = *a.impl()->Grid();
  const FloatGrid& gb = *b.impl()->Grid();
  EXPECT_TRUE(ga.transform() == gb.transform());
  EXPECT_EQ(ga.getGridClass(), gb.getGridClass());
  EXPECT_EQ(std::bit_cast<std::uint32_t>(ga.background()), std::bit_cast<std::uint32_t>(gb.background()));
  EXPECT_EQ(a.impl()->spec.voxel_size, b.impl()->spec.voxel_size);
  EXPECT_EQ(a.impl()->spec.half_width_voxels, b.impl()->spec.half_width_voxels);
  EXPECT_EQ(a.impl()->spec.max_active_voxels, b.impl()->spec.max_active_voxels);
  const Root& ra = ga.tree().root();
  const Root& rb = gb.tree().root();
  ASSERT_EQ(ra.getTableSize(), rb.getTableSize());
  for (auto ia = ra.cbeginValueAll(), ib = rb.cbeginValueAll(); ia; ++ia, ++ib) {
    ASSERT_TRUE(ib);
    EXPECT_EQ(ia.getCoord(), ib.getCoord());
    EXPECT_EQ(std::bit_cast<std::uint32_t>(*ia), std::bit_cast<std::uint32_t>(*ib));
    EXPECT_EQ(ia.isValueOn(), ib.isValueOn());
  }
  int tiles_a = 0, tiles_b = 0;
  for (auto it = ra.cbeginValueAll(); it; ++it) ++tiles_a;
  for (auto it = rb.cbeginValueAll(); it; ++it) ++tiles_b;
  EXPECT_EQ(tiles_a, tiles_b);
  ExpectSameInternalNodes<Upper>(ga.tree(), gb.tree());
  ExpectSameInternalNodes<Lower>(ga.tree(), gb.tree());
  std::vector<const Leaf*> la, lb;
  ga.tree().getNodes(la);
  gb.tree().getNodes(lb);
  ASSERT_EQ(la.size(), lb.size());
  for (std::size_t i = 0; i < la.size(); ++i) {
    ASSERT_EQ(la[i]->origin(), lb[i]->origin());
    ASSERT_TRUE(la[i]->getValueMask() == lb[i]->getValueMask());
    for (openvdb::Index n = 0; n < Leaf::NUM_VALUES; ++n)
      ASSERT_EQ(std::bit_cast<std::uint32_t>(la[i]->getValue(n)), std::bit_cast<std::uint32_t>(lb[i]->getValue(n)));
  }
}

fg::Solid RoundTrip(const fg::Solid& s) {
  const auto bytes = fg::SolidNodeBytes(s);
  EXPECT_TRUE(bytes.has_value());
  EXPECT_TRUE(fg::IsSolidNodeBytes(*bytes));
  EXPECT_EQ(*bytes, *fg::SolidNodeBytes(s));  // deterministic
  return fg::SolidOfNodeBytes(*bytes);
}

}  // namespace

TEST(GeometrySolidNodes, TubeAcrossTheOriginRoundTripsExactly) {
  const fg::Solid tube = Tube();
  ASSERT_EQ(tube.impl()->Grid()->tree().root().childCount(), 8u);  // straddles the origin
  ExpectSameSolid(tube, RoundTrip(tube));
  // Smaller than OpenVDB's stream of the same tree.
  EXPECT_LT(fg::SolidNodeBytes(tube)->size(), tube.Serialize().size());
}

TEST(GeometrySolidNodes, EmptySolidsRoundTrip) {
  ExpectSameSolid(fg::Solid(), RoundTrip(fg::Solid()));
  EXPECT_TRUE(RoundTrip(fg::Solid()).empty());
  // A grid with no interior (one sphere minus a larger one), not the default Solid.
  const fg::GridSpec g = Spec(0.1);
  const fg::Solid none = fg::Difference(fg::Sphere(g, 1.0), fg::Sphere(g, 2.0));
  ASSERT_NE(none.impl(), nullptr);
  ExpectSameSolid(none, RoundTrip(none));
}

TEST(GeometrySolidNodes, SolidsWithInsideTilesRoundTripExactly) {
  // Away from the origin, inside tiles of 8^3 voxels in the lower nodes.
  const fg::Solid box = fg::Translate(fg::Box(Spec(0.25), {20, 16, 12}), {40, 30, 20});
  ExpectSameSolid(box, RoundTrip(box));
  // A box of 264 voxels a side round the origin holds whole 128^3 blocks: inside
  // tiles in the top-level nodes.
  const fg::Solid big = fg::Box(Spec(1.0), {264, 264, 264});
  std::vector<const Upper*> upper;
  big.impl()->Grid()->tree().getNodes(upper);
  bool upper_inside_tile = false;
  for (const Upper* node : upper)
    for (auto it = node->cbeginValueOff(); it; ++it) upper_inside_tile |= *it < 0;
  ASSERT_TRUE(upper_inside_tile);
  ExpectSameSolid(big, RoundTrip(big));
}

TEST(GeometrySolidNodes, LeavesAndTilesOfAnyValueRoundTripExactly) {
  // Inactive voxel values other than +-background (a full leaf), an active
  // tile and a non-background inactive tile in a lower node, a root tile:
  // none comes from this library's operations today, all must survive.
  const fg::Solid tube = Tube();
  FloatGrid::Ptr grid = tube.impl()->Grid()->deepCopy();
  std::vector<Leaf*> leaves;
  grid->tree().getNodes(leaves);
  ASSERT_FALSE(leaves.empty());
  for (openvdb::Index n = 0; n < Leaf::NUM_VALUES; ++n)
    if (!leaves[0]->isValueOn(n)) {
      leaves[0]->setValueOnly(n, 0.125f);
      break;
    }
  std::vector<Lower*> lower;
  grid->tree().getNodes(lower);
  ASSERT_FALSE(lower.empty());
  for (openvdb::Index n = 0, tiles = 0; n < Lower::NUM_VALUES && tiles < 2; ++n)
    if (!lower[0]->isChildMaskOn(n)) {
      const bool first = tiles++ == 0;  // the first tile active at 1.5, the second inactive at -0
      lower[0]->addTile(n, first ? 1.5f : -0.0f, first);
    }
  grid->tree().root().addTile(openvdb::Coord(40960, 0, -4096), -3.0f, true);
  const fg::Solid odd = fg::internal::MakeSolid(grid, tube.impl()->spec);
  ExpectSameSolid(odd, RoundTrip(odd));
}

TEST(GeometrySolidNodes, GridsItCannotEncodeExactlyAreDeclined) {
  const fg::Solid tube = Tube();
  FloatGrid::Ptr moved = tube.impl()->Grid()->deepCopy();
  moved->transform().postTranslate(openvdb::Vec3d(0.5, 0, 0));
  EXPECT_FALSE(fg::SolidNodeBytes(fg::internal::MakeSolid(moved, tube.impl()->spec)).has_value());
  FloatGrid::Ptr tagged = tube.impl()->Grid()->deepCopy();
  tagged->insertMeta("note", openvdb::StringMetadata("x"));
  EXPECT_FALSE(fg::SolidNodeBytes(fg::internal::MakeSolid(tagged, tube.impl()->spec)).has_value());
}

TEST(GeometrySolidNodes, TruncatedOrCorruptBytesAreInputErrors) {
  const std::string bytes = *fg::SolidNodeBytes(Tube());
  EXPECT_THROW(fg::SolidOfNodeBytes(""), InputError);
  EXPECT_THROW(fg::SolidOfNodeBytes("not nodes"), InputError);
  for (std::size_t n = 0; n < bytes.size(); n += 1 + n / 16)
    EXPECT_THROW(fg::SolidOfNodeBytes(bytes.substr(0, n)), InputError) << n;
  EXPECT_THROW(fg::SolidOfNodeBytes(bytes + "x"), InputError);
  // Flipped bits: either an InputError naming the byte or some other
  // well-formed tree (a flipped value bit is still a value), never a crash.
  std::mt19937 random(13);
  int errors = 0;
  for (int i = 0; i < 2000; ++i) {
    std::string flipped = bytes;
    const std::size_t at = 8 + random() % (bytes.size() - 8);
    flipped[at] = static_cast<char>(flipped[at] ^ (1 << (random() % 8)));
    try {
      fg::SolidOfNodeBytes(flipped);
    } catch (const InputError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("solid node bytes:"), std::string::npos) << e.what();
    }
  }
  EXPECT_GT(errors, 0);
}
