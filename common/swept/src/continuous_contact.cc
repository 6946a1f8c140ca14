// Conservative advancement between two rigidly moving triangle meshes with
// FCL distance queries. See continuous_contact.h.
#include "fabatlas/swept/continuous_contact.h"

#include <fcl/fcl.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "fabatlas/error.h"

namespace fabatlas::swept {

struct ContinuousContact::Impl {
  using Model = fcl::BVHModel<fcl::OBBRSSd>;
  std::vector<RigidMotion> motions;
  std::vector<std::shared_ptr<Model>> models;
  std::vector<double> speed;
};

namespace {

fcl::Transform3d ToFcl(const Transform& f) {
  fcl::Transform3d x = fcl::Transform3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) x.linear()(r, c) = f.rotation[r][c];
    x.translation()[r] = f.translation[r];
  }
  return x;
}

}  // namespace

ContinuousContact::ContinuousContact(const std::vector<MovingPart>& parts) : impl_(std::make_unique<Impl>()) {
  for (std::size_t p = 0; p < parts.size(); ++p) {
    const auto& m = parts[p].mesh;
    if (m.vertices.empty() || m.triangles.empty()) {
      throw InputError("continuous contact: part " + std::to_string(p) + ": mesh has no triangles");
    }
    std::vector<fcl::Vector3d> points;
    points.reserve(m.vertices.size());
    double radius = 0;
    const Vec3& pivot = parts[p].motion.pivot;
    for (const auto& v : m.vertices) {
      points.emplace_back(v[0], v[1], v[2]);
      radius = std::max(radius, std::hypot(v[0] - pivot[0], v[1] - pivot[1], v[2] - pivot[2]));
    }
    std::vector<fcl::Triangle> triangles;
    triangles.reserve(m.triangles.size());
    for (const auto& t : m.triangles) triangles.emplace_back(t[0], t[1], t[2]);
    auto model = std::make_shared<Impl::Model>();
    model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(points.size()));
    model->addSubModel(points, triangles);
    model->endModel();
    impl_->models.push_back(model);
    impl_->motions.push_back(parts[p].motion);
    impl_->speed.push_back(parts[p].motion.SpeedBound(radius));
  }
}

ContinuousContact::~ContinuousContact() = default;

double ContinuousContact::SpeedBound(int p) const { return impl_->speed.at(p); }

double ContinuousContact::Distance(int a, int b, double t) const {
  fcl::CollisionObjectd oa(impl_->models.at(a), ToFcl(impl_->motions[a].At(t)));
  fcl::CollisionObjectd ob(impl_->models.at(b), ToFcl(impl_->motions[b].At(t)));
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  fcl::distance(&oa, &ob, request, result);
  return result.min_distance;
}

ContinuousContact::Closest ContinuousContact::Nearest(int a, int b, double t) const {
  fcl::CollisionObjectd oa(impl_->models.at(a), ToFcl(impl_->motions[a].At(t)));
  fcl::CollisionObjectd ob(impl_->models.at(b), ToFcl(impl_->motions[b].At(t)));
  fcl::DistanceRequestd request;
  request.enable_nearest_points = true;
  fcl::DistanceResultd result;
  fcl::distance(&oa, &ob, request, result);
  Closest c;
  c.distance = result.min_distance;
  for (int k = 0; k < 3; ++k) c.point_a[k] = result.nearest_points[0][k], c.point_b[k] = result.nearest_points[1][k];
  return c;
}

ContactSearch ContinuousContact::Advance(int a, int b, double from, double to,
                                         const ContactSearchOptions& options) const {
  ContactSearch s;
  const double direction = to >= from ? 1.0 : -1.0;
  const double speed = impl_->speed.at(a) + impl_->speed.at(b);
  double t = from;
  while (true) {
    const double d = Distance(a, b, t);
    ++s.steps;
    if (d <= options.tolerance) {
      s.contact = true;
      s.t = t;
      return s;
    }
    if (speed <= 0) return s;  // neither moves: apart throughout
    if (s.steps >= options.max_steps) {
      s.contact = true;
      s.step_limit = true;
      s.t = t;
      return s;
    }
    // Apart for at least (d - tolerance / 2) / speed: no point moves
    // faster than its bound, so the gap cannot close sooner. Stepping to
    // where the gap may have shrunk to tolerance / 2 makes the next query
    // stop there at the latest.
    const double next = t + direction * (d - 0.5 * options.tolerance) / speed;
    if (direction * (next - to) > 0) {
      // Past the end: the last stretch [t, to] is shorter than the safe step.
      return s;
    }
    t = next;
  }
}

}  // namespace fabatlas::swept
