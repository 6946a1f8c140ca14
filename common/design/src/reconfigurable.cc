#include "reconfigurable.h"

#include <cmath>
#include <cstdio>
#include <map>

#include "fabatlas/exact_decimal.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/stopwatch.h"
#include "fabatlas/swept/swept_volume.h"
#include "exact_boolean.h"
#include "operations.h"

namespace fabatlas::design {
namespace {

using swept::Quaternion;
using swept::RigidMotion;
using swept::Transform;

double Number(const Argument& a, Scope& scope) {
  double v = Expression(a.text, scope, a.place).Evaluate();
  if (!std::isfinite(v))
    throw SampleFailure(kNoGeometry, a.place.str() + ": motion value evaluates to " + ExactDecimal(v));
  return v;
}

swept::Vec3 Point3(const Argument& a, Scope& scope) {
  return {Number(a.items[0], scope), Number(a.items[1], scope), Number(a.items[2], scope)};
}

// Unit quaternion of an orthonormal rotation matrix (Shepperd's method: the
// largest of w, x, y, z is computed from the trace, the others from it).
Quaternion FromMatrix(const std::array<std::array<double, 3>, 3>& m) {
  const double tr = m[0][0] + m[1][1] + m[2][2];
  Quaternion q;
  if (tr > 0) {
    const double s = 2 * std::sqrt(1 + tr);
    q = {0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s};
  } else if (m[0][0] > m[1][1] && m[0][0] > m[2][2]) {
    const double s = 2 * std::sqrt(1 + m[0][0] - m[1][1] - m[2][2]);
    q = {(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s};
  } else if (m[1][1] > m[2][2]) {
    const double s = 2 * std::sqrt(1 + m[1][1] - m[0][0] - m[2][2]);
    q = {(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s};
  } else {
    const double s = 2 * std::sqrt(1 + m[2][2] - m[0][0] - m[1][1]);
    q = {(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s};
  }
  return q;
}

// The motion that holds pose f for all t.
RigidMotion Constant(const Transform& f) {
  RigidMotion m;
  m.translation = {f.translation, f.translation, f.translation, f.translation};
  m.rotation_keys = {FromMatrix(f.rotation)};
  return m;
}

std::string Canonical(const RigidMotion& m) {
  std::string s = "T=";
  for (const auto& p : m.translation)
    for (double x : p) s += ExactDecimal(x) + ",";
  s += ";R=";
  for (const auto& q : m.rotation_keys)
    s += ExactDecimal(q.w) + "," + ExactDecimal(q.x) + "," + ExactDecimal(q.y) + "," + ExactDecimal(q.z) + ",";
  s += ";P=";
  for (double x : m.pivot) s += ExactDecimal(x) + ",";
  return s;
}

RigidMotion Resolve(const ObjectMotion& om, Scope& scope) {
  RigidMotion m;
  if (om.has_translation) {
    std::vector<swept::Vec3> p;
    for (const auto& item : om.translation.items) p.push_back(Point3(item, scope));
    if (p.size() == 2) {
      m = RigidMotion::Line(p[0], p[1]);
    } else {
      for (int k = 0; k < 4; ++k) m.translation[k] = p[k];
    }
  }
  if (om.has_rotation) {
    for (const auto& key : om.rotation.items) {
      const swept::Vec3 axis = Point3(key, scope);
      const double degrees = Number(key.items[3], scope);
      const bool zero_axis = axis[0] == 0 && axis[1] == 0 && axis[2] == 0;
      if (zero_axis && degrees != 0)
        throw SampleFailure(kNoGeometry, key.place.str() + ": a rotation key turns about a zero axis");
      m.rotation_keys.push_back(zero_axis ? Quaternion{} : Quaternion::FromAxisAngle(axis, degrees));
    }
  }
  if (om.has_pivot) m.pivot = Point3(om.pivot, scope);
  return m;
}

}  // namespace

std::size_t ObjectIndex(const Design& design, const std::string& name) {
  for (std::size_t i = 0; i < design.objects.size(); ++i)
    if (design.objects[i].name == name) return i;
  throw InputError(design.file.string() + ": unknown object '" + name + "'");
}

std::vector<ResolvedTransition> ResolveTransitions(const Design& design, Scope& scope) {
  const std::size_t n = design.objects.size();
  std::map<std::string, std::vector<Transform>> pose;  // state -> object poses
  if (!design.states.empty()) pose[design.states.front()] = std::vector<Transform>(n);
  std::vector<ResolvedTransition> out;
  for (const Transition& t : design.transitions) {
    ResolvedTransition r;
    r.name = t.name;
    const std::vector<Transform> from = pose.at(t.from);  // linted: reached earlier
    for (std::size_t i = 0; i < n; ++i) r.motions.push_back(Constant(from[i]));
    for (const ObjectMotion& om : t.motions) r.motions[ObjectIndex(design, om.object)] = Resolve(om, scope);
    if (!pose.count(t.to)) {
      std::vector<Transform> to;
      for (const auto& m : r.motions) to.push_back(m.At(1.0));
      pose[t.to] = std::move(to);
    }
    for (const auto& m : r.motions) r.canonical.push_back(Canonical(m));
    out.push_back(std::move(r));
  }
  return out;
}

mesh::TriangleMesh SweptCutter(const geometry::Solid& moving, const swept::RigidMotion& f_moving,
                               const swept::RigidMotion& f_frame, double offset, int time_steps,
                               const geometry::GridSpec& g, const SourcePlace& place,
                               swept::SweptVolumeSummary* summary) {
  if (!(offset >= 0)) throw SampleFailure(kNoGeometry, place.str() + ": carve_swept offset must be >= 0");
  if (time_steps < 2 || time_steps > 100000)
    throw SampleFailure(kNoGeometry, place.str() + ": carve_swept time_steps must be in [2, 100000]");
  if (moving.empty()) throw SampleFailure(kNoGeometry, place.str() + ": carve_swept: the moving object is empty");
  const mesh::TriangleMesh body = moving.ToMesh();
  swept::SweptVolumeOptions o;
  o.voxel_size = g.voxel_size;
  o.offset = offset;
  o.time_steps = time_steps;
  o.max_active_voxels = g.max_active_voxels;
  // Reconfigurables, Eq. 4: the moving object observed in the frame object's body
  // coordinates, f_frame^-1 o f_moving.
  const auto poses = swept::SamplePoses(
      body, [&](double t) { return f_frame.At(t).Inverse().Compose(f_moving.At(t)); }, o);
  const swept::SweptDistanceField field = swept::ComputeSweptDistance(body, poses, o, summary);
  return field.Surface(offset);
}

geometry::Solid CarveSwept(const geometry::Solid& target, const geometry::Solid& moving,
                           const swept::RigidMotion& f_moving, const swept::RigidMotion& f_frame, double offset,
                           int time_steps, const geometry::GridSpec& g, const SourcePlace& place, bool exact,
                           CarveSweptSummary* summary) {
  CarveSweptSummary s;
  Stopwatch watch;
  const mesh::TriangleMesh cutter = SweptCutter(moving, f_moving, f_frame, offset, time_steps, g, place, nullptr);
  s.sweep_seconds = watch.Seconds();
  s.cutter_triangles = cutter.triangles.size();
  geometry::Solid out = target;
  watch.Restart();
  if (!target.empty() && !cutter.triangles.empty()) {
    if (exact) {
      // Reconfigurables, Eq. 4 with an exact subtraction: the target's level-set
      // surface minus the cutter surface by CGAL corefinement. Both are
      // meshed on the design's grid, so the cutter is as dense as the
      // target and is subtracted as it is (docs/swept.md "Carving").
      const mesh::TriangleMesh a = target.ToMesh();
      s.target_triangles = a.triangles.size();
      try {
        out = SolidOfExactResult(ExactMeshBoolean("difference", {a, cutter}), g);
      } catch (const SampleFailure& e) {
        throw SampleFailure(e.type(), place.str() + ": carve_swept: " + e.what() +
                                          " (operand 0: the carved object, 1: the swept cutter)");
      }
    } else {
      out = geometry::Difference(target, geometry::FromMesh(g, cutter));
    }
  }
  s.subtract_seconds = watch.Seconds();
  if (summary) *summary = s;
  return out;
}

}  // namespace fabatlas::design
