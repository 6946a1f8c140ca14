// fabatlas/mesh/write_mesh.h — export a triangle mesh as STL, OBJ, OFF, PLY or 3MF.
#pragma once

#include <filesystem>
#include <string>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

// Writes `mesh` to `path` in the format named by its (case-insensitive)
// extension:
//   .stl  binary STL (float32 coordinates, facet normals from the corners);
//   .obj  Wavefront OBJ, `v` and `f` records, 17 significant digits;
//   .off  OFF, 17 significant digits;
//   .ply  binary_little_endian PLY with float64 x, y, z and int32 indices;
//   .3mf  3MF core (encode_3mf.h), millimetres.
// OBJ, OFF and PLY round-trip coordinates exactly; STL rounds to float32.
// The file is written to a temporary sibling ("<name>.tmp-<pid>") and renamed
// over `path` only once fully written and flushed, so readers never see a
// partial file. Throws fabatlas::InputError naming `path` for an unknown
// extension, an index out of range, or any I/O failure (missing directory,
// disk full, file size limit); the temporary file is removed in that case.
void WriteMesh(const TriangleMesh& mesh, const std::filesystem::path& path);

// The bytes WriteMesh would write for a file with this extension (".stl",
// ".obj", ".off", ".ply", ".3mf"; case-insensitive). Throws InputError for an
// unknown extension or an index out of range (the message names no file).
std::string EncodeMesh(const TriangleMesh& mesh, const std::string& extension);

}  // namespace fabatlas::mesh
