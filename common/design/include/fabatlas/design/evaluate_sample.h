// fabatlas/design/evaluate_sample.h — EvaluateSample(u) of Fab Forms Alg. 2 and
// the volumetric change ΔG of Eq. 2 between two evaluated samples.
#pragma once

#include <array>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "fabatlas/design/constraint_solve.h"
#include "fabatlas/design/design.h"
#include "fabatlas/design/subtree_cache.h"
#include "fabatlas/geometry/solid.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::design {

struct StateGraph;  // state_graph.h

// Failure types, in the order checks run. A sample's failure is the type of
// its first failed check.
inline constexpr const char* kUnsatConstraints = "unsat_constraints";
inline constexpr const char* kNoGeometry = "no_geometry";
inline constexpr const char* kNotWatertight = "not_watertight";
inline constexpr const char* kSelfIntersecting = "self_intersecting";
inline constexpr const char* kThinParts = "thin_parts";
inline constexpr const char* kUnstable = "unstable";
inline constexpr const char* kTooMuchMaterial = "too_much_material";
inline constexpr const char* kTooMuchDeformation = "too_much_deformation";  // fem check
// fem check: at this sample the fixed or loaded region selects nothing of the
// solid (or the solid has no FEM voxel), so there is no load path to test.
inline constexpr const char* kLoadCaseMissesSolid = "load_case_misses_solid";
inline constexpr const char* kCollision = "collision";                      // collision_free check
inline constexpr const char* kTooLittleClearance = "too_little_clearance";  // collision_free check
// collision_free check with `repair_with`: it collides, and automatic
// resolution within those parameters (resolve_collisions.h) makes the design
// valid.
inline constexpr const char* kRepairable = "repairable";
inline constexpr const char* kInfeasible = "infeasible";       // assembly_feasible check
inline constexpr const char* kFallsApart = "falls_apart";      // assembly_stable check
inline constexpr const char* kTargetMissed = "target_missed";  // target_reached check

struct CheckOutcome {
  std::string name;  // check name (constraints, geometry, then the design's)
  bool passed = false;
  std::string failure;  // failure type when not passed
  std::string reason;   // human explanation, e.g. "centre of mass 3.2 mm outside the support polygon"
  double seconds = 0;
  // Quantities the check measured (e.g. fem_max_displacement in mm); they
  // become properties of valid samples.
  std::map<std::string, double> measures{};
};

// One subtree root evaluated (or found in the cache) for this sample.
struct SubtreeRecord {
  std::string key;       // hex SHA-256 of (τ, ρ, voxel size): the cache key
  std::string topology;  // hex SHA-256 of τ alone
  std::string path;      // node position, e.g. "root/0/1"
  std::string op;
  double seconds = 0;  // root compute time given its children (0 if cached)
  bool from_cache = false;
  std::size_t bytes = 0;              // memory of the resulting grid
  std::vector<std::string> children;  // keys of the child subtrees
};

// A part of the design's result, as the designer made it: a top-level body of
// an OpenSCAD model, or one colour region of a body (docs/openscad.md, "Parts
// and colours"). Closed and outward like the sample's solid; the parts of a
// model are disjoint, and together they are the sample's solid.
struct Part {
  std::string name;              // "body1", or "body1-ff0000" for one colour of a body of several
  bool coloured = false;         // whether the model gave it a colour (rgba meaningful)
  std::array<double, 4> rgba{};  // red, green, blue, alpha in [0, 1] (OpenSCAD's color())
  mesh::TriangleMesh mesh;       // millimetres, z up
};

