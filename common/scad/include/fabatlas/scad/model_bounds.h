// fabatlas/scad/model_bounds.h — the box of an OpenSCAD model's solid at its
// own values, cheaply: its CSG tree (fabatlas's evaluator, evaluate_model.h,
// else OpenSCAD's CSG export, which builds no mesh) bounded node by node
// (csg_bounds.h), without evaluating any boolean. What import-scad sizes the
// level-set voxel by (docs/openscad.md, "Voxel size").
#pragma once

#include <filesystem>

#include "fabatlas/scad/csg_bounds.h"

namespace fabatlas::scad {

// The box of `model` with no value overridden. `known` is false (and
// `unknown` says why, "MODEL.scad: ...") when neither evaluation gives a tree
// or the tree has a node whose extent is not in its arguments (import,
// surface, text, resize). Never throws; runs `openscad` (300 s limit) only
// when fabatlas's evaluator declines the model. Thread-safe.
CsgBox ModelBounds(const std::filesystem::path& model);

}  // namespace fabatlas::scad
