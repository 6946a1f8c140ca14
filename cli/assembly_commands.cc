// fabatlas assemble PROGRAM.yaml [--json] [--mesh OUT.glb] — solve one
// FabHaL program (FabHacks; docs/assembly.md) and report feasibility,
// stability, the parts that fall apart, the target deviation and the time of
// each solver step (FabHacks Table 5's columns). Exit status 0 when feasible
// and stable, 1 otherwise, 2 for bad input.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>

#include <nlohmann/json.hpp>

#include "commands.h"
#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/read_mesh.h"
#include "fabatlas/mesh/write_mesh.h"
#include "fabatlas/artifact/glb.h"

namespace fabatlas::cli {
namespace {

struct AssembleArgs {
  std::string file, mesh_dir, mesh_out;
  bool json = false;
  assembly::SolveOptions options;
};

// Every part mesh placed at its solved pose, as one mesh (mm, world frame).
mesh::TriangleMesh PosedAssembly(const assembly::Program& prog, const assembly::SolveSummary& s,
                                 const std::string& mesh_dir) {
  mesh::TriangleMesh out;
  for (std::size_t i = 0; i < prog.instances.size() && i < s.poses.size(); ++i) {
    const assembly::Part& part = prog.PartOf(static_cast<int>(i));
    if (part.mesh.empty()) continue;
    const mesh::TriangleMesh m = mesh::ReadMesh(std::filesystem::path(mesh_dir) / part.mesh);
    const auto base = static_cast<std::int32_t>(out.vertices.size());
    for (const auto& v : m.vertices) {
      const Eigen::Vector3d w = s.poses[i] * Eigen::Vector3d(v[0], v[1], v[2]);
      out.vertices.push_back({w.x(), w.y(), w.z()});
    }
    for (const auto& t : m.triangles) out.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  }
  return out;
}

int Run(const AssembleArgs& args) {
  const std::string mesh_dir = args.mesh_dir.empty() ? assembly::DefaultMeshDir() : args.mesh_dir;
  const assembly::Program prog = assembly::LoadProgram(args.file, mesh_dir);
  const assembly::SolveSummary s = assembly::SolveAssembly(prog, args.options);
  const bool ok = s.prechecks_passed && s.feasible && s.stable;
  nlohmann::json j;
  j["program"] = args.file;
  j["parts"] = prog.instances.size();
  int cycles = 0;
  for (const auto& c : prog.connections) cycles += c.closing ? 1 : 0;
  j["cycles"] = cycles;
  j["prechecks_passed"] = s.prechecks_passed;
  j["feasible"] = s.feasible;
  j["stable"] = s.stable;
  j["falls_apart"] = s.falls_apart;
  j["slides"] = nlohmann::json::array();
  for (const auto& sl : s.slides)
    j["slides"].push_back({{"slide", sl.where}, {"load_angle_deg", sl.load_angle_deg}, {"held", sl.held}});
  j["target_deviation_mm"] = s.final_target_error_mm;
  j["target_deviation_deg"] = s.final_target_error_deg;
  j["step1_target_deviation_mm"] = s.step1_target_error_mm;
  j["step1_target_deviation_deg"] = s.step1_target_error_deg;
  j["relaxation_motion_mm"] = s.relax_displacement_mm;
  j["relaxation_motion_deg"] = s.relax_rotation_deg;
  j["relaxation_termination"] = s.relaxation_termination;
  j["messages"] = s.messages;
  j["timings_s"] = {{"quick_reject", s.precheck_seconds},         {"feasibility", s.feasibility_seconds},
                    {"feasibility_starts", s.feasibility_starts}, {"objective", s.objective_seconds},
                    {"relaxation", s.relaxation_seconds},         {"total", s.seconds}};
  for (std::size_t e = 0; e < prog.connections.size() && e < s.params.size(); ++e) {
    const auto& c = prog.connections[e];
    j["connections"].push_back({{"a", prog.instances[c.part_a].name + "." + c.primitive_a},
                                {"b", prog.instances[c.part_b].name + "." + c.primitive_b},
                                {"parameters", s.params[e]}});
  }
  for (std::size_t i = 0; i < prog.instances.size() && i < s.poses.size(); ++i) {
    const Eigen::Isometry3d& p = s.poses[i];
    const Eigen::Vector3d t = p.translation();
    j["poses"][prog.instances[i].name] = {
        {"position_mm", {t.x(), t.y(), t.z()}},
        {"rotation", {{p(0, 0), p(0, 1), p(0, 2)}, {p(1, 0), p(1, 1), p(1, 2)}, {p(2, 0), p(2, 1), p(2, 2)}}}};
  }
  if (!args.mesh_out.empty()) {
    const mesh::TriangleMesh m = PosedAssembly(prog, s, mesh_dir);
    const std::filesystem::path out(args.mesh_out);
    std::string ext = out.extension().string();
    for (auto& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (ext == ".glb") {
      std::ofstream f(out, std::ios::binary);
      const std::string bytes = artifact::MeshToGlb(m);
      if (!f || !f.write(bytes.data(), static_cast<std::streamsize>(bytes.size())))
        throw InputError(args.mesh_out + ": cannot write");
    } else {
      mesh::WriteMesh(m, out);
    }
    j["mesh"] = args.mesh_out;
  }
  if (args.json) {
    std::cout << j.dump(2) << "\n";
    return ok ? 0 : 1;
  }
  std::cout << std::fixed << std::setprecision(3);
  std::cout << args.file << ": " << prog.instances.size() << " parts, " << cycles << " cycles\n"
            << "  feasible: " << (s.feasible ? "yes" : "no") << ", stable: " << (s.stable ? "yes" : "no") << "\n";
  for (const auto& f : s.falls_apart) std::cout << "  falls apart: " << f << "\n";
  for (const auto& sl : s.slides)
    std::cout << "  " << sl.where << ": load " << std::setprecision(1) << sl.load_angle_deg << std::setprecision(3)
              << " deg from the rod's normal plane, " << (sl.held ? "held by friction" : "slid") << "\n";
  for (const auto& m : s.messages) std::cout << "  " << m << "\n";
  if (s.feasible)
    std::cout << "  target deviation: " << s.final_target_error_mm << " mm, " << s.final_target_error_deg
              << " deg (after step 1: " << s.step1_target_error_mm << " mm, " << s.step1_target_error_deg << " deg)\n";
  std::cout << "  time (s): quick reject " << s.precheck_seconds << ", feasibility " << s.feasibility_seconds << " ("
            << s.feasibility_starts << " starts), step 1 " << s.objective_seconds << ", relaxation "
            << s.relaxation_seconds << ", total " << s.seconds << "\n";
  return ok ? 0 : 1;
}

}  // namespace

void AddAssemblyCommands(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<AssembleArgs>();
  CLI::App* c = app.add_subcommand("assemble", "solve a FabHacks assembly program (docs/assembly.md)");
  c->add_option("program", args->file, "program YAML")->required();
  c->add_flag("--json", args->json, "print the report as JSON");
  c->add_option("--mesh", args->mesh_out, "write the posed assembly (.glb, .stl, .obj, .off, .ply)");
  c->add_option("--starts", args->options.restarts, "feasibility starts (default 16)");
  c->add_option("--objective-starts", args->options.objective_starts,
                "feasible starts that run the target objective (default 4)");
  c->add_flag(
      "--no-slide-friction", [args](std::int64_t) { args->options.slide_friction = false; },
      "connectors slide along rods without friction (the paper's model; docs/assembly.md)");
  c->add_option("--relaxation-target-weight", args->options.relaxation_target_weight,
                "start step 2 with the target term at this weight (J/mm², /10 per stage; default 0: none)");
  c->add_flag("--active-set", args->options.relaxation_active_set,
              "relax with an active set of parameters held at their bounds (docs/assembly.md)");
  c->add_option("--mesh-dir", args->mesh_dir, "part meshes (default $FABATLAS_SHARED_DIR/data/fabhacks/meshes)");
  c->callback([args, &exit_code] { exit_code = Run(*args); });
}

}  // namespace fabatlas::cli
