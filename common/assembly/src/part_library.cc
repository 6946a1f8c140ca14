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
  const ParamKind open = closed || clamped ? ParamKind::kBoundedAndClamped : ParamKind::kBoundedAndOpen;
  switch (type) {
    case PrimitiveType::kRod:
      return {{"t", 0, 1, open}, {"phi", 45, 135, ParamKind::kBoundedAndClamped}};
    case PrimitiveType::kHook: {
      // theta_max (optional) overrides the arc angle as the range of theta.
      const double tmax = shape.count("theta_max") ? shape.at("theta_max") : Shape("arc_angle");
      std::vector<ParamSpec> p{{"theta", 0, tmax, open}};
      if (flex) p.push_back({"phi", 45, 135, ParamKind::kBoundedAndClamped});
      return p;
    }
    case PrimitiveType::kRing: {
      std::vector<ParamSpec> p{{"theta", 0, 360, ParamKind::kUnbounded}};
      if (flex) p.push_back({"phi", 30, 150, ParamKind::kBoundedAndClamped});
      return p;
    }
    case PrimitiveType::kTube:
      return {{"t", 0, 1, open}, {"theta", 0, 360, ParamKind::kUnbounded}};
    case PrimitiveType::kClip:
      return {{"t", 0, 1, ParamKind::kBoundedAndClamped}};
    case PrimitiveType::kEdge:
      return {{"t", 0, 1, open}};
    case PrimitiveType::kSurface:
      return {{"t1", 0, 1, open}, {"t2", 0, 1, open}, {"spin", 0, 360, ParamKind::kUnbounded}};
    case PrimitiveType::kHemisphere:
      return {{"theta", 0, 360, ParamKind::kUnbounded},
              {"phi", 90, 270, ParamKind::kBoundedAndClamped},
              {"spin", 0, 360, ParamKind::kUnbounded}};
  }
  return {};
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
      return Shape("arc_radius") - Shape("thickness");
    case PrimitiveType::kClip:
      return Shape("gap");
    case PrimitiveType::kHemisphere:
      return 0;
  }
  return 0;
}

double Primitive::OccupiedSize(PrimitiveType partner) const {
  const bool partner_is_radius = partner == PrimitiveType::kHook || partner == PrimitiveType::kRing ||
                                 partner == PrimitiveType::kTube;
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
    case PrimitiveType::kHook: return "hook";
    case PrimitiveType::kRod: return "rod";
    case PrimitiveType::kRing: return "ring";
    case PrimitiveType::kTube: return "tube";
    case PrimitiveType::kHemisphere: return "hemisphere";
    case PrimitiveType::kClip: return "clip";
    case PrimitiveType::kEdge: return "edge";
    case PrimitiveType::kSurface: return "surface";
  }
  return "?";
}

namespace {

using PT = PrimitiveType;
bool IsRodHookRing(PT t) { return t == PT::kRod || t == PT::kHook || t == PT::kRing; }

struct Offset {
  Eigen::Vector3d euler;
  std::vector<int> flip_axes;
  bool found;
};

// EXAMPLES.md alignment table for the ordered pair (a, b).
Offset LookUp(const Primitive& a, const Primitive& b) {
  const PT ta = a.type, tb = b.type;
  if (ta == PT::kRod && a.ctl && tb == PT::kRing && b.ctl) return {{0, 0, 90}, {2}, true};
  if (IsRodHookRing(ta) && IsRodHookRing(tb)) return {{180, 0, 90}, {2}, true};
  if (ta == PT::kRod && tb == PT::kTube) return {b.ctl ? Eigen::Vector3d(0, 0, 0) : Eigen::Vector3d(0, 90, 0), {}, true};
  if (ta == PT::kTube && (tb == PT::kHook || tb == PT::kRing)) return {{0, 0, 90}, {2}, true};
  if (ta == PT::kHook && tb == PT::kEdge) return {{90, 0, -90}, {2}, true};
  if (ta == PT::kEdge && tb == PT::kHook) return {{-90, 0, 90}, {2}, true};
  if (ta == PT::kEdge && tb == PT::kClip) return {{0, -90, -90}, {1, 2}, true};
  if (ta == PT::kClip && tb == PT::kEdge) return {{0, 90, 90}, {1, 2}, true};
  if (ta == PT::kClip && tb == PT::kRod) return {{0, 180, 0}, {1}, true};
  if (ta == PT::kSurface && tb == PT::kSurface) return {{0, 0, 0}, {0}, true};
  return {{0, 0, 0}, {}, false};
}

Eigen::Matrix3d Apply(Offset o, bool flip) {
  if (flip)
    for (int ax : o.flip_axes) {
      double& v = o.euler[ax];
      if (v == 0) v = 180;
      else if (v == 180) v = 0;
      else v = -v;
    }
  return EulerToRotation(o.euler);
}

}  // namespace

