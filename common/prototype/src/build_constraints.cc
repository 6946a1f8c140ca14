// The linear constraints of a prototype (Model::Build, model.h): cuboid sizes,
// connections and holds, joint attachments and the functional relationships
// (Koo et al. Sec. 5), each in its group.
#include <algorithm>
#include <cmath>
#include <set>

#include "fabatlas/error.h"
#include "model.h"

namespace fabatlas::prototype::internal {

namespace {

struct Builder {
  const Model& m;
  std::vector<LinearConstraint>& out;
  std::vector<std::string>& groups;
  int group = 0;

  void Group(const std::string& name) {
    groups.push_back(name);
    group = static_cast<int>(groups.size()) - 1;
  }
  void Eq(const Affine& g, const std::string& label) { out.push_back({g, true, group, label}); }
  void Ge(const Affine& g, const std::string& label) { out.push_back({g, false, group, label}); }
  double V(const Affine& f) const { return f.Eval(m.base); }

  // Packing of a set of faces in their plane (Koo et al. Sec. 5.1, Fig. 6):
  // consecutive faces along an in-plane axis touch; the first faces along
  // it share their low coordinate, the last ones their high coordinate.
  void Pack(const std::vector<Face>& faces, int normal, const std::string& what) {
    if (faces.size() < 2) return;
    const double thr = 0.5;  // mm: overlaps below this are ignored, as the seed's threshold
    for (int u = 0; u < 3; ++u) {
      if (u == normal) continue;
      int v = 3 - u - normal;
      std::vector<bool> has_prev(faces.size()), has_next(faces.size());
      for (std::size_t i = 0; i < faces.size(); ++i) {
        int best = -1;
        double best_gap = 1e18;
        for (std::size_t j = 0; j < faces.size(); ++j) {
          if (i == j) continue;
          double overlap_v = std::min(V(faces[i].box.hi[v]), V(faces[j].box.hi[v])) -
                             std::max(V(faces[i].box.lo[v]), V(faces[j].box.lo[v]));
          double gap = V(faces[j].box.lo[u]) - V(faces[i].box.hi[u]);
          if (overlap_v > thr && gap > -thr && gap < best_gap) {
            best_gap = gap;
            best = static_cast<int>(j);
          }
        }
        if (best >= 0) {
          has_next[i] = has_prev[best] = true;
          Eq(faces[best].box.lo[u] - faces[i].box.hi[u], what + ": " + faces[i].name + " touches " + faces[best].name);
        }
      }
      int first = -1, last = -1;
      for (std::size_t i = 0; i < faces.size(); ++i) {
        if (!has_prev[i]) {
          if (first < 0)
            first = static_cast<int>(i);
          else
            Eq(faces[i].box.lo[u] - faces[first].box.lo[u],
               what + ": " + faces[i].name + " aligned with " + faces[first].name);
        }
        if (!has_next[i]) {
          if (last < 0)
            last = static_cast<int>(i);
          else
            Eq(faces[i].box.hi[u] - faces[last].box.hi[u],
               what + ": " + faces[i].name + " aligned with " + faces[last].name);
        }
      }
    }
  }

  // The face of a set with the smallest low (or largest high) coordinate
  // along u, by the base values.
  const Face& Extreme(const std::vector<Face>& faces, int u, bool high) const {
    std::size_t best = 0;
    for (std::size_t i = 1; i < faces.size(); ++i) {
      double a = V(high ? faces[i].box.hi[u] : faces[i].box.lo[u]);
      double b = V(high ? faces[best].box.hi[u] : faces[best].box.lo[u]);
      if (high ? a > b : a < b) best = i;
    }
    return faces[best];
  }

