// The mesh road of OpenSCAD's CSG tree (csg_evaluation.h, docs/openscad.md
// "Two roads"): every subtree an exact mesh, OpenSCAD's own polygon meshes
// at the leaves and exact booleans, hulls, Minkowski sums and resizes above
// them, with level sets where the exact booleans cannot go.
#include "csg_evaluation.h"

#include <algorithm>
#include <cmath>

#include "fabatlas/error.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/exact_boolean.h"
#include "fabatlas/scad/evaluate_2d.h"
#include "fabatlas/scad/primitive_mesh.h"
#include "fabatlas/scad/surface_mesh.h"
#include "fabatlas/sha256.h"

namespace fabatlas::design::csg {

namespace fs = std::filesystem;

bool CsgEvaluation::MeshChildFrame(const CsgNode& n, const Affine& m, Affine* inner) {
  if (n.name == "hull") {
    *inner = m;
    return std::any_of(n.children.begin(), n.children.end(), [](const CsgNode& c) { return scad::Dimension(c) == 3; });
  }
  if (n.name == "minkowski" || n.name == "resize") {
    *inner = kIdentity;
    return true;
  }
  return false;
}

Solid CsgEvaluation::MeshOf(mesh::TriangleMesh mm, const Affine& a) {
  Transform(mm, a);
  const double det =
      a[0] * (a[5] * a[10] - a[6] * a[9]) - a[1] * (a[4] * a[10] - a[6] * a[8]) + a[2] * (a[4] * a[9] - a[5] * a[8]);
  if (det < 0)
    for (auto& t : mm.triangles) std::swap(t[1], t[2]);
  try {
    return geometry::MeshSolid(c_.grid, std::move(mm));
  } catch (const InputError& e) {
    Warn("CSG: " + std::string(e.what()) + "; the object is left out, as OpenSCAD leaves it out");
    return Solid();
  }
}

Solid CsgEvaluation::MeshOfChildren(const CsgNode& n, const Affine& m, const std::vector<Result>& kids,
                                    SubtreeRecord& record) {
  const std::string where = n.name + " (CSG line " + std::to_string(n.line) + ")";
  if (n.name == "hull") {
    std::vector<std::array<double, 3>> points;
    for (const auto& k : kids) {
      if (k.solid.empty()) continue;
      const mesh::TriangleMesh mm = k.solid.ToMesh();
      points.insert(points.end(), mm.vertices.begin(), mm.vertices.end());
    }
    return MeshOf(mesh::ConvexHull(points), kIdentity);
  }
  std::vector<mesh::TriangleMesh> operands;
  bool meshes = true;
  for (const auto& k : kids) {
    if (k.solid.empty())
      operands.emplace_back();
    else if (const mesh::TriangleMesh* b = k.solid.boundary())
      operands.push_back(*b);
    else
      meshes = false;
  }
  if (n.name == "resize") return MeshResized(n, m, kids);
  if (n.name == "minkowski") {
    if (!meshes) throw NoNativeEquivalent{"minkowski of a level set"};
    mesh::BooleanSummary summary;
    try {
      return MeshOf(mesh::MinkowskiSum(operands, &summary), m);
    } catch (const InputError& e) {
      throw NoNativeEquivalent{"minkowski: " + std::string(e.what())};
    }
  }
  const mesh::BooleanOp op = n.name == "difference"     ? mesh::BooleanOp::kDifference
                             : n.name == "intersection" ? mesh::BooleanOp::kIntersection
                                                        : mesh::BooleanOp::kUnion;
  // One child (a transform, a colour, a group of one): the child itself.
  if (op == mesh::BooleanOp::kUnion && kids.size() == 1) return kids[0].solid;
  if (kids.empty()) return Solid();
  if (meshes) {
    mesh::BooleanSummary summary;
    try {
      Solid out = MeshOf(mesh::ExactBoolean(op, operands, &summary), kIdentity);
      if (summary.nef) Warn(where + ": computed with Nef polyhedra (" + summary.nef_why + ")");
      return out;
    } catch (const InputError& e) {
      Warn(where + ": " + e.what() + "; evaluated with level sets instead");
    }
  } else {
    Warn(where + ": an operand is a level set; evaluated with level sets");
  }
  record.op = std::string(kCsgLevelSetOp) + n.name;
  Solid acc;
  bool first = true;
  for (const auto& k : kids) {
    if (first)
      acc = k.solid;
    else if (op == mesh::BooleanOp::kUnion)
      acc = geometry::Union(acc, k.solid);
    else if (op == mesh::BooleanOp::kDifference)
      acc = geometry::Difference(acc, k.solid);
    else
      acc = geometry::Intersection(acc, k.solid);
    first = false;
  }
  return acc;
}

Solid CsgEvaluation::MeshResized(const CsgNode& n, const Affine& m, const std::vector<Result>& kids) {
  if (kids.empty() || kids[0].solid.empty()) return Solid();
  const Solid& child = kids[0].solid;
  const geometry::Box3 box = child.BoundingBox();
  std::vector<double> size = {0, 0, 0};
  std::vector<bool> automatic = {false, false, false};
  if (auto it = n.args.find("newsize"); it != n.args.end()) {
    const auto v = Numbers(it->second);
    for (std::size_t i = 0; i < 3 && i < v.size(); ++i) size[i] = v[i];
  }
  if (auto it = n.args.find("auto"); it != n.args.end()) {
    if (it->second.type == CsgValue::Type::kBoolean)
      automatic = {it->second.boolean, it->second.boolean, it->second.boolean};
    for (std::size_t i = 0; i < 3 && i < it->second.items.size(); ++i)
      automatic[i] = it->second.items[i].type == CsgValue::Type::kBoolean ? it->second.items[i].boolean
                                                                          : Num(it->second.items[i], 0) != 0;
  }
  double scale[3] = {1, 1, 1}, largest = 0;
  for (int i = 0; i < 3; ++i) {
    const double extent = box.max[i] - box.min[i];
    if (size[i] > 0 && extent > 0) {
      scale[i] = size[i] / extent;
      largest = std::max(largest, scale[i]);
    }
  }
  for (int i = 0; i < 3; ++i)
    if (size[i] <= 0 && automatic[i] && largest > 0) scale[i] = largest;
  const Affine s = {scale[0], 0, 0, 0, 0, scale[1], 0, 0, 0, 0, scale[2], 0};
  return MeshOf(child.ToMesh(), Compose(m, s));
}

mesh::TriangleMesh CsgEvaluation::Outward(mesh::TriangleMesh mm) {
  if (mesh::EnclosedVolume(mm) < 0)
    for (auto& t : mm.triangles) std::swap(t[1], t[2]);
  return mm;
}

Solid CsgEvaluation::MeshLeaf(const CsgNode& n, const Affine& m) {
  if (n.name == "cube" || n.name == "sphere" || n.name == "cylinder") return MeshOf(PrimitiveMesh(n), m);
  if (n.name == "polyhedron") {
    mesh::TriangleMesh mm = PrimitiveMesh(n);
    for (const auto& v : mm.vertices)
      if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
        Warn("polyhedron (CSG line " + std::to_string(n.line) +
             "): a point is not finite; left out, as OpenSCAD's render of it encloses nothing");
        return Solid();
      }
    Outside(model_.filename().string() + ": polyhedron (CSG line " + std::to_string(n.line) + ")",
            Sha256Hex(n.canonical), mm);
    mm = Outward(std::move(mm));
    // OpenSCAD renders an approximately convex polyhedron as its hull.
    if (scad::ApproximatelyConvex(mm)) mm = mesh::ConvexHull(mm.vertices);
    return MeshOf(std::move(mm), m);
  }
  if (n.name == "linear_extrude" || n.name == "rotate_extrude") return MeshExtruded(n, m);
  if (n.name == "import") return MeshImported(n, m);
  if (n.name == "surface") {
    auto f = n.args.find("file");
    fs::path file = f != n.args.end() && f->second.type == CsgValue::Type::kString ? f->second.text : "";
    if (file.is_relative()) file = model_.parent_path() / file;
    std::vector<std::string> warnings;
    const scad::HeightMap map = scad::ReadHeightMap(file, n.Boolean("invert", false), &warnings);
    for (const std::string& w : warnings) Warn("surface (CSG line " + std::to_string(n.line) + "): " + w);
    return MeshOf(scad::SurfaceMesh(map, n.Boolean("center", false)), m);
  }
  if (IsTwoD(n.name)) return Solid();    // 2D among 3D objects: ignored, as OpenSCAD ignores it
  if (n.name == "hull") return Solid();  // a hull of 2D children only
  throw NoNativeEquivalent{n.name};
}

