// solid_nodes.cc — a solid's level-set tree as bytes, node by node (see
// solid_nodes.h).
#include "fabatlas/geometry/solid_nodes.h"

#include <bit>
#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "solid_impl.h"

namespace fabatlas::geometry {

namespace {

static_assert(std::endian::native == std::endian::little, "the node encoding is written little-endian");

using openvdb::Coord;
using openvdb::FloatGrid;
using openvdb::FloatTree;
using Root = FloatTree::RootNodeType;
using Upper = Root::ChildNodeType;   // 32^3 slots, 4096 voxels a side
using Lower = Upper::ChildNodeType;  // 16^3 slots, 128 voxels a side
using Leaf = Lower::ChildNodeType;   // 8^3 voxels

constexpr char kMagic[8] = {'F', 'A', 'S', 'N', 'O', 'D', 'E', '1'};
constexpr std::uint8_t kLeafBand = 0;  // inactive values all +-background: sign mask, active values
constexpr std::uint8_t kLeafFull = 1;  // all 512 values
constexpr std::uint32_t kSignBit = 0x80000000u;

std::uint32_t Bits(float v) { return std::bit_cast<std::uint32_t>(v); }

class Writer {
 public:
  template <typename T>
  void Put(const T& v) {
    const auto* p = reinterpret_cast<const char*>(&v);
    out_.append(p, sizeof(T));
  }
  void PutBytes(const void* p, std::size_t n) { out_.append(static_cast<const char*>(p), n); }
  std::string Take() { return std::move(out_); }

 private:
  std::string out_;
};

void WriteLeaf(Writer& w, const Leaf& leaf, std::uint32_t bg) {
  const auto& mask = leaf.getValueMask();
  const float* values = leaf.buffer().data();
  std::uint64_t words[Leaf::NUM_VALUES / 64];
  std::uint64_t inside[Leaf::NUM_VALUES / 64] = {};
  bool band = true;
  for (openvdb::Index i = 0; i < Leaf::NUM_VALUES / 64; ++i) words[i] = mask.getWord<std::uint64_t>(i);
  for (openvdb::Index n = 0; n < Leaf::NUM_VALUES && band; ++n) {
    if (words[n >> 6] >> (n & 63) & 1) continue;
    const std::uint32_t b = Bits(values[n]);
    if (b == (bg ^ kSignBit))
      inside[n >> 6] |= std::uint64_t{1} << (n & 63);
    else if (b != bg)
      band = false;
  }
  w.Put(band ? kLeafBand : kLeafFull);
  w.PutBytes(words, sizeof words);
  if (!band) {
    w.PutBytes(values, Leaf::NUM_VALUES * sizeof(float));
    return;
  }
  w.PutBytes(inside, sizeof inside);
  for (openvdb::Index n = 0; n < Leaf::NUM_VALUES; ++n)
    if (words[n >> 6] >> (n & 63) & 1) w.Put(values[n]);
}

// An internal node: its children's offsets, its tiles that are not inactive
// background, then each child. The table is scanned a 64-slot word at a time
// (child, value mask and "value differs from the background" bits).
template <typename Node>
void WriteInternal(Writer& w, const Node& node, std::uint32_t bg) {
  const auto* table = node.getTable();
  std::vector<std::uint16_t> children, tiles;
  for (openvdb::Index word = 0; word < Node::NUM_VALUES / 64; ++word) {
    const std::uint64_t child = node.getChildMask().template getWord<std::uint64_t>(word);
    const std::uint64_t on = node.getValueMask().template getWord<std::uint64_t>(word);
    std::uint64_t differs = 0;
    for (int j = 0; j < 64; ++j) {
      std::uint32_t b;  // the value's bytes of the slot (a union with the child pointer)
      std::memcpy(&b, &table[word * 64 + j], sizeof b);
      differs |= std::uint64_t{b != bg} << j;
    }
    for (std::uint64_t m = child; m; m &= m - 1)
      children.push_back(static_cast<std::uint16_t>(word * 64 + std::countr_zero(m)));
    for (std::uint64_t m = (differs | on) & ~child; m; m &= m - 1)
      tiles.push_back(static_cast<std::uint16_t>(word * 64 + std::countr_zero(m)));
  }
  w.Put(static_cast<std::uint32_t>(children.size()));
  w.PutBytes(children.data(), children.size() * sizeof(std::uint16_t));
  w.Put(static_cast<std::uint32_t>(tiles.size()));
  for (std::uint16_t n : tiles) {
    w.Put(n);
    w.Put(table[n].getValue());
    w.Put(static_cast<std::uint8_t>(node.isValueMaskOn(n)));
  }
  for (std::uint16_t n : children) {
    if constexpr (std::is_same_v<Node, Lower>)
      WriteLeaf(w, *table[n].getChild(), bg);
    else
      WriteInternal(w, *table[n].getChild(), bg);
  }
}

class Reader {
 public:
  explicit Reader(std::string_view bytes) : bytes_(bytes) {}
  template <typename T>
  T Get() {
    T v;
    std::memcpy(&v, Take(sizeof(T)), sizeof(T));
    return v;
  }
  const char* Take(std::size_t n) {
    if (n > bytes_.size() - pos_) Fail("truncated");
    const char* p = bytes_.data() + pos_;
    pos_ += n;
    return p;
  }
  std::size_t left() const { return bytes_.size() - pos_; }
  [[noreturn]] void Fail(const char* what) const {
    throw InputError(std::string("solid node bytes: ") + what + " at byte " + std::to_string(pos_) + " of " +
                     std::to_string(bytes_.size()));
  }