  void Cover(const Relationship& r) {
    const Configuration& c = m.Config(r.configuration);
    std::vector<Face> fa, fb;
    for (const auto& s : r.a) fa.push_back(m.FaceIn(s, c, r.where));
    for (const auto& s : r.b) fb.push_back(m.FaceIn(s, c, r.where));
    if (fa.empty() || fb.empty()) throw InputError(r.where + ": cover needs covering and covered faces");
    int n = fb[0].axis;
    for (const auto* set : {&fa, &fb})
      for (const Face& f : *set) {
        if (f.axis != n)
          throw InputError(r.where + ": faces " + f.name + " and " + fb[0].name + " are not parallel in '" + c.name +
                           "'");
        if (&f != &fb[0]) Eq(f.plane - fb[0].plane, r.name + ": " + f.name + " in the plane of " + fb[0].name);
      }
    Pack(fa, n, r.name);
    Pack(fb, n, r.name);
    bool just = !r.just.empty();
    for (int u = 0; u < 3; ++u) {
      if (u == n) continue;
      Affine lo = Extreme(fb, u, false).box.lo[u] - Extreme(fa, u, false).box.lo[u];
      Affine hi = Extreme(fa, u, true).box.hi[u] - Extreme(fb, u, true).box.hi[u];
      std::string ax(1, "xyz"[u]);
      if (just) {
        Eq(lo, r.name + ": covering " + ax + "0 = covered " + ax + "0");
        Eq(hi, r.name + ": covering " + ax + "1 = covered " + ax + "1");
      } else {
        Ge(lo, r.name + ": covering " + ax + "0 <= covered " + ax + "0");
        Ge(hi, r.name + ": covering " + ax + "1 >= covered " + ax + "1");
      }
    }
  }

  void Fit(const Relationship& r) {
    const Configuration& c = m.Config(r.configuration);
    int outer = m.CuboidIndex(r.b[0], r.where);
    int frame = m.cuboid_part[outer];
    Box ob = m.BoxIn(outer, c, frame);
    // A part fits with all its solid cuboids; naming a piece ("lid.tab")
    // makes the fit partial (Koo et al. Sec. 4.2, Fig. 4b).
    std::vector<Box> boxes;
    std::vector<std::string> names;
    std::vector<int> entry;
    for (std::size_t e = 0; e < r.a.size(); ++e) {
      for (int ci : m.SolidsOf(r.a[e], r.where)) {
        if (m.cuboid_part[ci] == frame) throw InputError(r.where + ": '" + r.a[e] + "' cannot fit inside its own part");
        boxes.push_back(m.BoxIn(ci, c, frame));
        names.push_back(m.cuboid_names[ci]);
        entry.push_back(static_cast<int>(e));
      }
    }
    for (int u : r.axes) {
      std::string ax(1, "xyz"[u]);
      for (int side = 0; side < 2; ++side) {
        std::string sname = ax + (side ? "1" : "0");
        bool just = std::find(r.just.begin(), r.just.end(), sname) != r.just.end();
        std::size_t extreme = 0;
        for (std::size_t i = 0; i < boxes.size(); ++i) {
          Affine g = side ? ob.hi[u] - boxes[i].hi[u] : boxes[i].lo[u] - ob.lo[u];
          Ge(g, r.name + ": " + names[i] + " " + sname + " inside " + r.b[0]);
          double vi = V(side ? boxes[i].hi[u] : boxes[i].lo[u]),
                 ve = V(side ? boxes[extreme].hi[u] : boxes[extreme].lo[u]);
          if (side ? vi > ve : vi < ve) extreme = i;
        }
        if (just) {
          Affine g = side ? ob.hi[u] - boxes[extreme].hi[u] : boxes[extreme].lo[u] - ob.lo[u];
          Eq(g, r.name + ": " + names[extreme] + " just fits " + r.b[0] + " at " + sname);
        }
      }
    }
    // Inner parts do not overlap: each pair is kept apart along the axis
    // where the user's arrangement separates them most (Koo et al. Sec. 5.2).
    for (std::size_t i = 0; i < boxes.size(); ++i)
      for (std::size_t j = i + 1; j < boxes.size(); ++j) {
        if (entry[i] == entry[j]) continue;  // cuboids of one part
        int best_u = 0;
        bool j_after = true;
        double best = -1e18;
        for (int u = 0; u < 3; ++u) {
          double s1 = V(boxes[j].lo[u]) - V(boxes[i].hi[u]), s2 = V(boxes[i].lo[u]) - V(boxes[j].hi[u]);
          if (s1 > best) {
            best = s1;
            best_u = u;
            j_after = true;
          }
          if (s2 > best) {
            best = s2;
            best_u = u;
            j_after = false;
          }
        }
        const Box& first = j_after ? boxes[i] : boxes[j];
        const Box& second = j_after ? boxes[j] : boxes[i];
        Ge(second.lo[best_u] - first.hi[best_u],
           r.name + ": " + names[i] + " and " + names[j] + " apart along " + "xyz"[best_u]);
      }
  }