Solid CsgEvaluation::MeshExtruded(const CsgNode& n, const Affine& m) {
  // The 2D child as OpenSCAD computes it (Clipper), extruded to
  // OpenSCAD's mesh (evaluate_2d.h); projections below evaluate their
  // 3D children on this road, texts and 2D imports are OpenSCAD's outlines.
  scad::Evaluate2dOptions options;
  options.model_dir = model_.parent_path();
  options.outline = [this](const CsgNode& c) { return Outline2(c); };
  options.mesh3d = [this](const CsgNode& c) {
    return Evaluate3(c, kIdentity, leaf_path_ + "/" + std::to_string(++projections_)).solid.ToMesh();
  };
  std::vector<std::string> warnings;
  mesh::TriangleMesh mm;
  try {
    mm = n.name == "linear_extrude" ? scad::LinearExtrude(n, options, &warnings)
                                    : scad::RotateExtrude(n, options, &warnings);
  } catch (const scad::NoNativeEquivalentError& e) {
    throw NoNativeEquivalent{e.what()};
  } catch (const InputError& e) {  // an import outside the model's directory
    throw SampleFailure(kNoGeometry, model_.filename().string() + ": " + e.what());
  }
  for (const std::string& w : warnings) Warn(n.name + " (CSG line " + std::to_string(n.line) + "): " + w);
  return MeshOf(std::move(mm), m);
}

Solid CsgEvaluation::MeshImported(const CsgNode& n, const Affine& m) {
  const std::optional<fs::path> file = ImportedMeshFile(n);
  if (!file) return Solid();  // 2D: OpenSCAD ignores it among 3D objects
  mesh::TriangleMesh mm;
  try {
    mm = ReadImportedMesh(n, *file);
  } catch (const InputError& e) {
    Warn("import (CSG line " + std::to_string(n.line) + "): " + e.what() + "; left out, as OpenSCAD leaves it out");
    return Solid();
  }
  return MeshOf(Outward(std::move(mm)), m);
}

}  // namespace fabatlas::design::csg
