// OpenSCAD 2021.01's 2-D operations through Clipper 6.4.2 (clipper_shape.h).
#include "clipper_shape.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace fabatlas::scad::internal {
namespace {

using ClipperLib::cInt;
using ClipperLib::IntPoint;
using ClipperLib::Path;
using ClipperLib::Paths;

// Clipper refuses coordinates beyond its range with an exception; OpenSCAD
// then skips the polygon with this warning.
void AddPathsOrWarn(ClipperLib::Clipper& clipper, const Paths& paths, ClipperLib::PolyType type,
                    std::vector<std::string>* warnings) {
  try {
    clipper.AddPaths(paths, type, true);
  } catch (const ClipperLib::clipperException&) {
    if (warnings) warnings->push_back("WARNING: Range check failed for polygon. skipping");
  }
}

Paths SanitizedPaths(const Shape* shape, std::vector<std::string>* warnings) {
  if (!shape) return {};
  Paths paths = ToPaths(*shape);
  if (!shape->sanitized) {
    ClipperLib::Clipper clipper;
    AddPathsOrWarn(clipper, paths, ClipperLib::ptSubject, warnings);
    ClipperLib::PolyTree tree;
    clipper.Execute(ClipperLib::ctUnion, tree, ClipperLib::pftEvenOdd, ClipperLib::pftEvenOdd);
    ClipperLib::PolyTreeToPaths(tree, paths);
  }
  return paths;
}

// The quads swept by `path` moving around `pattern` (both closed): for each
// edge of the pattern translated to each vertex of the path and the next one,
// the quad between the two copies, counter-clockwise. Clipper's own
// MinkowskiSum unions them at once; OpenSCAD keeps them apart for the union
// that follows (fewer rounded crossing points).
void ConvolutionQuads(const Path& pattern, const Path& path, Paths& quads) {
  const std::size_t np = pattern.size(), nq = path.size();
  if (np == 0 || nq == 0) return;
  std::vector<Path> copies(nq);
  for (std::size_t i = 0; i < nq; ++i)
    for (const IntPoint& p : pattern) copies[i].push_back(IntPoint(path[i].X + p.X, path[i].Y + p.Y));
  for (std::size_t i = 0; i < nq; ++i)
    for (std::size_t j = 0; j < np; ++j) {
      const std::size_t i2 = (i + 1) % nq, j2 = (j + 1) % np;
      Path quad{copies[i][j], copies[i2][j], copies[i2][j2], copies[i][j2]};
      if (!ClipperLib::Orientation(quad)) ClipperLib::ReversePath(quad);
      quads.push_back(std::move(quad));
    }
}

// `a` translated to the first vertex of each counter-clockwise loop of `b`:
// the inside of the sum that the convolution of the outlines leaves open.
void FillInsides(const Paths& a, const Paths& b, Paths& target) {
  for (const Path& bp : b) {
    if (bp.empty() || !ClipperLib::Orientation(bp)) continue;
    for (const Path& ap : a) {
      Path moved = ap;
      for (IntPoint& p : moved) p.X += bp[0].X, p.Y += bp[0].Y;
      target.push_back(std::move(moved));
    }
  }
}

Shape UnionNonZero(const Paths& paths, bool strictly_simple) {
  ClipperLib::Clipper clipper;
  clipper.StrictlySimple(strictly_simple);
  try {
    clipper.AddPaths(paths, ClipperLib::ptSubject, true);
  } catch (const ClipperLib::clipperException&) {
    return {};
  }
  ClipperLib::PolyTree tree;
  clipper.Execute(ClipperLib::ctUnion, tree, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
  return FromTree(tree);
}

using P3 = std::array<double, 3>;

// The loops where a closed mesh crosses z = 0, with a vertex at z = 0 taken
// as above the plane when `zero_above` (the section just below the plane)
// and below it otherwise (just above).
std::vector<Loop> SliceLoops(const mesh::TriangleMesh& m, bool zero_above) {
  std::map<P3, int> ids;  // welds vertices a soup repeats
  std::vector<int> id(m.vertices.size());
  for (std::size_t i = 0; i < m.vertices.size(); ++i)
    id[i] = ids.emplace(m.vertices[i], static_cast<int>(ids.size())).first->second;
  auto above = [&](int v) { return zero_above ? m.vertices[v][2] >= 0 : m.vertices[v][2] > 0; };
  // Crossing edges (welded ids, low first) chained through the triangles.
  std::map<std::pair<int, int>, Point2> point;
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> links;
  for (const auto& t : m.triangles) {
    std::vector<std::pair<int, int>> cut;
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      if (above(a) == above(b)) continue;
      std::pair<int, int> key{id[a], id[b]};
      int lo = a, hi = b;
      if (key.first > key.second) std::swap(key.first, key.second), std::swap(lo, hi);
      if (!point.count(key)) {
        const P3& p = m.vertices[lo];
        const P3& q = m.vertices[hi];
        const double s = p[2] / (p[2] - q[2]);
        point[key] = {p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])};
      }
      cut.push_back(key);
    }
    if (cut.size() != 2) continue;
    links[cut[0]].push_back(cut[1]);
    links[cut[1]].push_back(cut[0]);
  }
  std::vector<Loop> loops;
  std::map<std::pair<int, int>, bool> used;
  for (const auto& [start, next] : links) {
    if (used[start]) continue;
    Loop loop;
    std::pair<int, int> at = start, prev{-1, -1};
    while (!used[at]) {
      used[at] = true;
      loop.push_back(point[at]);
      const auto& n = links[at];
      std::pair<int, int> go = prev;
      for (const auto& c : n)
        if (c != prev && !used[c]) go = c;
      if (go == prev || go.first < 0) break;
      prev = at;
      at = go;
    }
    if (loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return loops;
}

// A coordinate on OpenSCAD's grid, truncated toward zero as its conversion
// does; beyond the integers (or NaN) a value Clipper's range test refuses
// (OpenSCAD's conversion is undefined there).
cInt Grid(double mm) {
  const double v = mm * kClipperScale;
  if (!(std::abs(v) < 9.2e18)) return v < 0 ? static_cast<cInt>(-9.2e18) : static_cast<cInt>(9.2e18);
  return static_cast<cInt>(v);
}

}  // namespace

