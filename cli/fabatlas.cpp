// fabatlas — the operator's and designer's command line.
//   fabatlas validate DESIGN
//   fabatlas eval DESIGN [--at name=value,...] [--json] [--mesh out.stl]
//   fabatlas dg DESIGN --a name=value,... --b name=value,... [--json]
// Bad input: one line on stderr and exit status 2.
#include <CLI/CLI.hpp>

#include <iostream>

#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/error.h"
#include "fabatlas/mesh/write_mesh.h"
#include "sample_report.h"

using namespace fabatlas;

namespace {

int Validate(const std::string& path) {
  design::Design d = design::LoadDesign(path);
  std::cout << path << ": ok (" << d.exposed.size() << " exposed, " << d.mutables.size() << " mutable parameters, "
            << d.constraints.size() << " constraints, " << d.checks.size() << " checks)\n";
  return 0;
}

int Eval(const std::string& path, const std::string& at, bool json, const std::string& mesh_out) {
  design::Design d = design::LoadDesign(path);
  design::Point u = design::ParsePoint(d, at, "--at");
  design::SampleResult r = design::EvaluateSample(d, u);
  if (!mesh_out.empty()) {
    if (r.solid.empty()) throw InputError("--mesh " + mesh_out + ": the sample has no geometry to write (" + r.failure + ")");
    mesh::WriteMesh(r.solid.ToMesh(), mesh_out);
  }
  if (json) std::cout << cli::SampleJson(d, r).dump(2) << "\n";
  else std::cout << cli::SampleText(d, r);
  return 0;
}

int Dg(const std::string& path, const std::string& a, const std::string& b, bool json) {
  design::Design d = design::LoadDesign(path);
  design::SampleResult ra = design::EvaluateSample(d, design::ParsePoint(d, a, "--a"));
  design::SampleResult rb = design::EvaluateSample(d, design::ParsePoint(d, b, "--b"));
  double dg = design::DeltaG(ra, rb);
  if (json) {
    nlohmann::json j{{"dg", dg}, {"a", cli::SampleJson(d, ra)}, {"b", cli::SampleJson(d, rb)}};
    j["a"].erase("subtrees");
    j["b"].erase("subtrees");
    std::cout << j.dump(2) << "\n";
  } else {
    std::cout << "dG = " << dg << "  (a " << (ra.valid ? "valid" : "invalid: " + ra.failure) << ", b "
              << (rb.valid ? "valid" : "invalid: " + rb.failure) << ")\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fabatlas: precompute the valid, fabricable region of a parametric design"};
  app.require_subcommand(1);
  std::string design_path, at, a, b, mesh_out;
  bool json = false;

  auto* validate = app.add_subcommand("validate", "parse and lint a design file");
  validate->add_option("design", design_path, "design YAML")->required();

  auto* eval = app.add_subcommand("eval", "evaluate one sample: checks, properties, timings");
  eval->add_option("design", design_path, "design YAML")->required();
  eval->add_option("--at", at, "name=value,... (others take their defaults)");
  eval->add_flag("--json", json, "print JSON");
  eval->add_option("--mesh", mesh_out, "write the sample's mesh (.stl, .obj, .off, .ply)");

  auto* dg = app.add_subcommand("dg", "volumetric change dG between two samples (seed 001 Eq. 2)");
  dg->add_option("design", design_path, "design YAML")->required();
  dg->add_option("--a", a, "first point, name=value,...")->required();
  dg->add_option("--b", b, "second point, name=value,...")->required();
  dg->add_flag("--json", json, "print JSON");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int code = app.exit(e);
    return code == 0 ? 0 : kExitBadInput;
  }
  try {
    if (*validate) return Validate(design_path);
    if (*eval) return Eval(design_path, at, json, mesh_out);
    if (*dg) return Dg(design_path, a, b, json);
  } catch (const InputError& e) {
    std::cerr << "fabatlas: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "fabatlas: internal error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
