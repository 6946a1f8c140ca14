#include "fabatlas/assembly/part_library.h"

#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>

#include "connector_frames.h"
#include "fabatlas/assembly/fit_primitive.h"
#include "fabatlas/assembly/mass_properties.h"
#include "yaml_errors.h"

namespace fabatlas::assembly {

double Primitive::Shape(const std::string& key) const {
  auto it = shape.find(key);
  if (it == shape.end()) throw std::out_of_range("primitive '" + name + "' lacks shape '" + key + "'");
  return it->second;
}

std::vector<ParamSpec> Primitive::Params() const {
  // PARTS.md §1.10: periodic parameters wrap; a bounded parameter is
  // BOUNDED_AND_CLAMPED when the primitive's ends are closed (is_open false)
  // and otherwise BOUNDED_AND_OPEN — but only parameters that move the
  // contact along the primitive (rod/tube/edge t, hook θ, the point on a
  // hemisphere) can run off it (FabHacks 4.3.3: "hooks or rings that slide
  // past the end of the dowel rod fall off"). The orientation limits (rod φ
  // around the rod, the flex φ of hooks and rings) are geometric stops: leaving
  // them turns a connector against its partner, it does not slip off, so we
  // keep them clamped (the reference marks them open with the primitive;
  // docs/assembly.md "Falling apart").
  const ParamKind b = clamped ? ParamKind::kBoundedAndClamped : ParamKind::kBoundedAndOpen;
  const ParamKind c = ParamKind::kBoundedAndClamped;
  const ParamKind u = ParamKind::kUnbounded;
  std::vector<ParamSpec> p;
  switch (type) {
    case PrimitiveType::kRod:
      p = {{"t", 0, 1, b, 0.5}};
      if (!ctl) p.push_back({"phi", 45, 135, c, 90});
      break;
    case PrimitiveType::kHook: {
      const double alpha = Shape("arc_angle");
      const double lo = shape.count("theta_min") ? shape.at("theta_min") : 0;
      const double hi = shape.count("theta_max") ? shape.at("theta_max") : alpha;
      p = {{"theta", lo, hi, alpha >= 360 ? u : b, alpha / 2}};
      if (flex) p.push_back({"phi", 45, 135, c, 90});
      break;
    }
    case PrimitiveType::kRing:
      if (ctl) return {{"u1", 0, 360, u, 0}, {"u2", 0, 360, u, 180}};
      p = {{"theta", 0, 360, u, 180}};
      if (flex) p.push_back({"phi", 30, 150, c, 90});
      break;
    case PrimitiveType::kTube:
      p = {{"t", 0, 1, b, 0.5}, {"theta", 0, 360, u, 180}};
      break;
    case PrimitiveType::kClip:
      return {{"t", 0, 1, c, 0.5}};
    case PrimitiveType::kEdge:
      p = {{"t", 0, 1, ParamKind::kBoundedAndOpen, 0.5}};
      break;
    case PrimitiveType::kSurface:
      return {{"t1", 0, 1, b, 0.5}, {"t2", 0, 1, b, 0.5}, {"spin", 0, 360, u, 0}};
    case PrimitiveType::kHemisphere:
      return {{"theta", 90, 270, ParamKind::kBoundedAndOpen, 180},
              {"phi", 90, 270, ParamKind::kBoundedAndOpen, 180},
              {"spin", 0, 360, u, 0}};
  }
  p[0].blocked_min = blocked_min;
  p[0].blocked_max = blocked_max;
  return p;
}

std::vector<ParamSpec> Primitive::BaseFormParams() const {
  std::vector<ParamSpec> p = Params();
  for (auto& s : p) {
    if (type == PrimitiveType::kRing && s.name == "theta") continue;  // θ stays free
    if (type == PrimitiveType::kTube && s.name == "theta") continue;  // θ stays free
    s.held = true;
    if (type == PrimitiveType::kRing && ctl) s.init = s.name == "u1" ? 180 : 0;  // R(0,180,0)
  }
  return p;
}

std::string Primitive::ClassName(bool variant) const {
  static const char* kNames[] = {"Hook", "Rod", "Ring", "Tube", "Hemisphere", "Clip", "Edge", "Surface"};
  std::string n = kNames[static_cast<int>(type)];
  if (!variant) return n;
  if (ctl) return n + "Ctl";
  if (flex) return n + "Flex";
  return n;
}

double Primitive::CriticalDimension() const {
  switch (type) {
    case PrimitiveType::kRod:
    case PrimitiveType::kTube:
    case PrimitiveType::kEdge:
    case PrimitiveType::kSurface:
      return Shape("length");
    case PrimitiveType::kHook:
    case PrimitiveType::kRing:
      return Shape("arc_radius");  // the reference's critical_dim (a rod fits if its radius is below it)
    case PrimitiveType::kClip:
      return Shape("gap");
    case PrimitiveType::kHemisphere:
      return 0;
  }
  return 0;
}

double Primitive::OccupiedSize(PrimitiveType partner) const {
  const bool partner_is_radius =
      partner == PrimitiveType::kHook || partner == PrimitiveType::kRing || partner == PrimitiveType::kTube;
  switch (type) {
    case PrimitiveType::kHook:
    case PrimitiveType::kRing:
      // wire diameter along a rod / inside a hoop
      return 2 * Shape("thickness");
    case PrimitiveType::kRod:
      return partner_is_radius ? Shape("radius") : 2 * Shape("radius");
    case PrimitiveType::kTube:
      return partner_is_radius ? Shape("inner_radius") + Shape("thickness") : Shape("length");
    case PrimitiveType::kClip:
      return Shape("thickness");  // the clip's jaw, not its width, sits on the partner
    case PrimitiveType::kEdge:
      return Shape("thickness");
    case PrimitiveType::kSurface:
    case PrimitiveType::kHemisphere:
      return 0;
  }
  return 0;
}

const Primitive* Part::Find(const std::string& n) const {
  for (const auto& p : primitives)
    if (p.name == n) return &p;
  return nullptr;
}

Eigen::Isometry3d ConnectorFrame(const Primitive& p, const std::vector<double>& s) {
  const Eigen::Matrix4d local = internal::LocalConnectorFrame<double>(p, s.data());
  Eigen::Isometry3d m;
  m.matrix() = ToIsometry(p.frame).matrix() * local;
  return m;
}

const char* ToString(PrimitiveType t) {
  switch (t) {
    case PrimitiveType::kHook:
      return "hook";
    case PrimitiveType::kRod:
      return "rod";
    case PrimitiveType::kRing:
      return "ring";
    case PrimitiveType::kTube:
      return "tube";
    case PrimitiveType::kHemisphere:
      return "hemisphere";
    case PrimitiveType::kClip:
      return "clip";
    case PrimitiveType::kEdge:
      return "edge";
    case PrimitiveType::kSurface:
      return "surface";
  }
  return "?";
}

namespace {

using PT = PrimitiveType;

struct Offset {
  Eigen::Vector3d euler;
  std::vector<int> flip_axes;
};

// PARTS.md §2.2: alignment frame and flip axes per ordered class-name key.
Offset LookUp(const std::string& key) {
  const auto us = key.find('_');
  const std::string k1 = key.substr(0, us), k2 = key.substr(us + 1);
  auto in = [](const std::string& k, std::initializer_list<const char*> set) {
    for (const char* s : set)
      if (k == s) return true;
    return false;
  };
  if ((k1 == "RodCtl" && k2 == "RingCtl") || (k1 == "RingCtl" && k2 == "RodCtl")) return {{0, 0, 90}, {2}};
  const auto rodhook = {"Rod", "RodCtl", "Hook", "HookFlex"};
  const auto hookring = {"Hook", "HookFlex", "Ring", "RingFlex", "RingCtl"};
  if ((in(k1, rodhook) && in(k2, hookring)) || (in(k2, rodhook) && in(k1, hookring))) return {{180, 0, 90}, {2}};
  if (key == "Rod_Tube" || key == "Tube_Rod") return {{0, 90, 0}, {}};
  if (key == "Rod_TubeCtl" || key == "TubeCtl_Rod") return {{0, 0, 0}, {}};
  const auto hookring4 = {"Hook", "HookFlex", "Ring", "RingFlex"};
  if ((k1 == "Tube" && in(k2, hookring4)) || (k2 == "Tube" && in(k1, hookring4))) return {{0, 0, 90}, {2}};
  if (key == "Hook_Edge" || key == "HookFlex_Edge") return {{90, 0, -90}, {2}};
  if (key == "Edge_Hook" || key == "Edge_HookFlex") return {{-90, 0, 90}, {2}};
  if (key == "Edge_Clip") return {{0, -90, -90}, {1, 2}};
  if (key == "Clip_Edge") return {{0, 90, 90}, {1, 2}};
  if (in(key, {"Clip_Rod", "Rod_Clip", "Clip_RodCtl", "RodCtl_Clip"})) return {{0, 180, 0}, {1}};
  if (key == "Surface_Surface") return {{0, 0, 0}, {0}};
  return {{0, 0, 0}, {}};
}

}  // namespace

Eigen::Matrix3d AlignmentOffset(const std::string& key, bool flip) {
  Offset o = LookUp(key);
  // PARTS.md §2.1: "flip" maps each flip axis 0 -> 180, 180 -> 0, else negates.
  if (flip)
    for (int ax : o.flip_axes) {
      double& v = o.euler[ax];
      if (v == 0)
        v = 180;
      else if (v == 180)
        v = 0;
      else
        v = -v;
    }
  return EulerToRotation(o.euler);
}

bool CanConnect(PrimitiveType a, PrimitiveType b) {
  auto pair = [&](PT x, PT y) { return (a == x && b == y) || (a == y && b == x); };
  return pair(PT::kHook, PT::kRod) || pair(PT::kHook, PT::kRing) || pair(PT::kHook, PT::kHook) ||
         pair(PT::kHook, PT::kTube) || pair(PT::kHook, PT::kEdge) || pair(PT::kRing, PT::kRod) ||
         pair(PT::kRing, PT::kRing) || pair(PT::kRing, PT::kTube) || pair(PT::kRod, PT::kTube) ||
         pair(PT::kTube, PT::kTube) || pair(PT::kRod, PT::kClip) || pair(PT::kClip, PT::kEdge) ||
         pair(PT::kSurface, PT::kSurface) || pair(PT::kHemisphere, PT::kSurface);
}

namespace {

PrimitiveType ParseType(const std::string& file, const YAML::Node& n) {
  const std::string s = internal::AsString(file, n, "primitive type");
  static const std::map<std::string, PT> kTypes{{"hook", PT::kHook},
                                                {"rod", PT::kRod},
                                                {"ring", PT::kRing},
                                                {"tube", PT::kTube},
                                                {"hemisphere", PT::kHemisphere},
                                                {"clip", PT::kClip},
                                                {"edge", PT::kEdge},
                                                {"surface", PT::kSurface}};
  auto it = kTypes.find(s);
  if (it == kTypes.end()) internal::Fail(file, n, "unknown primitive type '" + s + "'");
  return it->second;
}

const std::map<PT, std::vector<std::string>>& RequiredShape() {
  static const std::map<PT, std::vector<std::string>> k{
      {PT::kHook, {"arc_radius", "arc_angle", "thickness"}},
      {PT::kRing, {"arc_radius", "thickness"}},
      {PT::kRod, {"length", "radius"}},
      {PT::kTube, {"length", "inner_radius", "thickness"}},
      {PT::kClip, {"width", "height", "thickness", "base_dist", "gap"}},
      {PT::kEdge, {"length", "width", "thickness"}},
      {PT::kSurface, {"length", "width"}},
      {PT::kHemisphere, {"radius"}}};
  return k;
}

Eigen::Vector3d AsVector(const std::string& file, const YAML::Node& n, const std::string& what) {
  if (!n.IsSequence() || n.size() != 3) internal::Fail(file, n, what + " must be [x, y, z]");
  return {internal::AsDouble(file, n[0], what), internal::AsDouble(file, n[1], what),
          internal::AsDouble(file, n[2], what)};
}

// fit: {select: [[x0,y0,z0],[x1,y1,z1]], up: [x,y,z], down: [x,y,z], shift: [x,y,z]} — the
// primitive frame derived from the mesh vertices inside the box (hook/ring:
// FitArc + ArcFrame; rod: FitAxis + AxisFrame; fabatlas/assembly/fit_primitive.h).
// Remembered per (mesh, arguments): generated families reload the library.
Frame FitFrame(const std::string& file, const YAML::Node& n, const Primitive& p, const std::string& mesh) {
  using internal::Fail;
  if (!n.IsMap() || !n["select"] || !n["select"].IsSequence() || n["select"].size() != 2)
    Fail(file, n, "fit needs select: [[xmin, ymin, zmin], [xmax, ymax, zmax]]");
  for (const auto& kv : n)
    if (const auto k = kv.first.as<std::string>(); k != "select" && k != "up" && k != "down" && k != "shift")
      Fail(file, kv.first, "unknown key '" + k + "' in fit (expected select, up, down, shift)");
  const Eigen::Vector3d lo = AsVector(file, n["select"][0], "select"), hi = AsVector(file, n["select"][1], "select");
  const Eigen::Vector3d up = n["up"] ? AsVector(file, n["up"], "up") : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d down =
      n["down"] ? AsVector(file, n["down"], "down") : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
  const bool arc = p.type == PrimitiveType::kHook || p.type == PrimitiveType::kRing;
  if (!arc && p.type != PrimitiveType::kRod) Fail(file, n, "fit is implemented for hooks, rings and rods");
  const double arc_angle = p.type == PrimitiveType::kHook ? p.Shape("arc_angle") : 360;
  std::ostringstream key;
  key.precision(17);
  key << mesh << "|" << static_cast<int>(p.type) << "|" << arc_angle << "|" << lo.transpose() << "|" << hi.transpose()
      << "|" << up.transpose() << "|" << down.transpose() << "|"
      << (n["shift"] ? AsVector(file, n["shift"], "shift") : Eigen::Vector3d::Zero()).transpose();
  static std::mutex mutex;
  static std::map<std::string, Frame> known;
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = known.find(key.str()); it != known.end()) return it->second;
  }
  Frame f;
  try {
    const auto points = MeshPointsIn(mesh, lo, hi);
    f = arc ? ArcFrame(FitArc(points), arc_angle, down) : AxisFrame(FitAxis(points), up);
  } catch (const InputError& e) {
    Fail(file, n, "primitive '" + p.name + "': " + e.what());
  }
  // shift: a translation (mm, part frame) added to the fitted frame, e.g.
  // a turnbuckle hook moved out by half the extension.
  if (n["shift"]) f.position += AsVector(file, n["shift"], "shift");
  std::lock_guard<std::mutex> lock(mutex);
  return known[key.str()] = f;
}

}  // namespace