  void Support(const Relationship& r) {
    const Configuration& c = m.Config(r.configuration);
    std::set<int> supporting, supported;
    for (const auto& [sa, sb] : r.pairs) {
      Face a = m.FaceIn(sa, c, r.where), b = m.FaceIn(sb, c, r.where);
      if (a.axis != 2 || b.axis != 2)
        throw InputError(r.where + ": support faces must be horizontal in '" + c.name + "' (" + sa + ", " + sb + ")");
      std::string pair = sa + " under " + sb;
      Eq(a.plane - b.plane, r.name + ": " + pair + " at the same height");
      for (int u = 0; u < 2; ++u) {
        std::string ax(1, "xy"[u]);
        Ge(b.box.hi[u] - a.box.lo[u] - Affine::Const(r.min_overlap), r.name + ": " + pair + " overlap in " + ax);
        Ge(a.box.hi[u] - b.box.lo[u] - Affine::Const(r.min_overlap), r.name + ": " + pair + " overlap in " + ax);
      }
      supporting.insert(m.cuboid_part[m.CuboidIndex(sa.substr(0, sa.rfind('.')), r.where)]);
      supported.insert(m.cuboid_part[m.CuboidIndex(sb.substr(0, sb.rfind('.')), r.where)]);
    }
    // Parts that only support stand on one ground plane (Sec. 4.3).
    int first = -1;
    for (int p : supporting) {
      if (supported.count(p)) continue;
      if (first < 0) {
        first = p;
        continue;
      }
      Eq(m.BoxIn(p, c).lo[2] - m.BoxIn(first, c).lo[2],
         r.name + ": " + m.proto.parts[p].name + " on the ground with " + m.proto.parts[first].name);
    }
  }

  void Flush(const Relationship& r) {
    const Configuration& c = m.Config(r.configuration);
    Face a = m.FaceIn(r.a[0], c, r.where), b = m.FaceIn(r.a[1], c, r.where);
    if (a.axis != b.axis)
      throw InputError(r.where + ": flush faces " + r.a[0] + " and " + r.a[1] + " are not parallel");
    Eq(a.plane - b.plane, r.name + ": " + r.a[0] + " flush with " + r.a[1]);
  }

  void Geometric(const Relationship& r) {
    const std::string& e = r.expression;
    for (const char* op : {"==", ">=", "<="}) {
      auto at = e.find(op);
      if (at == std::string::npos) continue;
      Affine l = m.ParseExpression(e.substr(0, at), r.where), rr = m.ParseExpression(e.substr(at + 2), r.where);
      if (std::string(op) == "==")
        Eq(l - rr, r.name + ": " + e);
      else if (std::string(op) == ">=")
        Ge(l - rr, r.name + ": " + e);
      else
        Ge(rr - l, r.name + ": " + e);
      return;
    }
    throw InputError(r.where + ": geometric constraint '" + e + "' needs ==, >= or <=");
  }

