// fabatlas/assembly/part_library.h — connector primitives and parts of the
// FabHacks annotated object library (FabHacks, section 4.1; parametrisations,
// variants, flags and alignment frames from data/fabhacks/PARTS.md §1–2).
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
  double init = 0.5;  // default value (PARTS.md §1), the solver's first start
  // A BOUNDED_AND_OPEN parameter whose end is blocked by the part itself
  // (a rod running into a wider body): leaving through that end is not
  // falling apart.
  bool blocked_min = false, blocked_max = false;
  bool held = false;  // held at `init` in every phase (a primitive's fixed base form, PARTS.md §2.3)
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
  Frame frame;  // base frame in the part frame
  // Closed for connecting (the reference's is_open_for_connect = false): two
  // closed primitives cannot be joined (rings always are).
  bool closed = false;
  // Closed ends (is_open = false): bounded parameters are BOUNDED_AND_CLAMPED
  // instead of BOUNDED_AND_OPEN (PARTS.md §1.10).
  bool clamped = false;
  bool flex = false;  // Flex variant: extra orientation DoF phi (hook/ring)
  bool ctl = false;   // Ctl (centre-line) variant of rod, ring, tube: own frame formula
  // Ends of the slide parameter (rod/tube/edge t, hook θ) blocked by the part's
  // own body ("min" / "max" / "both"), see ParamSpec; for rods, checked
  // against the part's mesh with MeasureRodEnds (rod_ends.h).
  bool blocked_min = false, blocked_max = false;

  double Shape(const std::string& key) const;  // throws std::out_of_range
  // Connection DoFs s of this primitive, in order, with ranges, kinds and
  // defaults (PARTS.md §1).
  std::vector<ParamSpec> Params() const;
  // The same DoFs in the primitive's fixed base form (PARTS.md §1: rod t ½ φ
  // 90, hook θ α/2 φ 90, ring φ 90 with θ free, tube t ½ with θ free,
  // surface ½ ½ 0): held parameters carry their value in `init`.
  std::vector<ParamSpec> BaseFormParams() const;
  // The reference's class name of this primitive for alignment keys:
  // "Rod", "RodCtl", "HookFlex", "RingCtl", ... (`variant` true) or the base
  // class "Rod", "Hook", ... (`variant` false).
  std::string ClassName(bool variant) const;
  // Critical dimension (FabHacks, 4.1): length for rod/tube/edge/surface,
  // inner (hoop) radius for hook/ring, gap for clip, 0 for hemisphere.
  double CriticalDimension() const;
  // What this primitive occupies of the critical dimension of a partner:
  // wire diameter for hook/ring, rod diameter, tube length, clip width, ...
  double OccupiedSize(PrimitiveType partner) const;
};

// Primitive frame M(s) in the part frame: base frame · parametrised frame.
Eigen::Isometry3d ConnectorFrame(const Primitive& p, const std::vector<double>& s);

// Alignment frame A of key "<class1>_<class2>" (PARTS.md §2.2), with `flip`
// applied to its flip axes: P_1·M_1(s_1)·A = P_2·M_2(s_2). Unknown keys:
// identity. attach(new, placed) uses the key placed_new with variant class
// names, connect(e1, e2) the key e1_e2 with base class names (§2.1).
Eigen::Matrix3d AlignmentOffset(const std::string& key, bool flip);

// Table 1 of FabHacks: may these two primitive types connect at all?
bool CanConnect(PrimitiveType a, PrimitiveType b);

const char* ToString(PrimitiveType t);

struct Part {
  std::string name;
  std::string mesh;                                          // file name inside the mesh directory ("" = none)
  double mass = 0;                                           // mesh volume (mm^3) × density 1 = grams at 1 g/cm^3
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
