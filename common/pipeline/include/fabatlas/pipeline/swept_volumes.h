// fabatlas/pipeline/swept_volumes.h — the cutters of a design's carve_swept
// nodes as job outputs (Reconfigurable Prototypes Sec. 6.7, docs/swept.md;
// format in docs/protocol.md "Swept volumes of a job").
#pragma once

#include <filesystem>
#include <vector>

#include "fabatlas/design/design.h"
#include "fabatlas/design/evaluate_sample.h"
#include "fabatlas/pipeline/executor.h"
#include "fabatlas/sampling/design_space.h"

namespace fabatlas::pipeline {

// One task per carve_swept node of the design (the tree, then each object's
// tree, depth first), all at the centre of the design space (the middle key
// of every dimension that can be split, else its lowest key). Empty when the
// design has no carve_swept node.
std::vector<SweptVolumeTask> SweptVolumeTasks(const design::Design& design, const sampling::DesignSpace& space);

// Writes out_dir/swept_volumes.json (the point, then per node: computed,
// volume_mm3, triangles, time_steps, active_voxels, surface_sha256 and the
// mesh file) and each computed cutter as out_dir/swept_<k>.ply (binary PLY,
// float64, in the frame object's body coordinates). results[k] belongs to
// tasks[k]. Writes nothing for no tasks. Throws InputError naming the file on
// I/O failure.
void WriteSweptVolumes(const sampling::DesignSpace& space, const std::vector<SweptVolumeTask>& tasks,
                       const std::vector<design::SweptVolumeResult>& results, const std::filesystem::path& out_dir);

}  // namespace fabatlas::pipeline
