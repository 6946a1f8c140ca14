// Evaluate3, the one recursion over OpenSCAD's CSG tree (csg_evaluation.h):
// keys, records, the subtree cache, and the dispatch of a subtree to its
// road.
#include "csg_evaluation.h"

#include <algorithm>
#include <cctype>
#include <utility>

#include "fabatlas/error.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/scad/customizer.h"
#include "fabatlas/scad/evaluate_2d.h"
#include "fabatlas/sha256.h"
#include "fabatlas/stopwatch.h"

namespace fabatlas::design::csg {

CsgEvaluation::Result CsgEvaluation::Evaluate3(const CsgNode& n, const Affine& m, const std::string& path,
                                               bool need_solid) {
  const std::string key = KeyOf(n, m);
  SubtreeRecord record;
  record.key = key;
  record.topology = Sha256Hex("csg|" + Topology(n));
  record.path = path;
  record.op = kCsgNativeOp + n.name;
  if (c_.cache) {
    if (auto hit = c_.cache->Find(key)) return Recalled(n, m, path, *hit, record);
  }
  Result result{Solid(), nullptr, key};
  const std::size_t outside_before = c_.outside ? c_.outside->size() : 0;
  // Children first (3D nodes whose children are 3D), each its own record.
  Affine inner;
  const bool boolean = ChildFrame(n, m, &inner) || (mesh_road_ && MeshChildFrame(n, m, &inner));
  const Children kids = boolean ? EvaluateChildren(n, inner, path) : Children{};
  const Stopwatch start;
  if (mesh_road_) {
    result.solid = OnMeshRoad(n, m, path, boolean, kids, record);
  } else if (boolean) {
    CombineLevelSets(n, kids.results, result);
  } else {
    try {
      result = Leaf(n, m);
      result.key = key;
    } catch (const NoNativeEquivalent& e) {
      record.op = kCsgRenderedOp + n.name;
      result.solid = Rendered(n, m, e.what);
    }
  }
  // With a subtree cache every node becomes a level set, so that each one
  // can be offered and found again in later samples (Fab Forms Sec. 6).
  if (result.field && (need_solid || c_.cache)) {
    result.solid = Sample(*result.field);
    result.field = nullptr;
  }
  record.seconds = start.Seconds();
  record.bytes = result.solid.MemoryBytes();
  for (const auto& k : kids.results) record.children.push_back(k.key);
  if (c_.cache && !result.field) Offer(record, kids, outside_before, result);
  if (c_.records) c_.records->push_back(std::move(record));
  return result;
}

CsgEvaluation::Result CsgEvaluation::Recalled(const CsgNode& n, const Affine& m, const std::string& path,
                                              const CachedSubtree& hit, SubtreeRecord& record) {
  record.from_cache = true;
  record.bytes = hit.solid.MemoryBytes();
  const SubtreeTrace* trace = hit.trace.get();
  if (trace && !trace->op.empty()) {
    if (c_.records) AppendDescendantRecords(*trace, path, c_.records);
    record.children = trace->children;
  } else {
    Affine inner;
    if (ChildFrame(n, m, &inner))
      for (const auto& c : n.children)
        if (!IsTwoD(c.name)) record.children.push_back(KeyOf(c, inner));
  }
  if (trace && c_.outside) c_.outside->insert(c_.outside->end(), trace->outside.begin(), trace->outside.end());
  if (c_.records) c_.records->push_back(record);
  return {hit.solid, nullptr, record.key, hit.trace};
}

CsgEvaluation::Children CsgEvaluation::EvaluateChildren(const CsgNode& n, const Affine& inner,
                                                        const std::string& path) {
  Children kids;
  for (std::size_t i = 0; i < n.children.size(); ++i) {
    if (mesh_road_ ? scad::Dimension(n.children[i]) == 2 : IsTwoD(n.children[i].name)) {
      if (mesh_road_) {
        Warn(n.children[i].name + " (CSG line " + std::to_string(n.children[i].line) +
             "): a 2D object among 3D ones is ignored, as OpenSCAD ignores it");
        kids.two_d_first = kids.two_d_first || kids.results.empty();
        kids.two_d = true;
      }
      continue;
    }
    kids.paths.push_back("/" + std::to_string(i));
    kids.results.push_back(Evaluate3(n.children[i], inner, path + kids.paths.back()));
  }
  return kids;
}

Solid CsgEvaluation::OnMeshRoad(const CsgNode& n, const Affine& m, const std::string& path, bool boolean,
                                const Children& kids, SubtreeRecord& record) {
  try {
    if (boolean && ((n.name == "intersection" && kids.two_d) || (n.name == "difference" && kids.two_d_first)))
      return Solid();
    if (boolean) return MeshOfChildren(n, m, kids.results, record);
    leaf_path_ = path;
    return MeshLeaf(n, m);
  } catch (const NoNativeEquivalent& e) {
    record.op = kCsgRenderedOp + n.name;
    return Rendered(n, m, e.what);
  }
}

void CsgEvaluation::CombineLevelSets(const CsgNode& n, const std::vector<Result>& kids, Result& result) {
  const Combine op = n.name == "difference"     ? Combine::kDifference
                     : n.name == "intersection" ? Combine::kIntersection
                                                : Combine::kUnion;
  bool all_fields = true;
  for (const auto& k : kids) all_fields = all_fields && (k.field || k.solid.empty());
  if (all_fields) {
    std::vector<std::shared_ptr<const Field>> fields;
    for (const auto& k : kids) fields.push_back(k.field);
    result.field = CombineFields(op, fields);
    return;
  }
  std::vector<Solid> solids;
  for (const auto& k : kids) solids.push_back(k.field ? Sample(*k.field) : k.solid);
  if (op == Combine::kUnion) {
    for (const auto& k : solids) result.solid = geometry::Union(result.solid, k);
  } else if (!solids.empty()) {
    result.solid = solids[0];
    for (std::size_t i = 1; i < solids.size(); ++i)
      result.solid = op == Combine::kDifference ? geometry::Difference(result.solid, solids[i])
                                                : geometry::Intersection(result.solid, solids[i]);
  }
}

void CsgEvaluation::Offer(const SubtreeRecord& record, const Children& kids, std::size_t outside_before,
                          Result& result) {
  auto trace = std::make_shared<SubtreeTrace>();
  trace->topology = record.topology;
  trace->op = record.op;
  trace->bytes = record.bytes;
  trace->children = record.children;
  trace->child_paths = kids.paths;
  for (const auto& k : kids.results) trace->child_traces.push_back(k.trace);
  if (c_.outside) trace->outside.assign(c_.outside->begin() + outside_before, c_.outside->end());
  result.trace = trace;
  c_.cache->Offer(record.key, EntryOf(result.solid, std::move(trace)), record.seconds);
}

std::string CsgEvaluation::KeyOf(const CsgNode& n, const Affine& m) const {
  return Sha256Hex(std::string(mesh_road_ ? "csg-mesh" : "csg") +
                   "|voxel=" + scad::FormatScadNumber(c_.grid.voxel_size) + "|m=" + AffineText(m) + "|" + n.canonical);
}

bool CsgEvaluation::ChildFrame(const CsgNode& n, const Affine& m, Affine* inner) {
  *inner = m;
  const bool boolean = n.name == "group" || n.name == "union" || n.name == "render" || n.name == "color" ||
                       n.name == "difference" || n.name == "intersection" || n.name == "multmatrix";
  if (n.name != "multmatrix") return boolean;
  try {
    *inner = Compose(m, MatrixOf(n));
  } catch (const NoNativeEquivalent&) {
    return false;  // rendered by OpenSCAD
  }
  return true;
}

std::string CsgEvaluation::Topology(const CsgNode& n) {
  std::string t = n.name + "(";
  for (const auto& c : n.children) t += Topology(c) + ";";
  return t + ")";
}

Solid CsgEvaluation::Sample(const Field& f) {
  try {
    if (f.parts.empty()) return geometry::FromDistance(c_.grid, f.bounds, f.leaf, "csg");
    const FieldProgram program(f, c_.grid.half_width_voxels * c_.grid.voxel_size);
    return geometry::FromDistance(
        c_.grid, f.bounds, [&program](double x, double y, double z) { return program(x, y, z); }, "csg");
  } catch (const InputError& e) {
    throw SampleFailure(kNoGeometry, model_.filename().string() + ": " + e.what());
  }
}

void CsgEvaluation::Outside(const std::string& what, const std::string& key, const mesh::TriangleMesh& m) {
  if (c_.outside) c_.outside->push_back({what, key, std::make_shared<const mesh::TriangleMesh>(m)});
}

void CsgEvaluation::Warn(const std::string& text) {
  if (c_.warnings) c_.warnings->push_back(model_.filename().string() + ": " + text);
}

std::optional<std::filesystem::path> CsgEvaluation::ImportedMeshFile(const CsgNode& n) const {
  auto f = n.args.find("file");
  if (f == n.args.end() || f->second.type != CsgValue::Type::kString) throw NoNativeEquivalent{"import"};
  std::filesystem::path file = f->second.text;
  std::string ext = file.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
  if (ext == ".dxf" || ext == ".svg") return std::nullopt;
  if (ext != ".stl" && ext != ".off" && ext != ".obj" && ext != ".3mf" && ext != ".amf")
    throw NoNativeEquivalent{"import of " + ext};
  if (file.is_relative()) file = model_.parent_path() / file;
  return file;
}

mesh::TriangleMesh CsgEvaluation::ReadImportedMesh(const CsgNode& n, const std::filesystem::path& file) {
  mesh::TriangleMesh mm = mesh::ReadMesh(file);
  Outside(file.string() + " (imported by " + model_.filename().string() + ")", Sha256Hex(n.canonical), mm);
  return mm;
}

Solid CsgEvaluation::Minus(const Solid& a, const std::vector<Solid>& others) {
  if (a.empty() || others.empty()) return a;
  if (!mesh_road_) {
    Solid out = a;
    for (const Solid& b : others) out = geometry::Difference(out, b);
    return out;
  }
  CsgNode n;
  n.name = "difference";
  std::vector<Result> kids{{a, nullptr, ""}};
  for (const Solid& b : others) kids.push_back({b, nullptr, ""});
  SubtreeRecord record;
  return MeshOfChildren(n, kIdentity, kids, record);
}

}  // namespace fabatlas::design::csg