Paths ToPaths(const Shape& shape) {
  Paths paths;
  for (const Loop& loop : shape.loops) {
    Path p;
    for (const Point2& v : loop) p.push_back(IntPoint(Grid(v[0]), Grid(v[1])));
    if (!shape.sanitized && !ClipperLib::Orientation(p)) std::reverse(p.begin(), p.end());
    paths.push_back(std::move(p));
  }
  return paths;
}

Shape FromTree(const ClipperLib::PolyTree& tree) {
  Shape shape;
  for (const ClipperLib::PolyNode* node = tree.GetFirst(); node; node = node->GetNext()) {
    Path cleaned;
    ClipperLib::CleanPolygon(node->Contour, cleaned);
    if (cleaned.size() < 3) continue;
    Loop loop;
    for (const IntPoint& p : cleaned) loop.push_back({p.X / kClipperScale, p.Y / kClipperScale});
    shape.loops.push_back(std::move(loop));
  }
  shape.sanitized = true;
  return shape;
}

Shape Sanitize(const Shape& shape, std::vector<std::string>* warnings) {
  Shape unsanitized = shape;
  unsanitized.sanitized = false;
  ClipperLib::Clipper clipper;
  AddPathsOrWarn(clipper, ToPaths(unsanitized), ClipperLib::ptSubject, warnings);
  ClipperLib::PolyTree tree;
  clipper.Execute(ClipperLib::ctUnion, tree, ClipperLib::pftEvenOdd, ClipperLib::pftEvenOdd);
  return FromTree(tree);
}

