// Energy, chain rule and line search of collision resolution
// (Reconfigurables, Secs. 6.2–6.6). See contact_energy.h.
#include "contact_energy.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>

#include "fabatlas/error.h"

namespace fabatlas::design {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using KPoint = Kernel::Point_3;
using Triangle = Kernel::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

using swept::Transform;

Vec3 Sub(const Vec3& p, const Vec3& q) { return {p[0] - q[0], p[1] - q[1], p[2] - q[2]}; }
double Dot(const Vec3& p, const Vec3& q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; }

// Signed distance to a closed mesh near its surface (negative inside): the
// distance to the closest triangle, signed by that triangle's outward
// normal. Good for points within a fraction of a feature of the surface,
// which is all the chain rule asks (a point on the surface at u, against
// the surface at u + h).
class NearSurface {
 public:
  explicit NearSurface(const mesh::TriangleMesh& m) {
    triangles_.reserve(m.triangles.size());
    for (const auto& t : m.triangles) {
      const auto& p = m.vertices[t[0]];
      const auto& q = m.vertices[t[1]];
      const auto& r = m.vertices[t[2]];
      triangles_.emplace_back(KPoint(p[0], p[1], p[2]), KPoint(q[0], q[1], q[2]), KPoint(r[0], r[1], r[2]));
    }
    tree_ = std::make_unique<Tree>(triangles_.cbegin(), triangles_.cend());
    tree_->accelerate_distance_queries();
  }
  double SignedDistance(const Vec3& x) const {
    const KPoint q(x[0], x[1], x[2]);
    const auto [closest, id] = tree_->closest_point_and_primitive(q);
    const double d = std::sqrt(CGAL::to_double(CGAL::squared_distance(q, closest)));
    const Kernel::Vector_3 n = CGAL::normal(id->vertex(0), id->vertex(1), id->vertex(2));
    return (q - closest) * n < 0 ? -d : d;
  }

 private:
  std::vector<Triangle> triangles_;
  std::unique_ptr<Tree> tree_;
};

bool SameMesh(const mesh::TriangleMesh& x, const mesh::TriangleMesh& y) {
  return x.vertices == y.vertices && x.triangles == y.triangles;
}

}  // namespace

std::vector<Freedom> Freedoms(const Design& design, const ResolutionOptions& options) {
  std::vector<Freedom> out;
  for (const auto& p : design.exposed) {
    const bool named =
        std::find(options.parameters.begin(), options.parameters.end(), p.name) != options.parameters.end();
    if (!options.parameters.empty() && !named) continue;
    if (p.kind != ParameterKind::kReal) {
      if (named)
        throw InputError(design.file.string() + ": parameter '" + p.name +
                         "' is not real; only real parameters can be resolved");
      continue;
    }
    if (p.max > p.min) out.push_back({p.name, p.min, p.max});
  }
  for (const auto& name : options.parameters)
    if (!design.FindExposed(name)) throw InputError(design.file.string() + ": unknown parameter '" + name + "'");
  return out;
}

double ContactState::PairEnergy(int a, int b) const {
  double e = 0;
  for (const auto& p : pairs)
    if (p.a == a && p.b == b) e += p.normal.energy;
  return e;
}

ContactState EvaluateContacts(const Design& design, const Point& u, int time_steps, SubtreeCache* cache) {
  StateGraph graph;
  EvaluateOptions o;
  o.cache = cache;
  o.run_checks = false;
  o.keep_solid = false;
  o.state_graph = &graph;
  const SampleResult r = EvaluateSample(design, u, o);
  if (!r.failure.empty() || graph.objects.size() != design.objects.size()) {
    ContactState s;
    s.u = u;
    s.failure = r.failure.empty() ? std::string(kNoGeometry) : r.failure;
    s.reason = r.failure_reason;
    s.energy = std::numeric_limits<double>::infinity();
    return s;
  }
  return ContactsOf(u, std::move(graph), time_steps);
}

StateGraphResult EvaluateWithChecks(const Design& design, const Point& u, SubtreeCache* cache) {
  StateGraphResult out;
  EvaluateOptions o;
  o.cache = cache;
  o.keep_solid = false;
  o.repair_collisions = false;
  o.state_graph = &out.graph;
  out.sample = EvaluateSample(design, u, o);
  return out;
}

