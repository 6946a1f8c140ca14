#include "operations.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <fstream>

#include "assembly_node.h"
#include "exact_boolean.h"
#include "fabatlas/error.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/prototype/fabricate.h"
#include "fabatlas/prototype/solve.h"
#include "openscad_node.h"

namespace fabatlas::design {
namespace {

using geometry::Solid;
using geometry::Vec2;
using geometry::Vec3;

std::vector<Vec2> Points2(const ResolvedArgs& a, const std::string& name) {
  const auto& n = a.values.at(name).numbers;
  std::vector<Vec2> out;
  for (std::size_t i = 0; i + 1 < n.size(); i += 2) out.push_back({n[i], n[i + 1]});
  return out;
}

std::vector<Vec3> Points3(const ResolvedArgs& a, const std::string& name) {
  const auto& n = a.values.at(name).numbers;
  std::vector<Vec3> out;
  for (std::size_t i = 0; i + 2 < n.size(); i += 3) out.push_back({n[i], n[i + 1], n[i + 2]});
  return out;
}

// Union of many solids as a balanced reduction (fewer large intermediate grids).
Solid UnionAll(std::vector<Solid> solids) {
  if (solids.empty()) return Solid();
  while (solids.size() > 1) {
    std::vector<Solid> next;
    for (std::size_t i = 0; i + 1 < solids.size(); i += 2) next.push_back(geometry::Union(solids[i], solids[i + 1]));
    if (solids.size() % 2) next.push_back(solids.back());
    solids.swap(next);
  }
  return solids[0];
}

int Count(const ResolvedArgs& a, const std::string& name, const Node& node) {
  double c = a.Number(name);
  if (c < 1 || c > 10000 || c != std::round(c))
    throw SampleFailure("no_geometry", node.place.str() + ": '" + name + "' of " + node.op +
                                           " must be a whole number in [1, 10000], got " + std::to_string(c));
  return static_cast<int>(c);
}

// Arc-length parameterised tentacle of unioned spheres (Fab Forms Table 2,
// tea-light holder): a planar curve of constant curvature that starts at the
// origin heading +z and bends towards `heading` degrees in the xy-plane;
// sphere radii shrink linearly from base to tip; spheres are spaced by
// `spacing` times the local radius (default 0.5) so the union is smooth.
Solid Tentacle(const geometry::GridSpec& g, const ResolvedArgs& a, const Node& node) {
  double length = a.Number("length"), r0 = a.Number("base_radius"), r1 = a.Number("tip_radius");
  double k = a.Number("curvature"), heading = a.Number("heading", 0) * M_PI / 180, spacing = a.Number("spacing", 0.5);
  if (length <= 0 || r0 <= 0 || r1 <= 0 || spacing <= 0)
    throw SampleFailure("no_geometry", node.place.str() + ": tentacle needs positive length, radii and spacing");
  std::vector<Solid> spheres;
  double s = 0;
  while (true) {
    double t = std::min(s / length, 1.0);
    double r = r0 + (r1 - r0) * t;
    double lateral = std::abs(k) < 1e-12 ? 0 : (1 - std::cos(k * s)) / k;
    double up = std::abs(k) < 1e-12 ? s : std::sin(k * s) / k;
    Vec3 c{lateral * std::cos(heading), lateral * std::sin(heading), up};
    spheres.push_back(geometry::Translate(geometry::Sphere(g, r), c));
    if (s >= length) break;
    s = std::min(length, s + spacing * std::min(r, r1));
    if (spheres.size() > 5000)
      throw SampleFailure("no_geometry", node.place.str() + ": tentacle would need more than 5000 spheres");
  }
  return UnionAll(std::move(spheres));
}

// A works-like prototype file with its parameters set from the design: the
// two-stage solve, then the printable geometry on this evaluation's grid.
Solid PrototypeNode(const geometry::GridSpec& g, const ResolvedArgs& a, const Node& node,
                    const std::filesystem::path& dir) {
  std::map<std::string, double> set;
  if (auto it = a.values.find("set"); it != a.values.end())
    for (std::size_t i = 0; i < it->second.keys.size(); ++i) set[it->second.keys[i]] = it->second.numbers[i];
  prototype::Prototype p;
  try {
    p = prototype::LoadPrototype(dir / a.Text("file"), set);
  } catch (const InputError& e) {
    throw DesignFault(node.place.str() + ": " + e.what());
  }
  prototype::SolveSummary s = prototype::SolvePrototype(p);
  if (!s.satisfiable) throw SampleFailure(kUnsatConstraints, node.place.str() + ": " + s.Explain());
  return prototype::Fabricate(p, s, g);
}

}  // namespace

Solid ApplyOperation(const Node& node, const ResolvedArgs& a, std::vector<Solid>& children, const geometry::GridSpec& g,
                     const std::filesystem::path& dir, std::vector<OutsideMesh>* outside) {
  const std::string& op = node.op;
  if (op == "sphere") return geometry::Sphere(g, a.Number("radius"));
  if (op == "box") return geometry::Box(g, a.Vec3("size"));
  if (op == "cylinder") return geometry::Cylinder(g, a.Number("radius"), a.Number("height"));
  if (op == "cone") return geometry::Cone(g, a.Number("bottom_radius"), a.Number("top_radius"), a.Number("height"));
  if (op == "torus") return geometry::Torus(g, a.Number("major_radius"), a.Number("minor_radius"));
  if (op == "capsule") return geometry::Capsule(g, a.Vec3("a"), a.Vec3("b"), a.Number("radius"));
  if (op == "extrude") return geometry::Extrude(g, Points2(a, "polygon"), a.Number("height"));
  if (op == "revolve") {
    double sides = a.Number("sides", 0);
    if (sides != std::round(sides) || (sides != 0 && sides < 3) || sides > 1000)
      throw SampleFailure("no_geometry",
                          node.place.str() + ": revolve sides must be 0 (smooth) or a whole number >= 3");
    return geometry::Revolve(g, Points2(a, "profile"), static_cast<int>(sides));
  }
  if (op == "spheres") {
    std::vector<Solid> balls;
    for (const Vec3& c : Points3(a, "centers"))
      balls.push_back(geometry::Translate(geometry::Sphere(g, a.Number("radius")), c));
    return UnionAll(std::move(balls));
  }
  if (op == "tentacle") return Tentacle(g, a, node);
  if (op == "mesh") {
    mesh::TriangleMesh m;
    try {
      m = mesh::ReadMesh(dir / a.Text("file"));
    } catch (const InputError& e) {
      throw DesignFault(node.place.str() + ": " + e.what());
    }
    if (outside)
      outside->push_back({a.Text("file"), a.values.at("file").digest, std::make_shared<const mesh::TriangleMesh>(m)});
    return geometry::FromMesh(g, m);
  }
  if (op == "openscad") {  // without a cache or records (EvaluateSample passes both)
    OpenScadNodeContext context;
    context.grid = g;
    context.outside = outside;
    return EvaluateOpenScadNode(node, a, dir, context).solid;
  }
  if (op == "prototype") return PrototypeNode(g, a, node, dir);
  if (op == "assembly") return AssemblyGeometry(g, *SolveAssemblyNode(a, node, dir), a, node, dir);

  // Operations over children. Transforms union several children first.
  if (op == "union" || op == "difference" || op == "intersection") {
    if (a.Text("exact", "false") == "true") return ExactBoolean(op, children, g);
    Solid acc = children[0];
    for (std::size_t i = 1; i < children.size(); ++i) {
      if (op == "union")
        acc = geometry::Union(acc, children[i]);
      else if (op == "difference")
        acc = geometry::Difference(acc, children[i]);
      else
        acc = geometry::Intersection(acc, children[i]);
    }
    return acc;
  }
  Solid input = children.size() == 1 ? children[0] : UnionAll(children);
  if (op == "translate") return geometry::Translate(input, a.Vec3("by"));
  if (op == "rotate") return geometry::Rotate(input, a.Vec3("degrees"));
  if (op == "scale") return geometry::Scale(input, a.Number("factor"));
  if (op == "offset") return geometry::Offset(input, a.Number("distance"));
  if (op == "shell") return geometry::Shell(input, a.Number("thickness"));
  if (op == "linear_array") return geometry::LinearArray(input, Count(a, "count", node), a.Vec3("step"));
  if (op == "polar_array") return geometry::PolarArray(input, Count(a, "count", node), a.Number("angle", 360));
  throw InputError(node.place.str() + ": unknown node type '" + op + "'");
}

}  // namespace fabatlas::design
