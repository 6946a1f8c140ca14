// fabatlas/mesh/encode_3mf.h — a triangle mesh as a 3MF package (3D
// Manufacturing Format, core specification 1.2), the format slicers open
// with units and without STL's duplicated vertices.
#pragma once

#include <array>
#include <string>
#include <vector>

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

// One object of a package of several: a part of the design.
struct Object3mf {
  std::string name;  // the object's name (slicers list it); empty: none
  const TriangleMesh* mesh = nullptr;
  bool coloured = false;         // false: no material
  std::array<double, 4> rgba{};  // sRGB red, green, blue, alpha in [0, 1]
};

// As Encode3mf, one object of type "model" per entry (ids 1, 2, ... in
// order, or 2, 3, ... after the materials) with its name, and one build item
// each, untransformed. The distinct colours of the coloured objects become
// one <basematerials> group (id 1; 3MF core specification 1.2, Sec. 5.1
// "Base Materials": each <base> named by its "#rrggbb[aa]" colour, with that
// displaycolor), and each coloured object points at its colour by pid and
// pindex (Sec. 4.1 "Object"), so a slicer assigns its colour or filament.
// With one uncoloured unnamed object the bytes are Encode3mf's.
std::string Encode3mfObjects(const std::vector<Object3mf>& objects);

}  // namespace fabatlas::mesh
