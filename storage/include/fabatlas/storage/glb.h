// fabatlas/storage/glb.h — triangle meshes as glTF 2.0 binary (GLB), the mesh
// format of the artifact's cache entries (docs/artifact.md), written and read
// with tinygltf so standard tools (Blender, three.js, gltf-validator) open it.
#pragma once

#include <string>
#include <string_view>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::storage {

// One scene, one node, one mesh with one triangle primitive: POSITION as
// float32 VEC3 in millimetres (with min/max bounds, as glTF requires) and
// uint32 indices. No normals, materials or extras. Deterministic: the same
// mesh gives the same bytes. An empty mesh gives a scene without a mesh.
std::string MeshToGlb(const mesh::TriangleMesh& mesh);

// Reads a GLB written by MeshToGlb (or any GLB whose first mesh primitive is
// float positions with uint8/16/32 indices). Throws InputError naming
// `source` when the bytes are not such a GLB.
mesh::TriangleMesh GlbToMesh(std::string_view glb, const std::string& source = "glb");

}  // namespace fabatlas::storage
