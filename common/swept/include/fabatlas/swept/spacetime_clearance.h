// fabatlas/swept/spacetime_clearance.h — minimum clearance between moving
// parts over a transition (Reconfigurables, section 5: the property that tells a
// designer how close a collision-free transition comes to colliding).
//
// clearance = min over samples t_i = i/(n-1) and pairs (a, b) of the distance
// between the posed meshes f_a(t_i) A and f_b(t_i) B. The distance between two
// disjoint closed triangle meshes is reached at a vertex of one against a
// triangle of the other, or between two edges; we take the vertex-triangle
// distances both ways (CGAL AABB_tree closest-point queries in each part's
// body frame), which overestimates the true distance by at most the edge-edge
// case (for meshes extracted from level sets, well under a voxel). Pruning:
// (pair, sample) whose posed bounding boxes are farther apart than the best
// distance found so far are skipped, and so is every vertex whose distance to
// the other part's body bounding box exceeds it. Parts that intersect or
// contain one another are not detected here: run DetectCollisions first (a
// colliding transition has clearance 0 by definition).
// Units: millimetres. Threading: TBB over samples.
#pragma once

#include <cstddef>
#include <limits>
#include <vector>

#include "fabatlas/swept/spacetime_collision.h"

namespace fabatlas::swept {

struct ClearanceOptions {
  int time_steps = 101;  // samples t_i = i/(n-1), n >= 2
  // Distances above this are not resolved (report min_clearance = this
  // value when nothing comes closer); infinity = exact everywhere.
  double max_distance = std::numeric_limits<double>::infinity();
};

struct ClearanceReport {
  double min_clearance = std::numeric_limits<double>::infinity();  // mm
  double t = 0;                                                    // sample where it is reached
  int part_a = -1, part_b = -1;             // the pair (part_a < part_b), -1 if fewer than two parts
  Vec3 point_a{0, 0, 0}, point_b{0, 0, 0};  // closest points, world coordinates at t
  std::size_t pair_samples_tested = 0;      // (pair, sample) combinations not pruned
  std::size_t vertex_queries = 0;           // closest-point queries run
};

// Throws InputError for empty meshes, bad indices or time_steps < 2.
ClearanceReport MinimumClearance(const std::vector<MovingPart>& parts, const ClearanceOptions& options = {});

}  // namespace fabatlas::swept
