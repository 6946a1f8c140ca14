// Internal: the evaluation of OpenSCAD's CSG tree for the `openscad` node
// (openscad_node.h, docs/openscad.md): every subtree keyed by (τ, ρ),
// recorded, looked up in and offered to the subtree cache, and computed on
// one of two roads, exact meshes (csg_mesh_road.cc) or level sets
// (csg_level_set_leaves.cc, csg_field.h); subtrees with no native
// equivalent are OpenSCAD's own renders and outlines
// (csg_openscad_subtrees.cc).
#pragma once

#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "csg_affine.h"
#include "csg_arguments.h"
#include "csg_field.h"
#include "csg_shape_2d.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"
#include "openscad_node.h"

namespace fabatlas::design::csg {

using geometry::Solid;

class CsgEvaluation {
 public:
  // mesh_road: every subtree an exact mesh (mesh::ExactBoolean and friends),
  // else today's level sets (docs/openscad.md, "Two roads").
  CsgEvaluation(OpenScadNodeContext& context, const std::filesystem::path& model, const std::filesystem::path& work,
                bool mesh_road)
      : c_(context), model_(model), work_(work), mesh_road_(mesh_road), render2_([this](const CsgNode& n) {
          return Outline2(n);
        }) {}

  // A subtree's geometry: a level set, or (while every node below is a
  // convex primitive, a straight prism or a boolean of them) its signed
  // distance bound not sampled yet, so a whole CSG tree of such nodes is
  // sampled once in its result's band instead of once per leaf plus a grid
  // copy per boolean. Both empty: no material.
  struct Result {
    Solid solid{};
    std::shared_ptr<const Field> field{};
    std::string key{};
    std::shared_ptr<const SubtreeTrace> trace{};  // with a subtree cache (null when found without one)
  };

  // Subtree n under the composed transform m, recorded at `path` (its
  // descendants below it, post-order). need_solid: sample a field result
  // (the root of the evaluation). Fields are combined only without a
  // subtree cache.
  Result Evaluate3(const CsgNode& n, const Affine& m, const std::string& path, bool need_solid = false);

  // a minus every solid of `others` (the parts' disjointness: an earlier
  // part keeps what it shares with a later one), as a difference node would.
  Solid Minus(const Solid& a, const std::vector<Solid>& others);

 private:
  // The evaluated 3D children of a boolean, in order.
  struct Children {
    std::vector<Result> results;
    std::vector<std::string> paths;  // below the parent's path ("/0", "/2")
    // OpenSCAD 2021.01 takes a 2D object among 3D ones as no material (with
    // a warning): it empties an intersection, and a difference it comes
    // first in. Set on the mesh road only.
    bool two_d = false, two_d_first = false;
  };

  // ---- Evaluate3's steps (csg_evaluation.cc) ----

  // A cache hit of subtree n: recorded with the records of its descendants
  // and its outside meshes as its trace holds them, else (a cache filled
  // elsewhere) only with the keys of the children it was computed from.
  Result Recalled(const CsgNode& n, const Affine& m, const std::string& path, const CachedSubtree& hit,
                  SubtreeRecord& record);

  // The 3D children of a boolean under `inner`, each its own record.
  Children EvaluateChildren(const CsgNode& n, const Affine& inner, const std::string& path);

  // Subtree n on the mesh road: a boolean of its children, else a leaf;
  // OpenSCAD's render where there is no native equivalent.
  Solid OnMeshRoad(const CsgNode& n, const Affine& m, const std::string& path, bool boolean, const Children& kids,
                   SubtreeRecord& record);

  // A boolean of children on the level-set road: a field while every child
  // is one, else the level-set booleans; into result.field or result.solid.
  void CombineLevelSets(const CsgNode& n, const std::vector<Result>& kids, Result& result);

  // Offers a computed subtree to the cache with its trace (its record, its
  // children's traces and the outside meshes met since `outside_before`).
  void Offer(const SubtreeRecord& record, const Children& kids, std::size_t outside_before, Result& result);

  // The cache key of subtree n under the composed transform m.
  std::string KeyOf(const CsgNode& n, const Affine& m) const;

  // Whether n is evaluated from its 3D children (booleans and multmatrix
  // with a native matrix), and the transform they are evaluated under.
  static bool ChildFrame(const CsgNode& n, const Affine& m, Affine* inner);

  static std::string Topology(const CsgNode& n);

  // A field sampled in its band (geometry::FromDistance).
  Solid Sample(const Field& f);

  // Records a mesh that entered from outside fabatlas (OpenScadNodeContext::outside).
  void Outside(const std::string& what, const std::string& key, const mesh::TriangleMesh& m);

  // A warning of the model, in the log (OpenScadNodeContext::warnings).
  void Warn(const std::string& text);

  // The mesh file an `import` node names (STL, OFF, OBJ, 3MF or AMF),
  // relative paths resolved against the model's directory; nullopt for a
  // 2D file (DXF, SVG). Throws NoNativeEquivalent for a node without a file
  // or a format no road reads.
  std::optional<std::filesystem::path> ImportedMeshFile(const CsgNode& n) const;

  // Reads that file (mesh::ReadMesh) and records it as a mesh from outside
  // (Outside). Throws InputError when it cannot be read.
  mesh::TriangleMesh ReadImportedMesh(const CsgNode& n, const std::filesystem::path& file);

  // ---- The level-set road's leaves (csg_level_set_leaves.cc) ----

