// fabatlas validate | eval | dg — single designs and samples.
#include <iostream>
#include <memory>

#include "commands.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/write_mesh.h"
#include "sample_report.h"

namespace fabatlas::cli {

namespace {

struct DesignArgs {
  std::string design, at, a, b, mesh_out;
  bool json = false;
};

void Validate(const DesignArgs& args) {
  design::Design d = LoadDesignOrModel(args.design);
  std::cout << args.design << ": ok (" << d.exposed.size() << " exposed, " << d.mutables.size()
            << " mutable parameters, " << d.constraints.size() << " constraints, " << d.checks.size() << " checks)\n";
}

void Eval(const DesignArgs& args) {
  design::Design d = LoadDesignOrModel(args.design);
  design::EvaluateOptions options;
  options.keep_surface = !args.mesh_out.empty();  // the checks' surface is the one to write
  design::SampleResult r = design::EvaluateSample(d, design::ParsePoint(d, args.at, "--at"), options);
  if (!args.mesh_out.empty()) {
    if (r.solid.empty())
      throw InputError("--mesh " + args.mesh_out + ": the sample has no geometry to write (" + r.failure + ")");
    mesh::WriteMesh(r.surface ? *r.surface : r.solid.ToMesh(), args.mesh_out);
  }
  if (args.json) std::cout << SampleJson(d, r).dump(2) << "\n";
  else std::cout << SampleText(d, r);
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
  eval->add_option("--mesh", args->mesh_out, "write the sample's mesh (.stl, .obj, .off, .ply)");
  eval->callback([args] { Eval(*args); });

  auto* dg = app.add_subcommand("dg", "volumetric change dG = vol(A xor B) / vol(A union B) between two samples (0 = the same solid, 1 = disjoint)");
  dg->add_option("design", args->design, "design YAML or OpenSCAD model (.scad)")->required();
  dg->add_option("--a", args->a, "first point, name=value,...")->required();
  dg->add_option("--b", args->b, "second point, name=value,...")->required();
  dg->add_flag("--json", args->json, "print JSON");
  dg->callback([args] { Dg(*args); });
}

}  // namespace fabatlas::cli
