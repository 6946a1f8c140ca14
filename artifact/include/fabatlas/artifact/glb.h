// fabatlas/artifact/glb.h — triangle meshes as glTF 2.0 binary (GLB), the mesh
// format of the artifact's cache entries (docs/artifact.md), written and read
// with tinygltf so standard tools (Blender, three.js, gltf-validator) open it.
#pragma once

#include <string>
#include <string_view>
#include <array>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::artifact {

// One scene, one node, one mesh with one triangle primitive: POSITION as
// float32 VEC3 in the design's millimetres, z up (with min/max bounds, as
// glTF requires) and uint32 indices; the node's scale (1/1000) and rotation
// (-90 degrees about x) place it in glTF's metres with +Y up, so viewers
// (Blender, three.js) show it at its true size and upright. With `normals`
// (one unit vector per vertex, e.g. mesh::CreaseNormals for an exact mesh:
// flat at creases) a NORMAL attribute, else none (viewers compute smooth
// ones). No materials or extras. Deterministic: the same mesh gives the same
// bytes. An empty mesh gives a scene without a mesh.
std::string MeshToGlb(const mesh::TriangleMesh& mesh, const std::vector<std::array<float, 3>>* normals = nullptr);

// A solid's preview mesh as GLB: an exact mesh (the mesh road) with normals
// split at creases of 30 degrees, a level-set surface without normals.
std::string SolidPreviewGlb(const mesh::TriangleMesh& surface, bool exact);

// One part of a multi-part GLB (a body or colour region of an OpenSCAD
// model, design::Part).
struct GlbPart {
  std::string name;
  const mesh::TriangleMesh* mesh = nullptr;
  bool coloured = false;         // false: no material (viewers use their default)
  std::array<double, 4> rgba{};  // sRGB red, green, blue, alpha in [0, 1] (OpenSCAD's color())
};

// The parts as one scene of one node per part (named after it, with
// MeshToGlb's scale and rotation) holding its own mesh of one primitive, normals as SolidPreviewGlb gives them
// (`exact`: split at 30-degree creases). A coloured part's primitive has a material named "part NAME" whose
// baseColorFactor is its colour converted from sRGB to linear (glTF 2.0 Sec. 3.9.2: baseColorFactor is linear),
// metallic 0, roughness 0.6, alphaMode BLEND when alpha < 1. Deterministic.
std::string PartsToGlb(const std::vector<GlbPart>& parts, bool exact);

// Reads a GLB written by MeshToGlb (or any GLB whose first mesh primitive is
// float positions with uint8/16/32 indices): the primitive's positions as
// stored, node transforms not applied (for MeshToGlb's files: millimetres,
// z up, exactly as written). Throws InputError naming
// `source` when the bytes are not such a GLB.
mesh::TriangleMesh GlbToMesh(std::string_view glb, const std::string& source = "glb");

}  // namespace fabatlas::artifact