ContactState ContactsOf(const Point& u, StateGraph graph, int time_steps) {
  ContactState s;
  s.u = u;
  s.graph = std::move(graph);
  if (s.graph.objects.empty()) {
    s.failure = kNoGeometry;
    s.energy = std::numeric_limits<double>::infinity();
    return s;
  }
  s.has_geometry = true;
  swept::ContactNormalOptions co;
  co.time_steps = time_steps;
  co.first_contact = false;
  for (std::size_t k = 0; k < s.graph.transitions.size(); ++k) {
    std::vector<swept::MovingPart> parts;
    for (std::size_t i = 0; i < s.graph.objects.size(); ++i)
      parts.push_back({s.graph.objects[i], s.graph.transitions[k].motions[i]});
    for (int a = 0; a < static_cast<int>(parts.size()); ++a)
      for (int b = a + 1; b < static_cast<int>(parts.size()); ++b) {
        if (parts[a].mesh.triangles.empty() || parts[b].mesh.triangles.empty()) continue;
        // Broad phase: the posed boxes meet at some sample.
        bool meet = false;
        for (int i = 0; i < time_steps && !meet; ++i) {
          const double t = static_cast<double>(i) / (time_steps - 1);
          const swept::SpatialBox ba = swept::PosedBox(parts[a].mesh, parts[a].motion.At(t));
          const swept::SpatialBox bb = swept::PosedBox(parts[b].mesh, parts[b].motion.At(t));
          bool apart = false;
          for (int c = 0; c < 3; ++c) apart |= ba.min[c] > bb.max[c] || bb.min[c] > ba.max[c];
          meet = !apart;
        }
        if (!meet) continue;
        ContactState::Pair p{k, a, b, swept::SpacetimeContactNormal(parts, a, b, 0, 1, co)};
        if (p.normal.forces.empty()) continue;
        s.energy += p.normal.energy;
        s.pairs.push_back(std::move(p));
      }
  }
  return s;
}

std::vector<Perturbation> Perturb(const Design& design, const ContactState& at, const std::vector<Freedom>& free,
                                  const ResolutionOptions& options, SubtreeCache* cache) {
  std::vector<Perturbation> out;
  for (const Freedom& f : free) {
    double h = options.difference_step * (f.max - f.min);
    const double v = at.u.at(f.name);
    if (v + h > f.max) h = -h;
    Point u = at.u;
    u[f.name] = v + h;
    Perturbation p{f.name, h, {}};
    // Objects and motions only: the contours there are not needed.
    p.state.u = u;
    EvaluateOptions o;
    o.cache = cache;
    o.run_checks = false;
    o.keep_solid = false;
    o.state_graph = &p.state.graph;
    const SampleResult r = EvaluateSample(design, u, o);
    p.state.has_geometry = r.failure.empty() && p.state.graph.objects.size() == design.objects.size();
    out.push_back(std::move(p));
  }
  return out;
}

std::map<std::string, double> PairDescent(const ContactState& at, const std::vector<Perturbation>& perturbations, int a,
                                          int b) {
  std::map<std::string, double> out;
  for (const Perturbation& p : perturbations) {
    double sum = 0;
    if (p.state.has_geometry) {
      // The surfaces of a and b at u + h, where their shape changed.
      std::unique_ptr<NearSurface> surface[2];
      const int obj[2] = {a, b};
      for (int q = 0; q < 2; ++q)
        if (!SameMesh(at.graph.objects[obj[q]], p.state.graph.objects[obj[q]]))
          surface[q] = std::make_unique<NearSurface>(p.state.graph.objects[obj[q]]);
      for (const auto& pair : at.pairs) {
        if (pair.a != a || pair.b != b) continue;
        const auto& m0 = at.graph.transitions[pair.transition].motions;
        const auto& m1 = p.state.graph.transitions[pair.transition].motions;
        for (const auto& f : pair.normal.forces) {
          Vec3 velocity[2];
          for (int q = 0; q < 2; ++q) {
            const Transform f0 = m0[obj[q]].At(f.t);
            const Vec3 body = f0.Inverse().Apply(f.point);
            // The motion's change, applied to the body point.
            const Vec3 moved = m1[obj[q]].At(f.t).Apply(body);
            for (int c = 0; c < 3; ++c) velocity[q][c] = (moved[c] - f.point[c]) / p.h;
            // The surface's normal speed where its shape changed.
            if (surface[q]) {
              const double speed = -surface[q]->SignedDistance(body) / p.h;
              const Vec3& n = q == 0 ? f.normal_a : f.normal_b;
              for (int c = 0; c < 3; ++c) velocity[q][c] += speed * n[c];
            }
          }
          sum += Dot(f.force, Sub(velocity[1], velocity[0]));
        }
      }
    }
    out[p.name] = sum;
  }
  return out;
}

