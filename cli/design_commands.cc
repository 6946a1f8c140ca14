// fabatlas validate | eval | dg — single designs and samples.
#include <cctype>
#include <filesystem>
#include <iostream>
#include <memory>

#include "commands.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/encode_3mf.h"
#include "fabatlas/mesh/enclosed_volume.h"
#include "fabatlas/mesh/write_mesh.h"
#include "fabatlas/scad/part_trees.h"
#include "fabatlas/write_file_atomically.h"
#include "sample_report.h"

namespace fabatlas::cli {

namespace {

struct DesignArgs {
  std::string design, at, a, b, mesh_out, part;
  bool json = false, parts = false;
};

std::string Extension(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

void Validate(const DesignArgs& args) {
  design::Design d = LoadDesignOrModel(args.design);
  std::cout << args.design << ": ok (" << d.exposed.size() << " exposed, " << d.mutables.size()
            << " mutable parameters, " << d.constraints.size() << " constraints, " << d.checks.size() << " checks)\n";
}

void Eval(const DesignArgs& args) {
  design::Design d = LoadDesignOrModel(args.design);
  design::EvaluateOptions options;
  options.keep_surface = !args.mesh_out.empty();  // the checks' surface is the one to write
  // The parts (bodies, colour regions) when asked for, or when a 3MF gets
  // one object each.
  const bool three_mf = Extension(args.mesh_out) == ".3mf";
  std::vector<design::Part> parts;
  if (args.parts || !args.part.empty() || three_mf) options.parts = &parts;
  if (!args.part.empty() && args.mesh_out.empty()) throw InputError("--part " + args.part + " needs --mesh FILE");
  if (!args.part.empty() && three_mf) throw InputError("--part selects one part; a .3mf holds every part");
  design::SampleResult r = design::EvaluateSample(d, design::ParsePoint(d, args.at, "--at"), options);
  if (!args.mesh_out.empty()) {
    if (r.solid.empty())
      throw InputError("--mesh " + args.mesh_out + ": the sample has no geometry to write (" + r.failure + ")");
    if (!args.part.empty()) {
      const design::Part* chosen = nullptr;
      std::string names;
      for (const auto& p : parts) {
        if (p.name == args.part) chosen = &p;
        names += (names.empty() ? "" : ", ") + p.name;
      }
      if (!chosen) throw InputError("--part " + args.part + ": not one of the sample's parts: " + names);
      mesh::WriteMesh(chosen->mesh, args.mesh_out);
    } else if (three_mf && (parts.size() > 1 || (!parts.empty() && parts[0].coloured))) {
      std::vector<mesh::Object3mf> objects;
      for (const auto& p : parts) objects.push_back({p.name, &p.mesh, p.coloured, p.rgba});
      WriteFileAtomically(args.mesh_out, mesh::Encode3mfObjects(objects));
    } else {
      mesh::WriteMesh(r.surface ? *r.surface : r.solid.ToMesh(), args.mesh_out);
    }
  }
  if (args.json) {
    nlohmann::json j = SampleJson(d, r);
    if (options.parts) {
      j["parts"] = nlohmann::json::array();
      for (const auto& p : parts) {
        nlohmann::json part{
            {"name", p.name}, {"triangles", p.mesh.triangles.size()}, {"volume", mesh::EnclosedVolume(p.mesh)}};
        if (p.coloured) part["rgba"] = p.rgba;
        j["parts"].push_back(part);
      }
    }
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << SampleText(d, r);
    if (options.parts) {
      std::cout << "parts:";
      for (const auto& p : parts)
        std::cout << " " << p.name << (p.coloured ? " " + scad::HexColour(p.rgba) : "") << " ("
                  << mesh::EnclosedVolume(p.mesh) << " mm^3)";
      std::cout << "\n";
    }
  }
}

void Dg(const DesignArgs& args) {
  design::Design d = LoadDesignOrModel(args.design);
  design::SampleResult ra = design::EvaluateSample(d, design::ParsePoint(d, args.a, "--a"));
  design::SampleResult rb = design::EvaluateSample(d, design::ParsePoint(d, args.b, "--b"));
  double dg = design::DeltaG(ra, rb);
  if (args.json) {
    nlohmann::json j{{"dg", dg}, {"a", SampleJson(d, ra)}, {"b", SampleJson(d, rb)}};
    j["a"].erase("subtrees");
    j["b"].erase("subtrees");
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "dG = " << dg << "  (a " << (ra.valid ? "valid" : "invalid: " + ra.failure) << ", b "
              << (rb.valid ? "valid" : "invalid: " + rb.failure) << ")\n";
  }
}

}  // namespace

void AddDesignCommands(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<DesignArgs>();
  (void)exit_code;

  auto* validate = app.add_subcommand("validate", "parse and lint a design file");
  validate->add_option("design", args->design, "design YAML or OpenSCAD model (.scad)")->required();
  validate->callback([args] { Validate(*args); });

  auto* eval = app.add_subcommand("eval", "evaluate one sample: checks, properties, timings");
  eval->add_option("design", args->design, "design YAML or OpenSCAD model (.scad)")->required();
  eval->add_option("--at", args->at, "name=value,... (others take their defaults)");
  eval->add_flag("--json", args->json, "print JSON");
  eval->add_option("--mesh", args->mesh_out,
                   "write the sample's mesh (.stl, .obj, .off, .ply; .3mf: one object per part, coloured)");
  eval->add_flag("--parts", args->parts, "list the parts: an OpenSCAD model's bodies and colour regions");
  eval->add_option("--part", args->part, "with --mesh: write only this part (as --parts lists it)");
  eval->callback([args] { Eval(*args); });

  auto* dg = app.add_subcommand(
      "dg",
      "volumetric change dG = vol(A xor B) / vol(A union B) between two samples (0 = the same solid, 1 = disjoint)");
  dg->add_option("design", args->design, "design YAML or OpenSCAD model (.scad)")->required();
  dg->add_option("--a", args->a, "first point, name=value,...")->required();
  dg->add_option("--b", args->b, "second point, name=value,...")->required();
  dg->add_flag("--json", args->json, "print JSON");
  dg->callback([args] { Dg(*args); });
}

}  // namespace fabatlas::cli
