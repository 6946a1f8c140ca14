#include "assembly_node.h"

#include <cmath>
#include <map>
#include <mutex>

#include "fabatlas/assembly/clip_lights.h"
#include "fabatlas/assembly/mass_properties.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::design {
namespace {

std::string MeshDir(const ResolvedArgs& a, const std::filesystem::path& dir) {
  return AssemblyMeshDir(a.Text("meshes"), dir).string();
}

double SetValue(const ResolvedArgs& a, const std::string& key, const Node& node) {
  auto it = a.values.find("set");
  if (it != a.values.end())
    for (std::size_t i = 0; i < it->second.keys.size(); ++i)
      if (it->second.keys[i] == key) return it->second.numbers[i];
  throw DesignFault(node.place.str() + ": assembly family needs set." + key);
}

assembly::Program BuildProgram(const ResolvedArgs& a, const Node& node, const std::filesystem::path& dir) {
  const std::string family = a.Text("family"), file = (dir / a.Text("file")).string();
  try {
    if (family.empty()) {
      if (a.values.count("set")) throw DesignFault(node.place.str() + ": 'set' needs a 'family'");
      return assembly::LoadProgram(file, MeshDir(a, dir));
    }
    if (family != "clip_lights")
      throw DesignFault(node.place.str() + ": unknown assembly family '" + family + "' (expected clip_lights)");
    auto it = a.values.find("set");
    for (const auto& key : it == a.values.end() ? std::vector<std::string>{} : it->second.keys)
      if (key != "pairs" && key != "extension" && key != "ring")
        throw DesignFault(node.place.str() + ": unknown clip_lights parameter '" + key +
                          "' (expected pairs, extension, ring)");
    const double pairs = SetValue(a, "pairs", node), ring = SetValue(a, "ring", node);
    if (pairs != std::round(pairs) || ring != std::round(ring) || ring < 0 || ring > 3)
      throw DesignFault(node.place.str() + ": clip_lights needs whole pairs and ring in 0..3 (XS, S, M, L)");
    assembly::ClipLightsParams p{static_cast<int>(pairs), SetValue(a, "extension", node),
                                 static_cast<assembly::RingSize>(static_cast<int>(ring))};
    return assembly::BuildClipLights(p, file, MeshDir(a, dir));
  } catch (const DesignFault&) {
    throw;
  } catch (const InputError& e) {
    throw DesignFault(node.place.str() + ": " + e.what());
  }
}

const mesh::TriangleMesh& PartMeshAt(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<mesh::TriangleMesh>> meshes;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = meshes[path];
  if (!slot) {
    const assembly::PartMesh m = assembly::ReadPartMesh(path);
    auto out = std::make_shared<mesh::TriangleMesh>();
    for (const auto& v : m.vertices) out->vertices.push_back({v.x(), v.y(), v.z()});
    for (const auto& t : m.triangles) out->triangles.push_back({t[0], t[1], t[2]});
    slot = out;
  }
  return *slot;
}

}  // namespace

std::filesystem::path AssemblyMeshDir(const std::string& meshes, const std::filesystem::path& design_dir) {
  if (!meshes.empty()) return design_dir / meshes;
  std::error_code ec;
  if (std::filesystem::is_directory(design_dir / kBundledMeshDir, ec)) return design_dir / kBundledMeshDir;
  return assembly::DefaultMeshDir();
}

std::shared_ptr<const AssemblyOutcome> SolveAssemblyNode(const ResolvedArgs& args, const Node& node,
                                                         const std::filesystem::path& design_dir) {
  // Remembered per (design directory, resolved arguments incl. file digests).
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const AssemblyOutcome>> solved;
  const std::string key = design_dir.string() + "|" + args.Canonical();
  {
    std::lock_guard<std::mutex> lock(mutex);
    if (auto it = solved.find(key); it != solved.end()) return it->second;
  }
  auto out = std::make_shared<AssemblyOutcome>();
  out->program = BuildProgram(args, node, design_dir);
  out->summary = assembly::SolveAssembly(out->program);
  std::lock_guard<std::mutex> lock(mutex);
  if (solved.size() >= 4096) solved.clear();  // a few KB each; bound the process's memory
  return solved.emplace(key, std::move(out)).first->second;
}

geometry::Solid AssemblyGeometry(const geometry::GridSpec& grid, const AssemblyOutcome& o, const ResolvedArgs& args,
                                 const Node& node, const std::filesystem::path& design_dir) {
  const std::string dir = MeshDir(args, design_dir);
  geometry::Solid acc;
  bool any = false;
  for (std::size_t i = 0; i < o.program.instances.size() && i < o.summary.poses.size(); ++i) {
    const assembly::Part& part = o.program.PartOf(static_cast<int>(i));
    if (part.mesh.empty()) continue;
    mesh::TriangleMesh m;
    try {
      m = PartMeshAt((std::filesystem::path(dir) / part.mesh).string());
    } catch (const InputError& e) {
      throw DesignFault(node.place.str() + ": " + e.what());
    }
    const Eigen::Isometry3d& pose = o.summary.poses[i];
    for (auto& v : m.vertices) {
      const Eigen::Vector3d w = pose * Eigen::Vector3d(v[0], v[1], v[2]);
      v = {w.x(), w.y(), w.z()};
    }
    geometry::Solid s = geometry::FromMesh(grid, m);
    acc = any ? geometry::Union(acc, s) : s;
    any = true;
  }
  return acc;
}

}  // namespace fabatlas::design