 private:
  std::string_view bytes_;
  std::size_t pos_ = 0;
};

std::unique_ptr<Leaf> ReadLeaf(Reader& r, const Coord& origin, float background) {
  const auto kind = r.Get<std::uint8_t>();
  if (kind != kLeafBand && kind != kLeafFull) r.Fail("unknown leaf kind");
  auto leaf = std::make_unique<Leaf>(origin, background, false);
  std::uint64_t words[Leaf::NUM_VALUES / 64];
  std::memcpy(words, r.Take(sizeof words), sizeof words);
  for (openvdb::Index i = 0; i < Leaf::NUM_VALUES / 64; ++i) leaf->getValueMask().getWord<std::uint64_t>(i) = words[i];
  float* values = leaf->buffer().data();
  if (kind == kLeafFull) {
    std::memcpy(values, r.Take(Leaf::NUM_VALUES * sizeof(float)), Leaf::NUM_VALUES * sizeof(float));
    return leaf;
  }
  std::uint64_t inside[Leaf::NUM_VALUES / 64];
  std::memcpy(inside, r.Take(sizeof inside), sizeof inside);
  for (openvdb::Index n = 0; n < Leaf::NUM_VALUES; ++n) {
    if (words[n >> 6] >> (n & 63) & 1)
      values[n] = r.Get<float>();
    else if (inside[n >> 6] >> (n & 63) & 1)
      values[n] = -background;
  }
  return leaf;
}

template <typename Node>
std::unique_ptr<Node> ReadInternal(Reader& r, const Coord& origin, float background) {
  auto node = std::make_unique<Node>(origin, background, false);
  const auto n_children = r.Get<std::uint32_t>();
  if (n_children > Node::NUM_VALUES) r.Fail("more children than a node has slots");
  std::vector<std::uint16_t> children(n_children);
  std::memcpy(children.data(), r.Take(n_children * sizeof(std::uint16_t)), n_children * sizeof(std::uint16_t));
  for (std::size_t i = 0; i < children.size(); ++i)
    if (children[i] >= Node::NUM_VALUES || (i > 0 && children[i] <= children[i - 1]))
      r.Fail("child offsets out of range or out of order");
  const auto n_tiles = r.Get<std::uint32_t>();
  if (n_tiles > Node::NUM_VALUES) r.Fail("more tiles than a node has slots");
  int last = -1;
  for (std::uint32_t i = 0; i < n_tiles; ++i) {
    const auto n = r.Get<std::uint16_t>();
    const auto value = r.Get<float>();
    const auto active = r.Get<std::uint8_t>();
    if (n >= Node::NUM_VALUES || static_cast<int>(n) <= last || active > 1) r.Fail("tile out of range or out of order");
    last = n;
    node->addTile(n, value, active == 1);
  }
  for (std::uint16_t n : children) {
    if (!node->isValueMaskOff(n) || node->getTable()[n].getValue() != background)
      r.Fail("a child where a tile was given");
    const Coord child_origin = node->offsetToGlobalCoord(n);
    if constexpr (std::is_same_v<Node, Lower>) {
      auto leaf = ReadLeaf(r, child_origin, background);
      node->addLeaf(leaf.release());
    } else {
      auto child = ReadInternal<typename Node::ChildNodeType>(r, child_origin, background);
      node->addChild(child.release());
    }
  }
  return node;
}

Coord ReadCoord(Reader& r) {
  const auto x = r.Get<std::int32_t>(), y = r.Get<std::int32_t>(), z = r.Get<std::int32_t>();
  return Coord(x, y, z);
}

void PutCoord(Writer& w, const Coord& c) {
  w.Put(static_cast<std::int32_t>(c.x()));
  w.Put(static_cast<std::int32_t>(c.y()));
  w.Put(static_cast<std::int32_t>(c.z()));
}

bool AlignedToUpper(const Coord& c) {
  constexpr std::int32_t mask = Upper::DIM - 1;
  return (c.x() & mask) == 0 && (c.y() & mask) == 0 && (c.z() & mask) == 0;
}

}  // namespace

bool IsSolidNodeBytes(std::string_view bytes) {
  return bytes.size() >= sizeof kMagic && std::memcmp(bytes.data(), kMagic, sizeof kMagic) == 0;
}

std::optional<std::string> SolidNodeBytes(const Solid& solid) {
  if (solid.boundary()) return std::nullopt;  // a mesh solid: Solid::Serialize keeps its exact mesh
  Writer w;
  w.PutBytes(kMagic, sizeof kMagic);
  const Solid::Impl* impl = solid.impl();
  if (!impl) {  // the empty Solid: voxel size 0, as Serialize() marks it
    const GridSpec spec;
    w.Put(0.0);
    w.Put(spec.half_width_voxels);
    w.Put(static_cast<std::uint64_t>(spec.max_active_voxels));
    return w.Take();
  }
  const FloatGrid& grid = *impl->Grid();
  if (grid.metaCount() != 2 || grid.getName() != "solid" || grid.getGridClass() != openvdb::GRID_LEVEL_SET ||
      grid.saveFloatAsHalf() || !(grid.transform() == *internal::CanonicalTransform(impl->spec.voxel_size)))
    return std::nullopt;
  w.Put(impl->spec.voxel_size);
  w.Put(impl->spec.half_width_voxels);
  w.Put(static_cast<std::uint64_t>(impl->spec.max_active_voxels));
  const Root& root = grid.tree().root();
  const float background = root.background();
  const std::uint32_t bg = Bits(background);
  w.Put(background);
  std::uint32_t root_tiles = 0;
  for (auto it = root.cbeginValueAll(); it; ++it) ++root_tiles;
  w.Put(root_tiles);
  for (auto it = root.cbeginValueAll(); it; ++it) {
    PutCoord(w, it.getCoord());
    w.Put(*it);
    w.Put(static_cast<std::uint8_t>(it.isValueOn()));
  }
  w.Put(static_cast<std::uint32_t>(root.childCount()));
  for (auto it = root.cbeginChildOn(); it; ++it) {
    PutCoord(w, it.getCoord());
    WriteInternal(w, *it, bg);
  }
  return w.Take();
}

Solid SolidOfNodeBytes(std::string_view bytes) {
  internal::EnsureOpenVdbInitialized();
  if (!IsSolidNodeBytes(bytes)) throw InputError("solid node bytes: no node-encoding magic number");
  Reader r(bytes);
  r.Take(sizeof kMagic);
  GridSpec spec;
  spec.voxel_size = r.Get<double>();
  spec.half_width_voxels = r.Get<double>();
  spec.max_active_voxels = static_cast<std::size_t>(r.Get<std::uint64_t>());
  if (spec.voxel_size == 0) {
    if (r.left() != 0) r.Fail("bytes after the empty solid");
    return Solid();
  }
  internal::ValidateSpec(spec, "solid node bytes");
  const auto background = r.Get<float>();
  if (!(background > 0)) r.Fail("background is not a positive distance");
  FloatGrid::Ptr grid = FloatGrid::create(background);
  grid->setTransform(internal::CanonicalTransform(spec.voxel_size));
  Root& root = grid->tree().root();
  const auto n_tiles = r.Get<std::uint32_t>();
  if (n_tiles > r.left() / 17) r.Fail("more root tiles than bytes");
  for (std::uint32_t i = 0; i < n_tiles; ++i) {
    const Coord c = ReadCoord(r);
    const auto value = r.Get<float>();
    const auto active = r.Get<std::uint8_t>();
    if (!AlignedToUpper(c) || active > 1) r.Fail("root tile off the root's grid");
    if (root.getValueDepth(c) != -1) r.Fail("two root entries at one place");
    root.addTile(c, value, active == 1);
  }
  const auto n_children = r.Get<std::uint32_t>();
  if (n_children > r.left() / 20) r.Fail("more root children than bytes");
  for (std::uint32_t i = 0; i < n_children; ++i) {
    const Coord c = ReadCoord(r);
    if (!AlignedToUpper(c)) r.Fail("root child off the root's grid");
    if (root.getValueDepth(c) != -1) r.Fail("two root entries at one place");
    auto child = ReadInternal<Upper>(r, c, background);
    root.addChild(child.release());
  }
  if (r.left() != 0) r.Fail("bytes after the tree");
  return internal::MakeSolid(grid, spec);
}

}  // namespace fabatlas::geometry
