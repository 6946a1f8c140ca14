// fabatlas/mesh/raw_mesh.h — a triangle mesh as plain bytes: the form in
// which a swept-volume cutter travels (tasks.proto SweptVolumeResult
// surface_sha256 / surface_blob) and is hashed.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

// Vertex coordinates as little-endian float64 (x, y, z per vertex), then
// triangle corner indices as little-endian int32: 24 V + 12 T bytes.
std::string RawMeshBytes(const TriangleMesh& mesh);

// The mesh of RawMeshBytes, given its triangle count (the bytes do not carry
// it). Throws InputError when the size is not 24 V + 12 T for a whole V or an
// index is out of range.
TriangleMesh MeshOfRawBytes(std::string_view bytes, std::size_t triangles);

}  // namespace fabatlas::mesh