PartLibrary LoadPartLibrary(const std::string& file, const std::string& mesh_dir) {
  using namespace internal;
  const YAML::Node root = LoadYamlFile(file);
  if (!root.IsMap() || !root["parts"] || !root["parts"].IsMap()) Fail(file, root, "expected a map 'parts:'");
  PartLibrary lib;
  for (const auto& kv : root["parts"]) {
    Part part;
    part.name = AsString(file, kv.first, "part name");
    const YAML::Node& n = kv.second;
    if (!n.IsMap()) Fail(file, n, "part '" + part.name + "' must be a map");
    for (const auto& key : n)
      if (const auto k = key.first.as<std::string>();
          k != "mesh" && k != "mass" && k != "centre_of_mass" && k != "primitives")
        Fail(file, key.first, "unknown key '" + k + "' in part '" + part.name + "'");
    if (n["mesh"]) {
      part.mesh = AsString(file, n["mesh"], "mesh");
      const std::string path = (std::filesystem::path(mesh_dir) / part.mesh).string();
      const MassProperties mp = ComputeMassProperties(path);
      part.mass = mp.volume_mm3;
      part.centre_of_mass = mp.centre_of_mass;
    }
    if (n["mass"]) part.mass = AsDouble(file, n["mass"], "mass");
    if (n["centre_of_mass"]) {
      const YAML::Node c = n["centre_of_mass"];
      if (!c.IsSequence() || c.size() != 3) Fail(file, c, "centre_of_mass must be [x,y,z]");
      for (int i = 0; i < 3; ++i) part.centre_of_mass[i] = AsDouble(file, c[i], "centre_of_mass");
    }
    if (part.mass < 0) Fail(file, n, "part '" + part.name + "' has negative mass");
    const YAML::Node prims = n["primitives"];
    if (!prims || !prims.IsMap()) Fail(file, n, "part '" + part.name + "' needs a map 'primitives:'");
    for (const auto& pk : prims) {
      Primitive p;
      p.name = AsString(file, pk.first, "primitive name");
      const YAML::Node& pn = pk.second;
      if (!pn.IsMap() || !pn["type"]) Fail(file, pn, "primitive '" + p.name + "' needs 'type'");
      p.type = ParseType(file, pn["type"]);
      for (const auto& e : pn) {
        const std::string k = e.first.as<std::string>();
        if (k == "type") continue;
        if (k == "frame")
          p.frame = AsFrame(file, e.second, "frame");
        else if (k == "fit")
          continue;  // after the shape, below
        else if (k == "closed")
          p.closed = e.second.as<bool>();
        else if (k == "flex")
          p.flex = e.second.as<bool>();
        else if (k == "clamped")
          p.clamped = e.second.as<bool>();
        else if (k == "ctl")
          p.ctl = e.second.as<bool>();
        else if (k == "blocked") {  // "min" / "max" / "both": that end of the slide parameter is blocked
          const std::string v = AsString(file, e.second, "blocked");
          if (v == "min" || v == "both") p.blocked_min = true;
          if (v == "max" || v == "both") p.blocked_max = true;
          if (v != "min" && v != "max" && v != "both") Fail(file, e.second, "blocked must be 'min', 'max' or 'both'");
        } else if (k == "range") {  // hook θ range [min, max] (default [0, arc_angle])
          if (!e.second.IsSequence() || e.second.size() != 2) Fail(file, e.second, "range must be [min, max]");
          p.shape["theta_min"] = AsDouble(file, e.second[0], "range");
          p.shape["theta_max"] = AsDouble(file, e.second[1], "range");
        } else
          p.shape[k] = AsDouble(file, e.second, "shape parameter '" + k + "'");
      }
      for (const auto& req : RequiredShape().at(p.type))
        if (!p.shape.count(req))
          Fail(file, pn, std::string(ToString(p.type)) + " '" + p.name + "' lacks '" + req + "'");
      if (p.type == PT::kRing) p.closed = true;  // rings are always closed for connecting (FabHacks, 4.1)
      if (pn["fit"]) {
        if (pn["frame"]) Fail(file, pn["fit"], "primitive '" + p.name + "' has both 'frame' and 'fit'");
        if (part.mesh.empty()) Fail(file, pn["fit"], "primitive '" + p.name + "': 'fit' needs the part's 'mesh'");
        p.frame = FitFrame(file, pn["fit"], p, (std::filesystem::path(mesh_dir) / part.mesh).string());
      }
      if ((p.type == PT::kHook || p.type == PT::kRing) && p.CriticalDimension() <= 0)
        Fail(file, pn, "primitive '" + p.name + "' has thickness >= arc_radius");
      part.primitives.push_back(p);
    }
    lib.parts[part.name] = part;
  }
  return lib;
}

std::vector<std::string> PartLibraryMeshes(const std::string& file) {
  using namespace internal;
  const YAML::Node root = LoadYamlFile(file);
  if (!root.IsMap() || !root["parts"] || !root["parts"].IsMap()) Fail(file, root, "expected a map 'parts:'");
  std::set<std::string> names;
  for (const auto& kv : root["parts"])
    if (kv.second.IsMap() && kv.second["mesh"]) names.insert(AsString(file, kv.second["mesh"], "mesh"));
  return {names.begin(), names.end()};
}

}  // namespace fabatlas::assembly
