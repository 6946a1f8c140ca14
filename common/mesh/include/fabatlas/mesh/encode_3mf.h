// fabatlas/mesh/encode_3mf.h — a triangle mesh as a 3MF package (3D
// Manufacturing Format, core specification 1.2), the format slicers open
// with units and without STL's duplicated vertices.
#pragma once

#include <string>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

// A ZIP package (entries deflated, CRC-32 from zlib) holding
// [Content_Types].xml, _rels/.rels and 3D/3dmodel.model: one object of type
// "model" with the mesh's vertices (millimetres, unit="millimeter", 9
// significant digits) and triangles as given, and one build item. The
// mesh should be closed and consistently oriented (3MF requires it); this
// function does not check. Deterministic: no timestamps (the ZIP dates are
// 1980-01-01). Indices must be in range (EncodeMesh checks them).
std::string Encode3mf(const TriangleMesh& mesh);

}  // namespace fabatlas::mesh