  // Cuboid c's sizes at least its part's min_size; a cavity inside its part,
  // its open face on the part's face.
  void Sizes(std::size_t c) {
    const Part& part = m.proto.parts[m.cuboid_part[c]];
    Group("sizes of " + m.cuboid_names[c] + " (" + part.where + ")");
    for (int ax = 0; ax < 3; ++ax)
      Ge(Affine::Var(6 * c + 2 * ax + 1) - Affine::Var(6 * c + 2 * ax) - Affine::Const(part.min_size),
         m.cuboid_names[c] + " " + "xyz"[ax] + " extent >= " + std::to_string(part.min_size));
    if (!m.cuboid_solid[c]) {  // a cavity: inside its part, open face on the part's face
      int p = m.cuboid_part[c];
      for (int k = 0; k < 6; ++k) {
        Affine g = Affine::Var(6 * c + k) - Affine::Var(6 * p + k);
        bool open = m.cuboids[c]->open == kCoord[k];
        if (open)
          Eq(g, m.cuboid_names[c] + " opens at " + kCoord[k]);
        else
          Ge(k % 2 ? (-1.0) * g : g, m.cuboid_names[c] + " " + kCoord[k] + " inside " + part.name);
      }
    }
  }

  // Piece c stays connected to the cuboid it is on: a face contact of the
  // user's arrangement (within 0.5 mm) stays a contact and the two overlap
  // by >= min_size across it; cuboids that overlap keep overlapping by
  // >= min_size on every axis. `align` coordinates stay equal.
  void Connection(std::size_t c) {
    const Part& part = m.proto.parts[m.cuboid_part[c]];
    const std::vector<std::string>& names = m.cuboid_names;
    int nb = m.CuboidIndex(m.cuboids[c]->on, part.where);
    Group("connection of " + names[c] + " to " + names[nb] + " (" + part.where + ")");
    auto var = [&](int cu, int k) { return Affine::Var(6 * cu + k); };
    int contact = -1, side = 0;
    bool overlaps = true;
    for (int ax = 0; ax < 3; ++ax) {
      double q0 = m.base[6 * c + 2 * ax], q1 = m.base[6 * c + 2 * ax + 1];
      double n0 = m.base[6 * nb + 2 * ax], n1 = m.base[6 * nb + 2 * ax + 1];
      if (std::abs(q0 - n1) <= 0.5) {
        contact = ax;
        side = 0;
      } else if (std::abs(q1 - n0) <= 0.5) {
        contact = ax;
        side = 1;
      } else
        overlaps &= std::min(q1, n1) - std::max(q0, n0) > 0;
    }
    if (contact < 0 && !overlaps)
      throw InputError(part.where + ": piece " + names[c] + " neither touches nor overlaps " + names[nb]);
    for (int ax = 0; ax < 3; ++ax) {
      std::string a(1, "xyz"[ax]);
      if (ax == contact) {
        if (side == 0)
          Eq(var(c, 2 * ax) - var(nb, 2 * ax + 1), names[c] + "." + a + "0 on " + names[nb] + "." + a + "1");
        else
          Eq(var(nb, 2 * ax) - var(c, 2 * ax + 1), names[c] + "." + a + "1 on " + names[nb] + "." + a + "0");
        continue;
      }
      Ge(var(c, 2 * ax + 1) - var(nb, 2 * ax) - Affine::Const(part.min_size),
         names[c] + " overlaps " + names[nb] + " in " + a);
      Ge(var(nb, 2 * ax + 1) - var(c, 2 * ax) - Affine::Const(part.min_size),
         names[c] + " overlaps " + names[nb] + " in " + a);
    }
    for (int k : m.cuboids[c]->align)
      Eq(var(c, k) - var(nb, k), names[c] + "." + kCoord[k] + " aligned with " + names[nb]);
  }

  // Cuboid c's held coordinates stay at their given values.
  void Held(std::size_t c) {
    const Part& part = m.proto.parts[m.cuboid_part[c]];
    const std::vector<int>& held = static_cast<int>(c) == m.cuboid_part[c] ? part.held : m.cuboids[c]->held;
    if (held.empty()) return;
    Group("held coordinates of " + m.cuboid_names[c] + " (" + part.where + ")");
    for (int k : held)
      Eq(Affine::Var(6 * c + k) - Affine::Const(m.cuboids[c]->box[k]),
         m.cuboid_names[c] + "." + kCoord[k] + " held at " + std::to_string(m.cuboids[c]->box[k]));
  }

