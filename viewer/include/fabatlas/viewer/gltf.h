// fabatlas/viewer/gltf.h — a triangle mesh as glTF 2.0 binary (.glb), the
// preview format the customiser loads (three.js GLTFLoader).
#pragma once

#include <string>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::viewer {

// One scene, one node, one mesh with a single triangle primitive: POSITION
// (float32, millimetres, with the min/max the spec requires) and uint32
// indices. Written with tinygltf. An empty mesh gives a valid file with an
// empty scene. Returns the .glb bytes.
std::string MeshToGlb(const mesh::TriangleMesh& mesh);

}  // namespace fabatlas::viewer
