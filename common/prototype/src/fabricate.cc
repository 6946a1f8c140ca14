// Koo et al. Sec. 7: cavities, joint geometry and gaps, on OpenVDB level sets
// (common/geometry) with swept volumes from common/swept.
#include "fabatlas/prototype/fabricate.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "fabatlas/error.h"
#include "fabatlas/swept/swept_volume.h"
#include "model.h"

namespace fabatlas::prototype {
namespace {

using geometry::Solid;
using geometry::Vec3;

Solid BoxAt(const geometry::GridSpec& g, const Vec3& lo, const Vec3& hi) {
  Vec3 size{hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
  for (double s : size)
    if (!(s > 0)) return Solid();
  return geometry::Translate(geometry::Box(g, size), {(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2});
}

// Cylinder of `radius` along `axis` over [a0, a1], through `p` (other coordinates).
Solid CylinderAlong(const geometry::GridSpec& g, int axis, double radius, double a0, double a1, const Vec3& p) {
  if (!(a1 > a0) || !(radius > 0)) return Solid();
  Solid c = geometry::Cylinder(g, radius, a1 - a0);
  if (axis == 0) c = geometry::Rotate(c, {0, 90, 0});
  if (axis == 1) c = geometry::Rotate(c, {90, 0, 0});
  Vec3 centre = p;
  centre[axis] = (a0 + a1) / 2;
  return geometry::Translate(c, centre);
}

Solid Add(const Solid& a, const Solid& b) { return a.empty() ? b : b.empty() ? a : geometry::Union(a, b); }
Solid Cut(const Solid& a, const Solid& b) { return a.empty() || b.empty() ? a : geometry::Difference(a, b); }

mesh::TriangleMesh BoxMesh(const std::array<double, 6>& b) {
  mesh::TriangleMesh m;
  for (int i = 0; i < 8; ++i) m.vertices.push_back({b[i & 1], b[2 + ((i >> 1) & 1)], b[4 + ((i >> 2) & 1)]});
  m.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return m;
}

// Mated rails of a slide (Koo et al. Sec. 7: "we add mated rails that allow
// the parts to move along the sliding vector"): a T-shaped tongue on the
// child's rail face runs in a T-slot cut into the parent, over the travel of
// every configuration. Sizes follow the depth t of parent material under
// the rail face: unit u = clamp(t / 8, 2 voxels, 3 mm); stem 2u wide, flange
// u high and overhanging the stem's slot by u on each side (2(2u + gap)
// wide), the parent's lip over the flange u thick, clearance `gap` all
// round. Throws InputError naming the joint when the parent is too thin or
// the faces overlap too little across the rail.
void SlideRails(const Prototype& p, const internal::Model& model, const SolveSummary& sol, const Eigen::VectorXd& x,
                const Joint& j, const geometry::GridSpec& g, Solid& child, Solid& parent) {
  const double gap = p.fabrication.gap, h = g.voxel_size;
  const int s = j.axis, n = j.on[0][j.on[0].size() - 2] - 'x', w = 3 - s - n;
  const double sigma = j.on[0].back() == '0' ? 1 : -1;  // the child lies on the +n side of the plane
  const double P = model.Resolve(j.on[0], j.where).Eval(x);
  auto cb = sol.cuboids.at(j.child), pb = sol.cuboids.at(j.parent);
  // The parent's material under the plane: the parent's cuboid, or the
  // cavity whose floor the child rides on.
  std::string owner = j.on[1].substr(0, j.on[1].rfind('.'));
  auto ob = sol.cuboids.at(owner);
  // Depth of material under the rail face: down to the parent's far face or
  // to the nearest other cavity over the rail's footprint.
  double t = sigma > 0 ? P - pb[2 * n] : pb[2 * n + 1] - P;
  for (const Cuboid& cav : p.parts[p.PartIndex(j.parent)].cavities) {
    if (cav.name == owner) continue;
    auto c = sol.cuboids.at(cav.name);
    bool over = c[2 * w + 1] > cb[2 * w] && c[2 * w] < cb[2 * w + 1];
    double depth = sigma > 0 ? P - c[2 * n + 1] : c[2 * n] - P;
    if (over && depth >= 0) t = std::min(t, depth);
  }
  double u = std::clamp(t / 8, 2 * h, 3.0);
  double a = u, bw = a + gap + u, ds = gap + u, hf = u;  // the flange overhangs the stem's slot by u
  char msg[200];
  if (ds + hf + gap > t - 2 * h) {
    std::snprintf(msg, sizeof msg, "%s is %.2f mm deep under its rail face; rails need %.2f", j.parent.c_str(), t,
                  ds + hf + gap + 2 * h);
    throw InputError(j.where + ": slide " + j.name + ": " + msg);
  }
  double w0 = std::max(cb[2 * w], ob[2 * w]), w1 = std::min(cb[2 * w + 1], ob[2 * w + 1]);
  if (w1 - w0 < 2 * (bw + gap) + 4 * h) {
    std::snprintf(msg, sizeof msg, "%s and %s overlap by %.2f mm across the rail; rails need %.2f", j.child.c_str(),
                  j.parent.c_str(), w1 - w0, 2 * (bw + gap) + 4 * h);
    throw InputError(j.where + ": slide " + j.name + ": " + msg);
  }
  double wc = (w0 + w1) / 2;
  double dmin = 0, dmax = 0;
  for (const Configuration& c : p.configurations) {
    double d = model.SlideValue(j, c).Eval(x);
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  // A box from s/w/n ranges; n as signed depths below the parent's printed
  // face (positive into the parent).
  const double face = P - sigma * gap / 2;
  auto rail_box = [&](double s0, double s1, double wlo, double whi, double d0, double d1) {
    Vec3 lo, hi;
    lo[s] = s0, hi[s] = s1, lo[w] = wlo, hi[w] = whi;
    lo[n] = std::min(face - sigma * d0, face - sigma * d1);
    hi[n] = std::max(face - sigma * d0, face - sigma * d1);
    return BoxAt(g, lo, hi);
  };
  double t0 = cb[2 * s] + gap, t1 = cb[2 * s + 1] - gap;
  // Tongue: stem from a voxel into the child's printed face, flange at its foot.
  child = Add(child, rail_box(t0, t1, wc - a, wc + a, -gap - h, ds + hf / 2));
  child = Add(child, rail_box(t0, t1, wc - bw, wc + bw, ds, ds + hf));
  // Slot over the travel.
  double s0 = t0 + dmin - gap, s1 = t1 + dmax + gap;
  parent = Cut(parent, rail_box(s0, s1, wc - a - gap, wc + a + gap, -gap - h, ds));
  parent = Cut(parent, rail_box(s0, s1, wc - bw - gap, wc + bw + gap, ds - gap, ds + hf + gap));
}

// What every fabrication step reads: the prototype, its model, the solution
// and its variable vector x, the grid, the gap and the voxel size (mm).
struct FabricationInputs {
  const Prototype& p;
  const internal::Model& model;
  const SolveSummary& sol;
  const Eigen::VectorXd& x;
  const geometry::GridSpec& g;
  double gap, h;
  std::array<double, 6> box_of(const std::string& name) const { return sol.cuboids.at(name); }
};

// The model's variable vector at the solution: the cuboids' bounds, then the
// free values.
Eigen::VectorXd SolutionVector(const internal::Model& model, const SolveSummary& sol) {
  Eigen::VectorXd x(model.variables);
  for (std::size_t c = 0; c < model.cuboids.size(); ++c)
    for (int k = 0; k < 6; ++k) x[6 * c + k] = sol.cuboids.at(model.cuboid_names[c])[k];
  for (std::size_t i = 0; i < model.free_names.size(); ++i)
    x[6 * model.cuboids.size() + i] = sol.free_values.at(model.free_names[i]);
  return x;
}

// Parts shrunk by gap/2 on every face, so touching faces end up a gap apart;
// a piece joins the cuboid it is on through a bridge over their contact
// (the shrunk boxes of a face contact are a gap apart too); cavities grown
// by gap/2 and pushed through their open face. One solid per part.
std::vector<Solid> PartSolids(const FabricationInputs& f) {
  const internal::Model& model = f.model;
  const geometry::GridSpec& g = f.g;
  const double gap = f.gap, h = f.h;
  std::vector<Solid> solids(f.p.parts.size());
  for (std::size_t c = 0; c < model.cuboids.size(); ++c) {
    if (!model.cuboid_solid[c]) continue;
    const int i = model.cuboid_part[c];
    auto b = f.box_of(model.cuboid_names[c]);
    solids[i] = Add(solids[i], BoxAt(g, {b[0] + gap / 2, b[2] + gap / 2, b[4] + gap / 2},
                                     {b[1] - gap / 2, b[3] - gap / 2, b[5] - gap / 2}));
    if (static_cast<int>(c) == i) continue;
    auto n = f.box_of(model.cuboids[c]->on);
    Vec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(b[2 * a], n[2 * a]) + gap / 2;
      hi[a] = std::min(b[2 * a + 1], n[2 * a + 1]) - gap / 2;
      if (hi[a] - lo[a] < h) {  // the contact axis: span the two gaps and a voxel into each
        double plane = std::abs(b[2 * a] - n[2 * a + 1]) < std::abs(b[2 * a + 1] - n[2 * a]) ? b[2 * a] : b[2 * a + 1];
        lo[a] = plane - gap / 2 - h;
        hi[a] = plane + gap / 2 + h;
      }
    }
    solids[i] = Add(solids[i], BoxAt(g, lo, hi));
  }
  for (std::size_t i = 0; i < solids.size(); ++i) {
    for (const Cuboid& cav : f.p.parts[i].cavities) {
      auto c = f.box_of(cav.name);
      Vec3 lo{c[0] - gap / 2, c[2] - gap / 2, c[4] - gap / 2}, hi{c[1] + gap / 2, c[3] + gap / 2, c[5] + gap / 2};
      if (!cav.open.empty()) {
        int ax = cav.open[0] - 'x';
        if (cav.open[1] == '0')
          lo[ax] -= 2 * gap + 2 * h;
        else
          hi[ax] += 2 * gap + 2 * h;
      }
      solids[i] = Cut(solids[i], BoxAt(g, lo, hi));
    }
  }
  return solids;
}

// Cavities by swept volume: each inner part moves from the base to the
// fitting configuration relative to the outer part; the sweep, offset by
// gap/2, is subtracted from the outer part. Counts fs->swept_cavities.
void CutSweptCavities(const FabricationInputs& f, std::vector<Solid>* solids, FabricateSummary* fs) {
  const internal::Model& model = f.model;
  const Eigen::VectorXd& x = f.x;
  for (const Relationship& r : f.p.relationships) {
    if (r.type != RelationType::kFit) continue;
    int oc = model.CuboidIndex(r.b[0], r.where);
    if (!model.cuboid_solid[oc]) continue;  // into a user cavity: already hollow
    int outer = model.cuboid_part[oc];
    const Configuration& c = model.Config(r.configuration);
    std::vector<int> inner;
    for (const std::string& in : r.a)
      for (int ci : model.SolidsOf(in, r.where)) inner.push_back(ci);
    for (int ci : inner) {
      int ip = model.cuboid_part[ci];
      if (!model.cuboid_solid[ci]) continue;
      auto pose = [&](double t) {
        internal::Pose pa = model.PoseOf(ip, c, t), pb = model.PoseOf(outer, c, t);
        swept::Transform tr;
        Eigen::Matrix3d R = pb.R.transpose() * pa.R;
        Eigen::Vector3d ta, tb;
        for (int k = 0; k < 3; ++k) {
          ta[k] = pa.t[k].Eval(x);
          tb[k] = pb.t[k].Eval(x);
        }
        Eigen::Vector3d t3 = pb.R.transpose() * (ta - tb);
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) tr.rotation[a][b] = R(a, b);
          tr.translation[a] = t3[a];
        }
        return tr;
      };
      mesh::TriangleMesh body = BoxMesh(f.box_of(model.cuboid_names[ci]));
      swept::SweptVolumeOptions so;
      so.voxel_size = f.h;
      so.offset = f.gap / 2;
      so.time_steps = 2;
      so.max_step_displacement = 2 * f.h;
      std::vector<swept::Transform> poses = swept::SamplePoses(body, pose, so);
      swept::SweptDistanceField field = swept::ComputeSweptDistance(body, poses, so);
      mesh::TriangleMesh surface = field.Surface(f.gap / 2);
      if (surface.empty()) continue;
      (*solids)[outer] = Cut((*solids)[outer], geometry::FromMesh(f.g, surface));
      ++fs->swept_cavities;
    }
  }
}

// The thinnest side (mm) of joint j's child and parent cuboids.
double ThinnestSide(const FabricationInputs& f, const Joint& j) {
  auto cb = f.box_of(j.child), pb = f.box_of(j.parent);
  double thin = 1e9;
  for (int a = 0; a < 3; ++a) thin = std::min({thin, cb[2 * a + 1] - cb[2 * a], pb[2 * a + 1] - pb[2 * a]});
  return thin;
}

// Hinge or sliding hinge j: a pin on the edge, radius half the thinnest
// part's thickness (Sec. 7), on the child `child`, running in a hole of the
// parent `parent`: through two yokes of the parent (hinge), or with its ends
// in slots of the parent along the slide vector over the range of slide
// values used (sliding hinge). Counts fs->joint_pieces.
void AddHinge(const FabricationInputs& f, const Joint& j, Solid& child, Solid& parent, FabricateSummary* fs) {
  const geometry::GridSpec& g = f.g;
  const double gap = f.gap, h = f.h;
  auto cb = f.box_of(j.child);
  double r = std::max(ThinnestSide(f, j) / 2, 2 * h);
  Vec3 e{0, 0, 0};
  int k = 0;
  for (int a = 0; a < 3; ++a)
    if (a != j.axis) e[a] = f.model.Resolve(j.at[k++][0], j.where).Eval(f.x);
  double lo = cb[2 * j.axis], hi = cb[2 * j.axis + 1], len = hi - lo;
  if (j.type == JointType::kHinge) {
    double ro = r + gap + std::max(r / 2, 2 * h), yl = len / 5;
    child = Add(child, CylinderAlong(g, j.axis, r, lo + gap / 2, hi - gap / 2, e));
    parent = Cut(parent, CylinderAlong(g, j.axis, r + gap, lo - gap, hi + gap, e));
    for (double y0 : {lo, hi - yl}) {
      Solid yoke =
          Cut(CylinderAlong(g, j.axis, ro, y0, y0 + yl, e), CylinderAlong(g, j.axis, r + gap, y0 - h, y0 + yl + h, e));
      child = Cut(child, CylinderAlong(g, j.axis, ro + gap, y0 - gap, y0 + yl + gap, e));
      child = Add(child, CylinderAlong(g, j.axis, r, lo + gap / 2, hi - gap / 2, e));
      parent = Add(parent, yoke);
      fs->joint_pieces += 1;
    }
    // The pin runs through the yokes' holes only: cut it back where the yoke sits.
    fs->joint_pieces += 1;
    return;
  }
  // Sliding hinge: a longer pin whose ends run in slots of the parent
  // along the slide vector over the range of slide values used.
  double ext = r + gap;
  child = Add(child, CylinderAlong(g, j.axis, r, lo - ext, hi + ext, e));
  parent = Cut(parent, CylinderAlong(g, j.axis, r + gap, lo - ext - gap, hi + ext + gap, e));
  double dmin = 0, dmax = 0;
  for (const Configuration& c : f.p.configurations) {
    auto it = c.values.find(j.name);
    if (it == c.values.end()) continue;
    double d = it->second.slide == "free" ? f.sol.free_values.at(j.name + "@" + c.name + ".s")
                                          : f.model.ParseExpression(it->second.slide, j.where).Eval(f.x);
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
  }
  int s = j.slide_axis, w = 3 - j.axis - s;
  for (int end = 0; end < 2; ++end) {
    Vec3 slo, shi;
    slo[j.axis] = end ? hi - gap : lo - ext - gap;
    shi[j.axis] = end ? hi + ext + gap : lo + gap;
    slo[s] = e[s] - r - gap + dmin;
    shi[s] = e[s] + r + gap + dmax;
    slo[w] = e[w] - r - gap;
    shi[w] = e[w] + r + gap;
    parent = Cut(parent, BoxAt(g, slo, shi));
  }
  fs->joint_pieces += 1;
}

// Double pivot j with solved pivots ps: a pivot pin and cap on the child
// and on the parent, and the free link between them (returned). Counts
// fs->joint_pieces.
Solid AddDoublePivot(const FabricationInputs& f, const Joint& j, const PivotSolution& ps, Solid& child, Solid& parent,
                     FabricateSummary* fs) {
  const geometry::GridSpec& g = f.g;
  const double gap = f.gap, h = f.h;
  auto cb = f.box_of(j.child);
  const double thin = ThinnestSide(f, j);
  int n = j.normal;
  double sigma = j.face.back() == '1' ? 1 : -1;
  double P = cb[2 * n + (sigma > 0 ? 1 : 0)];
  double rp = std::max(2 * h, std::min(thin / 4, 4.0));
  double tl = std::max(4 * h, rp), R = rp + gap + std::max(rp, 2 * h);
  auto along = [&](double a, double b) {
    return std::pair{std::min(P + sigma * a, P + sigma * b), std::max(P + sigma * a, P + sigma * b)};
  };
  Vec3 ua{ps.child_pivot[0], ps.child_pivot[1], ps.child_pivot[2]};
  Vec3 ub{ps.parent_pivot[0], ps.parent_pivot[1], ps.parent_pivot[2]};
  auto [p0, p1] = along(-2 * rp, 2 * gap + tl + tl);
  auto [c0, c1] = along(2 * gap + tl, 2 * gap + 2 * tl);
  auto [l0, l1] = along(gap, gap + tl);
  for (auto [part, u] : {std::pair{&child, ua}, std::pair{&parent, ub}}) {
    *part = Add(*part, CylinderAlong(g, n, rp, p0, p1, u));
    *part = Add(*part, CylinderAlong(g, n, R - h, c0, c1, u));
    fs->joint_pieces += 2;
  }
  Vec3 a = ua, b = ub;
  a[n] = b[n] = (l0 + l1) / 2;
  Vec3 slo{-1e4, -1e4, -1e4}, shi{1e4, 1e4, 1e4};
  slo[n] = l0;
  shi[n] = l1;
  Vec3 bl{std::min(a[0], b[0]) - R, std::min(a[1], b[1]) - R, std::min(a[2], b[2]) - R};
  Vec3 bh{std::max(a[0], b[0]) + R, std::max(a[1], b[1]) + R, std::max(a[2], b[2]) + R};
  bl[n] = l0;
  bh[n] = l1;
  Solid link = geometry::Intersection(geometry::Capsule(g, a, b, R), BoxAt(g, bl, bh));
  for (const Vec3& u : {ua, ub}) link = Cut(link, CylinderAlong(g, n, rp + gap, l0 - h, l1 + h, u));
  fs->joint_pieces += 1;
  return link;
}

}  // namespace

std::vector<FabricatedPiece> FabricatePieces(const Prototype& p, const SolveSummary& sol, const geometry::GridSpec& g,
                                             FabricateSummary* summary) {
  auto start = std::chrono::steady_clock::now();
  if (!sol.satisfiable) throw InputError(p.file + ": cannot fabricate: " + sol.Explain());
  internal::Model model(p);
  const Eigen::VectorXd x = SolutionVector(model, sol);
  const FabricationInputs f{p, model, sol, x, g, p.fabrication.gap, g.voxel_size};
  FabricateSummary fs;
  const std::size_t np = p.parts.size();
  std::vector<Solid> solids = PartSolids(f);
  CutSweptCavities(f, &solids, &fs);

  // Joint geometry.
  std::vector<std::pair<std::string, Solid>> extra;  // free pieces (links), by joint
  for (const Joint& j : p.joints) {
    int ci = p.PartIndex(j.child), pi = p.PartIndex(j.parent);
    if (j.type == JointType::kHinge || j.type == JointType::kSlidingHinge) {
      AddHinge(f, j, solids[ci], solids[pi], &fs);
    } else if (j.type == JointType::kDoublePivot) {
      const PivotSolution* ps = nullptr;
      for (const auto& q : sol.pivots)
        if (q.joint == j.name) ps = &q;
      if (!ps) continue;
      extra.push_back({j.name, AddDoublePivot(f, j, *ps, solids[ci], solids[pi], &fs)});
    }
    if (j.type == JointType::kSlide && !j.on.empty()) {
      SlideRails(p, model, sol, x, j, g, solids[ci], solids[pi]);
      fs.joint_pieces += 1;
    }
    // A slide without rail faces runs tightly in a cavity (a fit inside):
    // no extra geometry (Koo et al. Sec. 7).
  }

  std::vector<FabricatedPiece> out;
  for (std::size_t i = 0; i < np; ++i) {
    fs.part_volumes[p.parts[i].name] = solids[i].empty() ? 0 : solids[i].Volume();
    out.push_back({p.parts[i].name, solids[i]});
  }
  for (auto& [name, s] : extra) out.push_back({"link:" + name, s});
  fs.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary) *summary = fs;
  return out;
}

Solid Fabricate(const Prototype& p, const SolveSummary& sol, const geometry::GridSpec& g, FabricateSummary* summary) {
  auto start = std::chrono::steady_clock::now();
  FabricateSummary fs;
  Solid all;
  for (const FabricatedPiece& piece : FabricatePieces(p, sol, g, &fs)) all = Add(all, piece.solid);
  fs.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (summary) *summary = fs;
  return all;
}

}  // namespace fabatlas::prototype