Point Moved(const Point& u, const std::map<std::string, double>& direction, double step,
            const std::vector<Freedom>& free) {
  Point out = u;
  for (const Freedom& f : free) {
    const auto it = direction.find(f.name);
    if (it == direction.end()) continue;
    out[f.name] = std::clamp(u.at(f.name) + step * it->second, f.min, f.max);
  }
  return out;
}

namespace {

// The line searched (into `direction`, per unit step): steepest descent in
// coordinates scaled to each range, s_k = u_k / range_k, dE/ds_k = range_k
// dE/du_k, unit length in s, components pushing out of a bound dropped.
// Returns the step that reaches the first bound; 0, with `direction` left
// empty, when no component descends.
double DescentLine(const ContactState& at, const std::map<std::string, double>& descent,
                   const std::vector<Freedom>& free, std::map<std::string, double>& direction) {
  std::map<std::string, double> scaled;
  double norm = 0;
  for (const Freedom& f : free) {
    const double range = f.max - f.min;
    double g = descent.count(f.name) ? descent.at(f.name) * range : 0;
    const double v = at.u.at(f.name);
    if ((g > 0 && v >= f.max) || (g < 0 && v <= f.min)) g = 0;
    scaled[f.name] = g;
    norm += g * g;
  }
  norm = std::sqrt(norm);
  if (!(norm > 0)) return 0;
  // Unit steps in scaled coordinates; the step that reaches the first bound.
  double reach = std::numeric_limits<double>::infinity();
  for (const Freedom& f : free) {
    const double d = scaled[f.name] / norm;
    const double range = f.max - f.min;
    direction[f.name] = d * range;
    const double v = at.u.at(f.name);
    if (d > 0) reach = std::min(reach, (f.max - v) / range / d);
    if (d < 0) reach = std::min(reach, (f.min - v) / range / d);
  }
  return reach;
}

}  // namespace

LineSearch GoldenSectionSearch(const Design& design, const ContactState& at,
                               const std::map<std::string, double>& descent, const std::vector<Freedom>& free,
                               const ResolutionOptions& options, int time_steps, SubtreeCache* cache) {
  LineSearch ls;
  ls.u = at.u;
  ls.state = at;
  const double reach = DescentLine(at, descent, free, ls.direction);
  if (!(reach > 0) || !std::isfinite(reach)) return ls;

  struct Sample {
    double x;
    ContactState state;
  };
  std::vector<Sample> seen;
  auto energy = [&](double x) {
    seen.push_back({x, EvaluateContacts(design, Moved(at.u, ls.direction, x, free), time_steps, cache)});
    ++ls.evaluations;
    return seen.back().state.energy;
  };
  const double tolerance = options.energy_tolerance * at.energy;
  const double ratio = (std::sqrt(5.0) - 1) / 2;  // 0.618...
  double lo = 0, hi = reach;
  double c = hi - ratio * (hi - lo), d = lo + ratio * (hi - lo);
  double fc = energy(c), fd = energy(d);
  for (int i = 2; i < options.line_search_iterations; ++i) {
    // Flat energy above zero: the contour has not left yet, look further;
    // at zero: resolved, look for the smallest such step.
    bool keep_lower;
    if (std::abs(fc - fd) <= tolerance)
      keep_lower = fd <= tolerance;
    else
      keep_lower = fc < fd;
    if (keep_lower) {
      hi = d, d = c, fd = fc;
      c = hi - ratio * (hi - lo);
      fc = energy(c);
    } else {
      lo = c, c = d, fc = fd;
      d = lo + ratio * (hi - lo);
      fd = energy(d);
    }
  }
  ls.bracket = hi - lo;
  // The best point seen: the lowest energy, and among energies that equal
  // it (within the tolerance) the smallest step.
  double lowest = std::numeric_limits<double>::infinity();
  for (const Sample& s : seen) lowest = std::min(lowest, s.state.energy);
  const Sample* best = nullptr;
  for (const Sample& s : seen)
    if (s.state.energy <= lowest + tolerance && (!best || s.x < best->x)) best = &s;
  if (best && best->state.energy < at.energy - tolerance) {
    ls.moved = true;
    ls.step = best->x;
    ls.u = best->state.u;
    ls.state = best->state;
  }
  return ls;
}

}  // namespace fabatlas::design
