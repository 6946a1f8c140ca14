// Runs a design's checks on a sample (the kinds are in check_kinds.h), the
// surface checks in parallel beside the shared surface extraction.
#include "checks.h"

#include <algorithm>
#include <chrono>
#include <mutex>

#include <tbb/task_group.h>

#include "check_kinds.h"
#include "fabatlas/error.h"

namespace fabatlas::design {

const mesh::TriangleMesh& CheckContext::Mesh() {
  std::call_once(mesh_once_, [this] {
    mesh_ = solid_.ToMesh();
    mesh_made_ = true;
  });
  return mesh_;
}

std::shared_ptr<const mesh::TriangleMesh> CheckContext::TakeMesh() {
  if (!mesh_made_) return nullptr;
  return std::make_shared<const mesh::TriangleMesh>(std::move(mesh_));
}

double CheckContext::Number(const CheckSpec& spec, const std::string& name, double fallback) {
  auto it = spec.args.find(name);
  if (it == spec.args.end()) return fallback;
  std::lock_guard<std::mutex> lock(number_mutex_);
  return Expression(it->second.text, scope_, it->second.place).Evaluate();
}

CheckOutcome RunCheck(const CheckSpec& spec, CheckContext& context) {
  auto start = std::chrono::steady_clock::now();
  CheckOutcome o;
  if (spec.type == "watertight")
    o = check::Watertight(context);
  else if (spec.type == "min_thickness")
    o = check::MinThickness(spec, context);
  else if (spec.type == "stands")
    o = check::Stands(spec, context);
  else if (spec.type == "max_volume")
    o = check::MaxVolume(spec, context);
  else if (spec.type == "fem")
    o = check::Fem(spec, context);
  else if (spec.type == "collision_free")
    o = check::CollisionFree(spec, context);
  else if (spec.type == "assembly_feasible")
    o = check::AssemblyFeasible(context);
  else if (spec.type == "assembly_stable")
    o = check::AssemblyStable(context);
  else if (spec.type == "target_reached")
    o = check::TargetReached(spec, context);
  o.name = spec.name;
  o.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return o;
}

namespace {
// Checks that only read the sample's solid and its surface.
bool SurfaceCheck(const CheckSpec& spec) {
  return spec.type == "watertight" || spec.type == "min_thickness" || spec.type == "stands" ||
         spec.type == "max_volume";
}
// ... and of those, the ones that read the surface mesh.
bool ReadsMesh(const CheckSpec& spec) {
  if (spec.type == "min_thickness") {
    auto it = spec.args.find("method");
    return it == spec.args.end() || it->second.text != "opening";
  }
  return spec.type == "watertight" || spec.type == "stands";
}
// ... and the ones that read the solid's measures (Solid::Volume, CenterOfMass).
bool ReadsMeasures(const CheckSpec& spec) { return spec.type == "stands" || spec.type == "max_volume"; }
}  // namespace

std::vector<CheckOutcome> RunChecks(const std::vector<CheckSpec>& specs, CheckContext& context,
                                    double* surface_seconds) {
  std::vector<CheckOutcome> outcomes(specs.size());
  std::vector<std::exception_ptr> errors(specs.size());
  if (surface_seconds) *surface_seconds = 0;
  // The solid's measures (volume, centre of mass and bbox, one pass over its
  // leaves) beside the surface extraction when a check reads them: both are
  // parallel loops over the grid, and each fills the other's idle moments.
  tbb::task_group measures;
  if (std::any_of(specs.begin(), specs.end(), ReadsMeasures)) measures.run([&context] { context.solid().Volume(); });
  if (std::any_of(specs.begin(), specs.end(), ReadsMesh)) {
    auto start = std::chrono::steady_clock::now();
    context.Mesh();
    if (surface_seconds)
      *surface_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  measures.wait();
  tbb::task_group group;
  for (std::size_t i = 0; i < specs.size(); ++i)
    if (SurfaceCheck(specs[i]))
      group.run([&, i] {
        try {
          outcomes[i] = RunCheck(specs[i], context);
        } catch (...) {
          errors[i] = std::current_exception();
        }
      });
  group.wait();
  for (std::size_t i = 0; i < specs.size(); ++i) {
    if (errors[i]) std::rethrow_exception(errors[i]);  // the first in the design's order
    if (!SurfaceCheck(specs[i])) outcomes[i] = RunCheck(specs[i], context);
  }
  return outcomes;
}

std::vector<std::string> RepairParameters(const Design& design) {
  std::vector<std::string> out;
  for (const CheckSpec& spec : design.checks) {
    if (spec.type != "collision_free") continue;
    const auto it = spec.args.find("repair_with");
    if (it == spec.args.end()) continue;
    std::string name;
    for (const char c : it->second.text + ",") {
      if (c == ',' || c == ' ') {
        if (!name.empty()) out.push_back(name);
        name.clear();
      } else {
        name += c;
      }
    }
  }
  return out;
}

}  // namespace fabatlas::design
