// fabatlas/assembly/part_library.h — connector primitives and parts of the
// FabHacks annotated object library (FabHacks Sec. 4.1; parametrisations
// from data/fabhacks/EXAMPLES.md).
#pragma once

#include <map>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "fabatlas/assembly/frame.h"

namespace fabatlas::assembly {

enum class PrimitiveType { kHook, kRod, kRing, kTube, kHemisphere, kClip, kEdge, kSurface };

// How a connection parameter behaves at its bounds (FabHacks, section 4.3.3).
enum class ParamKind {
  kUnbounded,          // periodic, wraps around (ring angle)
  kBoundedAndClamped,  // geometry keeps it inside [min,max]
  kBoundedAndOpen,     // leaving [min,max] means the connection falls apart
};

struct ParamSpec {
  std::string name;
  double min = 0, max = 1;
  ParamKind kind = ParamKind::kBoundedAndClamped;
};

// One annotated connector primitive on a part. Shape parameters are mm/degrees:
//   hook/ring: arc_radius, arc_angle (hook only), thickness (wire radius)
//   rod: length, radius;  tube: length, inner_radius, thickness
//   clip: width, height, thickness, base_dist, gap;  edge: length, width, thickness
//   surface: length, width;  hemisphere: radius
struct Primitive {
  std::string name;
  PrimitiveType type = PrimitiveType::kRod;
  std::map<std::string, double> shape;
  Frame frame;         // base frame in the part frame
  bool closed = false; // closed primitive (rings always are)
  bool clamped = false; // ends blocked: slide parameters are BOUNDED_AND_CLAMPED (closed implies it)
  bool flex = false;   // Flex variant: extra orientation DoF phi (hook/ring)
  bool ctl = false;    // Ctl variant: only changes the alignment offset table

  double Shape(const std::string& key) const;  // throws std::out_of_range
  // Connection DoFs s of this primitive, in order (EXAMPLES.md).
  std::vector<ParamSpec> Params() const;
  // Critical dimension (FabHacks, 4.1): length for rod/tube/edge/surface,
  // inner (hoop) radius for hook/ring, gap for clip, 0 for hemisphere.
  double CriticalDimension() const;
  // What this primitive occupies of the critical dimension of a partner:
  // wire diameter for hook/ring, rod diameter, tube length, clip width, ...
  double OccupiedSize(PrimitiveType partner) const;
};

// Primitive frame M(s) in the part frame: base frame · parametrised frame.
Eigen::Isometry3d ConnectorFrame(const Primitive& p, const std::vector<double>& s);

// Alignment offset A for connect(a, b) (EXAMPLES.md table): P_a·M_a·A = P_b·M_b.
Eigen::Matrix3d AlignmentOffset(const Primitive& a, const Primitive& b, bool flip);

// Table 1 of FabHacks: may these two primitive types connect at all?
bool CanConnect(PrimitiveType a, PrimitiveType b);

const char* ToString(PrimitiveType t);

struct Part {
  std::string name;
  std::string mesh;  // file name inside the mesh directory ("" = none)
  double mass = 0;   // mesh volume (mm^3) × density 1 = grams at 1 g/cm^3
  Eigen::Vector3d centre_of_mass = Eigen::Vector3d::Zero();  // mm, part frame
  std::vector<Primitive> primitives;
  const Primitive* Find(const std::string& primitive) const;  // nullptr if absent
};

struct PartLibrary {
  std::map<std::string, Part> parts;
};

// Loads a part library YAML (format in docs/assembly.md). Mass and centre of
// mass come from the part's mesh in `mesh_dir` unless given explicitly.
// Throws InputError("file:line:col: message").
PartLibrary LoadPartLibrary(const std::string& yaml_path, const std::string& mesh_dir);

// The mesh file names (each part's `mesh:`, a name inside the mesh
// directory) a part library YAML names, sorted, each once; for job bundles,
// which carry them to workers. Throws InputError("file:line:col: message").
std::vector<std::string> PartLibraryMeshes(const std::string& yaml_path);

}  // namespace fabatlas::assembly
