// fabatlas/mesh/write_mesh.h — export a triangle mesh as STL, OBJ, OFF or PLY.
#pragma once

#include <filesystem>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

// Writes `mesh` to `path` in the format named by its (case-insensitive)
// extension:
//   .stl  binary STL (float32 coordinates, facet normals from the corners);
//   .obj  Wavefront OBJ, `v` and `f` records, 17 significant digits;
//   .off  OFF, 17 significant digits;
//   .ply  binary_little_endian PLY with float64 x, y, z and int32 indices.
// OBJ, OFF and PLY round-trip coordinates exactly; STL rounds to float32.
// The file is written to a temporary sibling ("<name>.tmp-<pid>") and renamed
// over `path` only once fully written and flushed, so readers never see a
// partial file. Throws fabatlas::InputError naming `path` for an unknown
// extension, an index out of range, or any I/O failure (missing directory,
// disk full, file size limit); the temporary file is removed in that case.
void WriteMesh(const TriangleMesh& mesh, const std::filesystem::path& path);

}  // namespace fabatlas::mesh