  Solid FromMesh(mesh::TriangleMesh m, const Affine& a);

  // A closed convex mesh (OpenSCAD's cubes, spheres, cylinders, hulls) under
  // a: its exact distance as a field; a level set when it is not convex.
  Result Convex(mesh::TriangleMesh m, const Affine& a);

  // The shape extruded loop by loop by `build`, combined as the shape's
  // booleans (even-odd within a loop set).
  Solid Extruded(const Shape2& s, const std::function<mesh::TriangleMesh(const Loop&)>& build, const Affine& m);

  // Points of a subtree made only of primitives, groups and transforms (for hull).
  void HullPoints(const CsgNode& n, const Affine& m, std::vector<std::array<double, 3>>& out);

  // OpenSCAD's polygon mesh of a cube, sphere, cylinder or polyhedron.
  mesh::TriangleMesh PrimitiveMesh(const CsgNode& n);

  // A leaf on the level-set road. Throws NoNativeEquivalent.
  Result Leaf(const CsgNode& n, const Affine& m);

  // linear_extrude on the level-set road: a prism field when straight,
  // else OpenSCAD's extruded mesh.
  Result LinearExtruded(const CsgNode& n, const Affine& m);

  // An imported STL, OFF, OBJ, 3MF or AMF mesh on the level-set road.
  Result Imported(const CsgNode& n, const Affine& m);

  // A straight linear_extrude (no twist, no scale) under a similarity: the
  // prism's signed distance from the outline's (exact per loop set), as a
  // field. Empty when the map is not a similarity (then meshes).
  std::optional<Result> Prism(const Shape2& s, double h, bool center, const Affine& m);

  // ---- OpenSCAD's own renders of subtrees (csg_openscad_subtrees.cc) ----

  // OpenSCAD exports this subtree alone (its canonical text is a program,
  // written as work_/<stem>-<k>.scad) to that path + `extension`, returned in
  // `out`; false with `run` telling why when it cannot.
  bool ExportSubtree(const CsgNode& n, const std::string& stem, const std::string& extension,
                     std::filesystem::path& out, scad::OpenScadRun& run);

  // OpenSCAD renders this subtree alone.
  Solid Rendered(const CsgNode& n, const Affine& m, const std::string& why);

  // OpenSCAD's 2D SVG export of a 2D subtree (its canonical text is a
  // program): a 2D export is cheap next to a 3D render, and the outline is
  // then extruded natively. Outlines are remembered per canonical text for
  // the process (a text's glyphs are the same in every sample with that
  // text), up to kOutlineBytes in all; beyond that all are forgotten at once
  // and remembering starts again. Throws NoNativeEquivalent when OpenSCAD
  // cannot export it.
  static constexpr std::size_t kOutlineBytes = std::size_t{32} << 20;
  std::vector<Loop> Outline2(const CsgNode& n);

  // A subtree's program runs in the work directory, where the files the
  // model imports by relative name (`import("x.dxf")`) must be found too:
  // they are linked there once (model_files.h).
  void LinkModelFiles();

  // ---- The mesh road (csg_mesh_road.cc) ----

  // Nodes evaluated from their 3D children on the mesh road beyond the
  // booleans and multmatrix: hull (children in the world frame: a hull
  // commutes with affine maps), minkowski and resize (children in their own
  // frame, the result mapped by m: a Minkowski sum would count m's
  // translation once per operand, a resize reads the child's own box).
  static bool MeshChildFrame(const CsgNode& n, const Affine& m, Affine* inner);

  // An exact mesh under a as a mesh solid; a mesh with a reflection is
  // turned inside out by the map, so its triangles are reversed.
  Solid MeshOf(mesh::TriangleMesh mm, const Affine& a);

  // A boolean, hull, minkowski or resize of evaluated children (kids: the
  // 3D children in order) on the mesh road. Operands that are not meshes (a
  // level-set fallback below) or that the exact booleans cannot take make it
  // a level-set boolean, named in the record ("csg-levelset:") and the log.
  Solid MeshOfChildren(const CsgNode& n, const Affine& m, const std::vector<Result>& kids, SubtreeRecord& record);

  // resize(newsize, auto): the child's own box scaled per axis to newsize;
  // an axis of newsize 0 keeps its size, or with auto takes the largest
  // scale of the axes given (OpenSCAD User Manual, "resize").
  Solid MeshResized(const CsgNode& n, const Affine& m, const std::vector<Result>& kids);

  // A mesh turned outward when it encloses a negative volume (an inverted
  // polyhedron, as OpenSCAD flips it).
  static mesh::TriangleMesh Outward(mesh::TriangleMesh mm);

  // A leaf on the mesh road: OpenSCAD's own polygon mesh of it.
  Solid MeshLeaf(const CsgNode& n, const Affine& m);

  // linear_extrude or rotate_extrude on the mesh road.
  Solid MeshExtruded(const CsgNode& n, const Affine& m);

  // An imported mesh on the mesh road (a 2D import among 3D objects: none).
  Solid MeshImported(const CsgNode& n, const Affine& m);

  OpenScadNodeContext& c_;
  std::filesystem::path model_, work_;
  bool mesh_road_ = true;
  std::string leaf_path_;  // the record path of the leaf MeshLeaf evaluates (its projections' children go below it)
  int projections_ = 0;
  int rendered_ = 0;
  bool linked_ = false;
  Render2 render2_;
};

}  // namespace fabatlas::design::csg