Shape Clip(const std::vector<const Shape*>& shapes, ClipperLib::ClipType op, std::vector<std::string>* warnings) {
  std::vector<Paths> all;
  for (const Shape* s : shapes) all.push_back(SanitizedPaths(s, warnings));
  ClipperLib::Clipper clipper;
  ClipperLib::PolyTree tree;
  if (op == ClipperLib::ctIntersection && all.size() >= 2) {
    Paths source = all[0];
    for (std::size_t i = 1; i < all.size(); ++i) {
      clipper.Clear();
      AddPathsOrWarn(clipper, source, ClipperLib::ptSubject, warnings);
      AddPathsOrWarn(clipper, all[i], ClipperLib::ptClip, warnings);
      clipper.Execute(op, tree, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
      if (i + 1 < all.size()) ClipperLib::PolyTreeToPaths(tree, source);
    }
    return FromTree(tree);
  }
  for (std::size_t i = 0; i < all.size(); ++i)
    AddPathsOrWarn(clipper, all[i], i == 0 ? ClipperLib::ptSubject : ClipperLib::ptClip, warnings);
  clipper.Execute(op, tree, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
  return FromTree(tree);
}

Shape Offset(const Shape& shape, double delta, ClipperLib::JoinType join, double miter_limit, double arc_tolerance) {
  ClipperLib::ClipperOffset offset(miter_limit, arc_tolerance * kClipperScale);
  offset.AddPaths(ToPaths(shape), join, ClipperLib::etClosedPolygon);
  ClipperLib::PolyTree tree;
  offset.Execute(tree, delta * kClipperScale);
  return FromTree(tree);
}

Shape Minkowski(const std::vector<const Shape*>& shapes) {
  if (shapes.empty()) return {};
  if (shapes.size() == 1) return shapes[0] ? *shapes[0] : Shape{};
  Paths lhs = shapes[0] ? ToPaths(*shapes[0]) : Paths{};
  Paths terms;
  bool any = false;
  for (std::size_t i = 1; i < shapes.size(); ++i) {
    if (!shapes[i]) continue;
    if (any) {  // the previous sum (not cleaned, as OpenSCAD keeps it) becomes the left operand
      ClipperLib::Clipper clipper;
      try {
        clipper.AddPaths(terms, ClipperLib::ptSubject, true);
      } catch (const ClipperLib::clipperException&) {
        return {};
      }
      clipper.Execute(ClipperLib::ctUnion, lhs, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
    }
    const Paths rhs = ToPaths(*shapes[i]);
    terms.clear();
    for (const Path& r : rhs)
      for (const Path& l : lhs) ConvolutionQuads(l, r, terms);
    FillInsides(lhs, rhs, terms);
    FillInsides(rhs, lhs, terms);
    any = true;
  }
  return UnionNonZero(terms, false);
}

Shape Shadow(const std::vector<mesh::TriangleMesh>& meshes) {
  Paths sum;
  for (const mesh::TriangleMesh& m : meshes) {
    Shape faces;
    faces.sanitized = false;  // each face turned counter-clockwise
    for (const auto& t : m.triangles) {
      Loop f;
      for (int k = 0; k < 3; ++k) f.push_back({m.vertices[t[k]][0], m.vertices[t[k]][1]});
      faces.loops.push_back(std::move(f));
    }
    ClipperLib::Clipper clipper;
    try {
      clipper.AddPaths(ToPaths(faces), ClipperLib::ptSubject, true);
    } catch (const ClipperLib::clipperException&) {
      continue;
    }
    Paths united;
    clipper.Execute(ClipperLib::ctUnion, united, ClipperLib::pftNonZero, ClipperLib::pftNonZero);
    sum.insert(sum.end(), united.begin(), united.end());
  }
  return UnionNonZero(sum, true);
}

Shape Section(const std::vector<mesh::TriangleMesh>& meshes) {
  std::vector<Shape> parts;
  for (const mesh::TriangleMesh& m : meshes)
    for (bool zero_above : {false, true}) parts.push_back(Shape{SliceLoops(m, zero_above), false});
  std::vector<const Shape*> in;
  for (const Shape& s : parts) in.push_back(&s);
  return Clip(in, ClipperLib::ctUnion, nullptr);
}

}  // namespace fabatlas::scad::internal
