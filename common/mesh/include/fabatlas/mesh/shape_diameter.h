// fabatlas/mesh/shape_diameter.h — local thickness by the shape diameter
// function (SDF) of Shapira, Shamir and Cohen-Or 2008 ("Consistent mesh
// partitioning and skeletonisation using the shape diameter function"), used
// by Fab Forms (section 5) for the "no very thin parts" check.
#pragma once

#include <cstdint>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"

namespace fabatlas::mesh {

struct ShapeDiameterOptions {
  // Rays per face, cast from the face centroid into the solid.
  int rays = 30;
  // Full opening angle of the ray cone around the inward normal, degrees.
  double cone_angle_degrees = 120.0;
  // A hit counts only on the far side of a wall: the hit face's outward
  // normal within this angle of the ray face's inward normal (degrees, in
  // (0, 180]). 60: the two sides of a wall at most 60 degrees from parallel,
  // so the neighbouring face across a convex edge (90 degrees at a cube's) is
  // not read as a wall, while a wedge sharper than 60 degrees still is. 180:
  // every inner-side hit counts (Shapira et al.'s SDF as published).
  double wall_angle_degrees = 60.0;
  // Faces thinner than this (mm) count in ShapeDiameterSummary::area_fraction_below.
  double thin_threshold = 1.0;
  // When > 0 and the mesh has more faces, only every k-th face (k = ceil(faces
  // / max_faces), a fixed stride, so results stay deterministic) is measured
  // and the area-weighted statistics estimate the whole surface from them;
  // unmeasured faces are NaN in per_face. 0 measures every face.
  std::int64_t max_faces = 0;
};

struct ShapeDiameterSummary {
  // Per input triangle: local thickness in mm, NaN when no ray found a valid hit
  // (open meshes, faces pointing inward) or the triangle is degenerate.
  std::vector<double> per_face;
  std::int64_t faces_measured = 0;  // faces rays were cast from
  std::int64_t faces_without_value = 0;
  // Statistics over faces with a value, weighted by face area (so they do not
  // depend on the tessellation); NaN when no face has a value.
  double min = 0.0;
  double percentile_5 = 0.0;
  double median = 0.0;
  double area_fraction_below = 0.0;  // area with value < thin_threshold / area with a value
};

// Shape diameter of every face of `mesh` (millimetres, outward normals).
// Estimator (details and tolerances in docs/mesh.md): ray i of n leaves the
// centroid at polar angle theta_i = (i + 1/2) / n * cone/2 around the inward
// normal and azimuth i * golden angle (a fixed pattern, no randomness); a hit
// counts only when it reaches the inner side of a face (that face's outward
// normal points along the ray) that faces back at the ray's face (normals
// more than 180 - wall_angle_degrees apart). Hit lengths further than one standard deviation
// from their median are dropped; the face value is the weighted median of the
// rest with Shapira's weights 1/theta. Raw SDF, no smoothing or normalisation.
// Rays are traced in float32 with Embree 3, a face's rays in packets of eight,
// over a TBB parallel loop; results are deterministic. Throws fabatlas::InputError for invalid options or an
// index out of range.
ShapeDiameterSummary ShapeDiameter(const TriangleMesh& mesh, const ShapeDiameterOptions& options = {});

}  // namespace fabatlas::mesh
