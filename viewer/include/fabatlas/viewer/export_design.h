// fabatlas/viewer/export_design.h — the customised design as a file to take
// home: `fabatlas export` and the customiser's Download button
// (GET /api/export) both call ExportDesign.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fabatlas/viewer/customiser.h"

namespace fabatlas::viewer {

// The voxel size a download is evaluated at: half the design's own
// (sampling and preview) voxel size, so the surface is four times finer in
// area and a wall of thickness w is resolved by 2w/h voxels instead of w/h.
// Narrow-band level sets grow with surface area, so memory and time grow
// about 4x over a preview (the design's resource limits still apply and are
// reported as one-line errors).
double FabricationVoxelSize(double design_voxel_size_mm);

struct ExportOptions {
  std::string format = "stl";  // stl (binary), 3mf, glb (metres, +Y up), obj
  double voxel_size = 0;       // mm; 0: FabricationVoxelSize(design voxel size)
  // stl, obj: one part by name (ExportResult::parts; "body2", "body1-ff0000")
  // instead of the whole; empty: the whole. 3mf and glb always hold every
  // part (one 3MF object each, coloured by basematerials; a glb node each,
  // with its material).
  std::string part;
};

struct ExportResult {
  std::string bytes;      // the file's bytes
  std::string file_name;  // "<design>-<name>=<value>_....<format>"
  std::vector<double> u;  // the point evaluated (exactly the one asked for)
  double voxel_size = 0;  // mm
  std::int64_t triangles = 0;
  double volume_mm3 = 0;            // of the closed mesh (divergence theorem)
  double seconds = 0;               // evaluation, checks and meshing, wall time
  std::vector<std::string> checks;  // the checks passed at exactly u (constraints, geometry, the design's)
  // The design's parts at u (an OpenSCAD model's top-level bodies and colour
  // regions, docs/openscad.md "Parts and colours"; one, "body1", otherwise),
  // as "name" or "name #rrggbb".
  std::vector<std::string> parts;
};

// Evaluates the design at exactly u (no snapping) with voxel size
// options.voxel_size, runs all its validity checks there (the constraints,
// the geometry and the design's checks, on the geometry to be written),
// meshes its zero level set and encodes it. Refuses, with an InputError of
// one line naming the point and the nearest valid point (PointText):
//   - a u outside the form's valid region (IsValidPoint, docs/viewer.md),
//     with why it is invalid;
//   - a u inside it (the region interpolates between samples) where a check
//     fails at exactly u, naming the first failed check and its reason.
// Also refuses an unknown format, an unknown part (naming the parts) and a
// mesh that is not closed (its border edge count), the whole's or a part's. Thread-safe; evaluates on the calling
// thread.
ExportResult ExportDesign(const Customiser& customiser, const std::vector<double>& u,
                          const ExportOptions& options = {});

// "radius=15,wall=6": parameter names in the form's order, enumerated values
// by label, numbers with up to 6 significant digits (what `--at` reads).
std::string PointText(const Customiser& customiser, const std::vector<double>& u);

// The valid sample nearest to u in parameter space scaled by each
// dimension's range (ties: lower id); -1 if the form has no valid sample.
std::int64_t NearestValidSample(const Customiser& customiser, const std::vector<double>& u);

}  // namespace fabatlas::viewer
