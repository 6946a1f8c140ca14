// Internal: the `assembly` operation node — a FabHacks assembly (FabHacks Sec. 4,
// docs/assembly.md) solved at the sample, its parts placed as geometry, and
// the solve's outcome for the assembly checks (feasible, stable,
// target_reached).
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "fabatlas/assembly/program.h"
#include "fabatlas/assembly/solve.h"
#include "fabatlas/design/design.h"
#include "fabatlas/geometry/solid.h"
#include "operations.h"

namespace fabatlas::design {

struct AssemblyOutcome {
  assembly::Program program;
  assembly::SolveSummary summary;
};

// Where a job bundle puts an assembly's part meshes when the node has no
// `meshes:` (design/data_files.h), relative to the design file.
inline constexpr const char* kBundledMeshDir = "assembly_meshes";

// The part mesh directory of an assembly node: its `meshes:` argument
// relative to the design file; else kBundledMeshDir beside the design when
// that directory exists (a materialized job bundle); else
// assembly::DefaultMeshDir().
std::filesystem::path AssemblyMeshDir(const std::string& meshes, const std::filesystem::path& design_dir);

// Builds and solves the node's program: `file` is a program YAML, or with
// `family: clip_lights` the part library and `set` holds pairs, extension
// (mm) and ring (0..3 = XS, S, M, L). Part meshes are read from
// AssemblyMeshDir().
// Solves are deterministic and remembered per resolved arguments (the node
// and the checks of one sample, and repeated samples, share one solve).
// A bad program or family argument is a DesignFault naming the node.
std::shared_ptr<const AssemblyOutcome> SolveAssemblyNode(const ResolvedArgs& args, const Node& node,
                                                         const std::filesystem::path& design_dir);

// The union of every part mesh with a mesh, placed at its solved pose (for an
// infeasible assembly, the closest attempt's poses).
geometry::Solid AssemblyGeometry(const geometry::GridSpec& grid, const AssemblyOutcome& outcome,
                                 const ResolvedArgs& args, const Node& node, const std::filesystem::path& design_dir);

}  // namespace fabatlas::design
