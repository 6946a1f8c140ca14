// fabatlas/swept/spacetime_collision.h — collision intervals between moving
// parts (Reconfigurables, section 5): first *when* (time spans), then *where*
// (spatial box and pair of parts).
//
// Time is discretised at t_i = i/(n-1). Each part contributes one spacetime
// proxy per interval [t_i, t_i+1]: the 4D box [t_i, t_i+1] x (AABB at t_i
// union AABB at t_i+1). The proxies of all parts sit in one bounding volume
// hierarchy over 4D boxes (median split on the longest axis, time scaled by
// the scene's spatial extent); overlapping proxies of two parts are candidate
// pairs, confirmed at the interval's end samples by an exact mesh test:
// the smaller part's triangles, posed into the larger part's body frame,
// against a CGAL AABB tree of its faces (built once per part; touching
// counts), then a point-in-volume test each way (CGAL Side_of_triangle_mesh)
// so that containment counts too. Two parts that both hold still are tested
// once. Consecutive colliding samples of a pair form one interval.
// Collisions strictly between samples are not seen: choose time_steps so that
// parts move less than their thinnest feature per step.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "fabatlas/mesh/triangle_mesh.h"
#include "fabatlas/swept/rigid_motion.h"

namespace fabatlas::swept {

struct MovingPart {
  mesh::TriangleMesh mesh;  // closed, body coordinates, mm
  RigidMotion motion;       // body -> world
};

struct SpacetimeOptions {
  int time_steps = 101;  // samples t_i = i/(n-1), n >= 2
  // Broad phase: the proxy hierarchy (default), every pair of proxies
  // (reference for tests and the benchmark; same result, O(proxies^2)), or
  // Embree's rtcCollide over the proxies flattened to 3D (each time interval
  // shifted along x into its own slab; boxes rounded outward to float, then
  // re-checked in double, so the candidates are the hierarchy's). Same result
  // with every choice; bench_collision compares them (docs/swept.md).
  enum class BroadPhase { kHierarchy, kAllPairs, kEmbree };
  BroadPhase broad_phase = BroadPhase::kHierarchy;
};

struct SpatialBox {
  Vec3 min{0, 0, 0};
  Vec3 max{0, 0, 0};
};

struct CollisionInterval {
  double t_begin = 0, t_end = 0;  // first and last colliding sample
  int part_a = 0, part_b = 0;     // indices into the parts, part_a < part_b
  SpatialBox where;               // union over the samples of the two parts' AABB intersection
};

struct CollisionReport {
  std::vector<CollisionInterval> intervals;  // sorted by t_begin, then (part_a, part_b)
  std::size_t proxies = 0;                   // spacetime boxes in the hierarchy
  std::size_t candidate_pairs = 0;           // proxy pairs that overlap
  std::size_t exact_tests = 0;               // mesh-mesh tests run
  double broad_phase_seconds = 0;            // wall time of building and querying the broad phase
  bool collision_free() const { return intervals.empty(); }
};

// Throws InputError for open meshes, bad indices or time_steps < 2.
CollisionReport DetectCollisions(const std::vector<MovingPart>& parts, const SpacetimeOptions& options = {});

}  // namespace fabatlas::swept