Eigen::Matrix3d AlignmentOffset(const Primitive& a, const Primitive& b, bool flip) {
  const Offset ab = LookUp(a, b);
  if (ab.found) return Apply(ab, flip);
  const Offset ba = LookUp(b, a);
  if (ba.found) return Apply(ba, flip).transpose();  // P_b M_b A_ba = P_a M_a
  return Eigen::Matrix3d::Identity();
}

bool CanConnect(PrimitiveType a, PrimitiveType b) {
  auto pair = [&](PT x, PT y) { return (a == x && b == y) || (a == y && b == x); };
  return pair(PT::kHook, PT::kRod) || pair(PT::kHook, PT::kRing) || pair(PT::kHook, PT::kHook) ||
         pair(PT::kHook, PT::kTube) || pair(PT::kHook, PT::kEdge) || pair(PT::kRing, PT::kRod) ||
         pair(PT::kRing, PT::kRing) || pair(PT::kRing, PT::kTube) || pair(PT::kRod, PT::kTube) ||
         pair(PT::kRod, PT::kClip) || pair(PT::kClip, PT::kEdge) || pair(PT::kSurface, PT::kSurface) ||
         pair(PT::kHemisphere, PT::kSurface);
}

namespace {

PrimitiveType ParseType(const std::string& file, const YAML::Node& n) {
  const std::string s = internal::AsString(file, n, "primitive type");
  static const std::map<std::string, PT> kTypes{{"hook", PT::kHook},   {"rod", PT::kRod},
                                                {"ring", PT::kRing},   {"tube", PT::kTube},
                                                {"hemisphere", PT::kHemisphere}, {"clip", PT::kClip},
                                                {"edge", PT::kEdge},   {"surface", PT::kSurface}};
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
  return {internal::AsDouble(file, n[0], what), internal::AsDouble(file, n[1], what), internal::AsDouble(file, n[2], what)};
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
  const Eigen::Vector3d down = n["down"] ? AsVector(file, n["down"], "down") : Eigen::Vector3d(-Eigen::Vector3d::UnitZ());
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
      if (const auto k = key.first.as<std::string>(); k != "mesh" && k != "mass" && k != "centre_of_mass" &&
                                                      k != "primitives")
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
        if (k == "frame") p.frame = AsFrame(file, e.second, "frame");
        else if (k == "fit") continue;  // after the shape, below
        else if (k == "closed") p.closed = e.second.as<bool>();
        else if (k == "flex") p.flex = e.second.as<bool>();
        else if (k == "clamped") p.clamped = e.second.as<bool>();
        else if (k == "ctl") p.ctl = e.second.as<bool>();
        else p.shape[k] = AsDouble(file, e.second, "shape parameter '" + k + "'");
      }
      for (const auto& req : RequiredShape().at(p.type))
        if (!p.shape.count(req)) Fail(file, pn, std::string(ToString(p.type)) + " '" + p.name + "' lacks '" + req + "'");
      if (p.type == PT::kRing) p.closed = true;  // rings are always closed (FabHacks, 4.1)
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
