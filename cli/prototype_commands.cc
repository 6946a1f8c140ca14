// fabatlas prototype FILE.yaml [--set name=value,...] [--remove part,...] [--stl OUT.stl] [--json]
// — solve a works-like prototype (Koo et al.) and export its printable geometry.
#include <iostream>
#include <memory>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/mesh_report.h"
#include "fabatlas/mesh/write_mesh.h"
#include "fabatlas/prototype/fabricate.h"
#include "fabatlas/prototype/solve.h"

namespace fabatlas::cli {
namespace {

struct PrototypeArgs {
  std::string file, set, remove, stl;
  double voxel = 0;
  bool json = false;
};

std::map<std::string, double> ParseSet(const std::string& text) {
  std::map<std::string, double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    auto eq = item.find('=');
    if (eq == std::string::npos) throw InputError("--set: '" + item + "' is not name=value");
    try {
      std::size_t used = 0;
      std::string v = item.substr(eq + 1);
      out[item.substr(0, eq)] = std::stod(v, &used);
      if (used != v.size()) throw std::invalid_argument(v);
    } catch (const std::exception&) {
      throw InputError("--set: '" + item + "' has no numeric value");
    }
  }
  return out;
}

int Run(const PrototypeArgs& args) {
  prototype::Prototype p = prototype::LoadPrototype(args.file, ParseSet(args.set));
  std::stringstream removed(args.remove);
  for (std::string part; std::getline(removed, part, ',');) p = prototype::RemovePart(p, part);
  prototype::SolveSummary s = prototype::SolvePrototype(p);
  nlohmann::json j;
  j["name"] = p.name;
  j["satisfiable"] = s.satisfiable;
  j["variables"] = s.variables;
  j["constraints"] = s.constraints;
  j["solve_seconds"] = s.seconds;
  if (!s.satisfiable) {
    j["conflicts"] = s.conflicts;
    j["violated"] = s.violated;
    if (args.json)
      std::cout << j.dump(2) << "\n";
    else
      std::cout << p.name << ": " << s.Explain() << "\n";
    return 3;
  }
  j["deviation_mm"] = s.deviation;
  for (const auto& [name, b] : s.cuboids) j["cuboids"][name] = b;
  for (const auto& [name, v] : s.free_values) j["free_values"][name] = v;
  for (const auto& q : s.pivots)
    j["pivots"].push_back({{"joint", q.joint},
                           {"a", q.a},
                           {"b", q.b},
                           {"child_pivot", q.child_pivot},
                           {"parent_pivot", q.parent_pivot},
                           {"link_length", q.link_length},
                           {"link_length_bound", q.link_length_bound}});
  if (!args.stl.empty()) {
    geometry::GridSpec g;
    g.voxel_size = args.voxel > 0 ? args.voxel : p.fabrication.voxel;
    prototype::FabricateSummary fs;
    geometry::Solid solid = prototype::Fabricate(p, s, g, &fs);
    mesh::TriangleMesh m = solid.ToMesh();
    mesh::WriteMesh(m, args.stl);
    mesh::MeshReport r = mesh::InspectMesh(m);
    j["fabricate_seconds"] = fs.seconds;
    j["swept_cavities"] = fs.swept_cavities;
    j["joint_pieces"] = fs.joint_pieces;
    j["part_volumes"] = fs.part_volumes;
    j["mesh"] = {{"triangles", m.triangles.size()},
                 {"closed", r.closed},
                 {"manifold", r.manifold},
                 {"self_intersecting", r.self_intersecting},
                 {"outward", r.outward},
                 {"components", r.components},
                 {"volume", r.volume},
                 {"reasons", r.Reasons()}};
  }
  if (args.json) {
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << p.name << ": satisfiable, " << s.variables << " variables, " << s.constraints
              << " constraints, deviation " << s.deviation << " mm, solved in " << s.seconds * 1000 << " ms\n";
    for (const auto& q : s.pivots)
      std::cout << "  pivot " << q.joint << ": a=" << q.a << " b=" << q.b << " link " << q.link_length << " mm\n";
    if (j.contains("mesh")) std::cout << "  wrote " << args.stl << ": " << j["mesh"].dump() << "\n";
  }
  return 0;
}

}  // namespace

void AddPrototypeCommands(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<PrototypeArgs>();
  auto* c = app.add_subcommand("prototype", "solve a works-like prototype and export printable geometry");
  c->add_option("file", args->file, "prototype YAML (docs/prototype.md)")->required();
  c->add_option("--set", args->set, "parameter overrides name=value,...");
  c->add_option("--remove", args->remove, "remove these parts first (a discrete edit), part,...");
  c->add_option("--stl", args->stl, "write the printable geometry (base configuration) here");
  c->add_option("--voxel", args->voxel, "level-set voxel, mm (default: the file's)");
  c->add_flag("--json", args->json, "print JSON");
  c->callback([args, &exit_code] { exit_code = Run(*args); });
}

}  // namespace fabatlas::cli