  // Joint j's attachment: a double pivot's faces coplanar, a slide's rail
  // faces on each other, the references a joint's position names equal.
  void Attachment(const Joint& j) {
    const Prototype& proto = m.proto;
    if (j.type == JointType::kDoublePivot) {
      // The pivots sit on two coplanar faces (Sec. 3), one per part.
      int k = 0;
      while (kCoord[k] != j.face) ++k;
      int c = proto.PartIndex(j.child), pa = proto.PartIndex(j.parent);
      Group("attachment of joint " + j.name + " (" + j.where + ")");
      Eq(Affine::Var(6 * c + k) - Affine::Var(6 * pa + k),
         j.name + ": " + j.child + "." + j.face + " coplanar with " + j.parent + "." + j.face);
      return;
    }
    if (j.type == JointType::kSlide && !j.on.empty()) {
      // Rails (Koo et al. Sec. 7): the two faces coplanar, and in every
      // configuration the child still overlaps the parent along the slide
      // by >= its min_size, so the rail stays in its groove.
      Group("attachment of joint " + j.name + " (" + j.where + ")");
      Eq(m.Resolve(j.on[0], j.where) - m.Resolve(j.on[1], j.where), j.name + ": " + j.on[0] + " on " + j.on[1]);
      int c = proto.PartIndex(j.child), pa = proto.PartIndex(j.parent);
      double ms = proto.parts[c].min_size;
      for (const Configuration& conf : proto.configurations) {
        Affine d = m.SlideValue(j, conf);
        int s = j.axis;
        Ge(Affine::Var(6 * c + 2 * s + 1) + d - Affine::Var(6 * pa + 2 * s) - Affine::Const(ms),
           j.name + ": " + j.child + " on " + j.parent + " in '" + conf.name + "' (" + "xyz"[s] + "0)");
        Ge(Affine::Var(6 * pa + 2 * s + 1) - Affine::Var(6 * c + 2 * s) - d - Affine::Const(ms),
           j.name + ": " + j.child + " on " + j.parent + " in '" + conf.name + "' (" + "xyz"[s] + "1)");
      }
      return;
    }
    bool any = false;
    for (const auto& refs : j.at) any |= refs.size() > 1;
    if (!any) return;
    Group("attachment of joint " + j.name + " (" + j.where + ")");
    for (const auto& refs : j.at)
      for (std::size_t i = 1; i < refs.size(); ++i)
        Eq(m.Resolve(refs[i], j.where) - m.Resolve(refs[0], j.where), j.name + ": " + refs[0] + " = " + refs[i]);
  }

  // Relationship r's constraints, by its type.
  void Relation(const Relationship& r) {
    Group(r.name + " (" + r.where + ")");
    switch (r.type) {
      case RelationType::kCover:
        Cover(r);
        break;
      case RelationType::kFit:
        Fit(r);
        break;
      case RelationType::kSupport:
        Support(r);
        break;
      case RelationType::kFlush:
        Flush(r);
        break;
      case RelationType::kGeometric:
        Geometric(r);
        break;
    }
  }
};

}  // namespace

void Model::Build(std::vector<LinearConstraint>& out, std::vector<std::string>& groups) const {
  Builder b{*this, out, groups};
  for (std::size_t c = 0; c < cuboids.size(); ++c) b.Sizes(c);
  for (std::size_t c = 0; c < cuboids.size(); ++c)
    if (cuboid_solid[c] && static_cast<int>(c) != cuboid_part[c]) b.Connection(c);
  for (std::size_t c = 0; c < cuboids.size(); ++c) b.Held(c);
  for (const Joint& j : proto.joints) b.Attachment(j);
  for (const Relationship& r : proto.relationships) b.Relation(r);
}

}  // namespace fabatlas::prototype::internal
