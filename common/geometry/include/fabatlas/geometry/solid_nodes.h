// fabatlas/geometry/solid_nodes.h — a solid's level-set tree as bytes, node
// by node, and back: the transport encoding of solids between processes of
// one job (protocol/solid_blob.h), not a file format (files keep
// Solid::Serialize(), OpenVDB's own stream).
//
// Why: OpenVDB's stream writes and reads every tile slot of every internal
// node, 32,768 per top-level node, whatever the solid holds; a small solid
// straddling the origin has 8 such nodes, so its stream costs ~0.65 ms each
// way for a few kilobytes of level set. This encoding lists only what differs
// from a fresh node: each node's children and its tiles whose value is not the
// background or that are active, and each leaf's value mask with its values
// (active values only when every inactive value is +-background, as in a
// narrow band; else all 512). Encoding still reads each internal node's
// table once (a word-wise scan); decoding allocates each node once.
//
// Layout (little-endian; docs/protocol.md "Geometry blobs"): an 8-byte magic,
// the GridSpec (voxel size, half width, max active voxels), then for a
// non-empty grid the background, the root's tiles and children, and each
// node depth-first in offset order, so equal solids give equal bytes.
//
// Exactness: SolidOfNodeBytes(SolidNodeBytes(s)) has the same tree, node for
// node (every tile and voxel value bit for bit, active states, background),
// the same transform, grid class and spec, so its Serialize() bytes equal
// s.Serialize().
//
// Threading: both functions are single-threaded and reentrant.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace fabatlas::geometry {

class Solid;

// The node bytes of `solid`; std::nullopt when it cannot be encoded exactly
// this way (a grid with a transform other than its spec's canonical one or
// with metadata beyond its name and class; no solid built by this library
// has either), and for a mesh solid (MeshSolid: its exact mesh is the solid,
// its level set only a view of it): callers then use Solid::Serialize().
std::optional<std::string> SolidNodeBytes(const Solid& solid);

// True when `bytes` start with the node encoding's magic number.
bool IsSolidNodeBytes(std::string_view bytes);

// The solid encoded in `bytes` (SolidNodeBytes' output). Throws InputError
// with one line saying what is wrong on truncated or inconsistent bytes.
Solid SolidOfNodeBytes(std::string_view bytes);

}  // namespace fabatlas::geometry