struct EvaluateOptions {
  SubtreeCache* cache = nullptr;  // optional; subtrees are looked up and offered
  bool keep_solid = true;         // keep the root level set in the result
  // false: a preview (Fab Forms Sec. 7): solve and build the geometry only,
  // skip the checks and properties (the sample is then valid iff it has
  // geometry).
  bool run_checks = true;
  // true: keep the surface the checks extracted in SampleResult::surface
  // (`fabatlas eval --mesh` writes it instead of extracting it again).
  bool keep_surface = false;
  // true: look every subtree up in `cache` before evaluating its children
  // (computing its key from the resolved arguments alone), so a hit skips the
  // whole subtree below it, as a preview with cache H does (Fab Forms
  // Sec. 6.2). The records of a hit's descendants are then absent. false
  // (sampling): children are always evaluated, every subtree is recorded.
  bool lookup_before_children = false;
  // Reconfigurables: when set (and the point has geometry), filled with the
  // objects' meshes, the transitions' motions and the collision_free check's
  // intervals (state_graph.h, EvaluateStateGraph).
  StateGraph* state_graph = nullptr;
  // true (a worker's job bundle): an OpenSCAD model naming a file outside
  // its directory (absolute, '..' out of it, a link pointing out) is refused
  // with InputError before anything reads that file (model_files.h). false
  // (a model evaluated where it lies): OpenSCAD's own lookup.
  bool confine_model_files = false;
  // Reconfigurables: a sample failing with `collision` whose collision_free
  // check names `repair_with` parameters is resolved within them
  // (resolve_collisions.h) and fails with `repairable` when that makes it
  // valid. false: no resolution (the resolution's own evaluations).
  bool repair_collisions = true;
  // When set (and the point has geometry), filled with the result's parts:
  // for a design whose tree is one `openscad` node, its model's top-level
  // bodies and colour regions (evaluated apart, after the sample's solid:
  // checks and properties still judge the union); for any other design one
  // uncoloured part, the solid's surface. The root is then not looked up in
  // `cache` as a whole (its CSG subtrees still are).
  std::vector<Part>* parts = nullptr;
};

struct SampleResult {
  Point u;
  bool valid = false;
  std::string failure;  // empty when valid
  std::string failure_reason;
  std::vector<CheckOutcome> checks;
  std::map<std::string, double> properties;
  std::map<std::string, double> values;  // every parameter after solving
  geometry::Solid solid;                 // root geometry (empty when invalid before geometry)
  // solid.ToMesh() as the checks read it, when EvaluateOptions::keep_surface
  // and a check extracted it; else null.
  std::shared_ptr<const mesh::TriangleMesh> surface;
  std::vector<SubtreeRecord> subtrees;  // post-order, root last
  // The sample's log: what OpenSCAD would warn of (a 2D object among 3D
  // ones, an object left out) and each fallback of the mesh road (Nef
  // polyhedra, level sets), "MODEL.scad: where: what". Subtrees found in the
  // geometry cache bring none.
  std::vector<std::string> warnings;
  // Wall seconds: solve, tree, checks (surface included), surface (the
  // extraction of the surface the checks read, when one does), properties,
  // total.
  std::map<std::string, double> timings;
};

// Fab Forms Alg. 2. Bad values at this point (a negative radius after solving)
// make the sample invalid with a reason; InputError is thrown only for
// problems of the design itself (e.g. a resource limit, an unreadable mesh).
SampleResult EvaluateSample(const Design& design, const Point& u, const EvaluateOptions& options = {});

// One carve_swept node's cutter on its own (worker task kind
// TASK_KIND_SWEPT_VOLUME, common/protocol/fabatlas/v1/tasks.proto): at point
// u, the eps-offset swept volume of the node's moving object along its
// transition, in the frame object's body coordinates (Reconfigurables, Sec. 6.7).
struct SweptVolumeResult {
  double volume = 0;              // mm^3 enclosed by the offset surface
  std::size_t triangles = 0;      // of the offset surface
  int time_steps = 0;             // time samples used
  std::size_t active_voxels = 0;  // of the sparse swept distance grid
  // The surface as mesh::RawMeshBytes (mesh::MeshOfRawBytes reads it back
  // given `triangles`) and their SHA-256 (hex). Both empty when the volume
  // was not computed.
  std::string surface_sha256;
  std::string surface_bytes;
};

// `node_path` addresses the node as subtree records do: "root/1/0" in the
// tree, "object:NAME/0" in an object's tree. Throws InputError for a path
// that names no carve_swept node, unsatisfiable constraints, or a value that
// makes the sweep impossible (the one-line reason).
SweptVolumeResult ComputeSweptVolume(const Design& design, const Point& u, const std::string& node_path);

// ΔG(u1,u2) = |V(G1) xor V(G2)| / |V(G1) union V(G2)| (Fab Forms Eq. 2), with
// invalid samples taken as empty: ΔG(invalid, invalid) = 0 and
// ΔG(valid, invalid) = 1.
double DeltaG(const SampleResult& a, const SampleResult& b);

}  // namespace fabatlas::design
