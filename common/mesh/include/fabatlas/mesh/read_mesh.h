// fabatlas/mesh/read_mesh.h — import a triangle mesh from STL, OBJ, OFF, PLY, 3MF or AMF.
#pragma once

#include <filesystem>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

// Reads the mesh at `path`; the format is chosen by the (case-insensitive)
// extension:
//   .stl  binary or ASCII STL (binary when the file size is exactly
//         84 + 50 * triangle count); STL repeats vertices per facet, so
//         vertices with bit-identical coordinates are merged on import;
//   .obj  Wavefront OBJ: `v` and `f` records (v, v/t, v//n, v/t/n, negative
//         relative indices); other records are ignored;
//   .off  OFF / COFF / NOFF (first three numbers of each vertex line);
//   .ply  ASCII, binary_little_endian or binary_big_endian PLY with a vertex
//         element (x, y, z) and a face element (vertex_indices list);
//   .3mf  3MF core: every build item's object (meshes and components under
//         their transforms);
//   .amf  AMF (plain or zipped XML): every object's volumes' triangles, in
//         no curved triangles, materials or constellations). 3MF and AMF
//         coordinates are taken as stored, whatever their unit attribute
//         (OpenSCAD 2021.01 ignores it too).
// Polygons with more than three corners are split into triangle fans around
// their first corner. Coordinates are taken as millimetres as stored.
//
// Throws fabatlas::InputError with a one-line message starting with the path
// when the file is missing or unreadable, the extension is unknown, the content
// is unparsable or truncated, it holds zero triangles, a coordinate is NaN or
// infinite, or a face index is out of range. Never crashes on garbage.
// Single-threaded; the whole file is read into memory.
TriangleMesh ReadMesh(const std::filesystem::path& path);

}  // namespace fabatlas::mesh
